"""Plots of the projectile's measures of instability, every run overlaid, against scaled depth
(thesis Figs 5.3, 5.4, 5.8, 5.24), its speed and axial force against depth, and each run's energy
terms against time: instability.py OUT_DIR RUN.json LABEL [RUN.json LABEL ...], with the
instability.json files `mesopen analyze` writes."""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1]
runs = []
for path, label in zip(sys.argv[2::2], sys.argv[3::2]):
    with open(path) as f:
        runs.append((json.load(f), label))


def figure(name, ylabel, curve, scale=1.0, xlabel="scaled depth (depth / projectile length)",
           x="scaled_depth", title=None):
    fig, ax = plt.subplots(figsize=(6.4, 4), dpi=120)
    drawn = False
    for run, label in runs:
        c = run["curves"]
        if not c.get(curve):
            continue
        xs = [1e6 * t for t in c["time"]] if x == "time_us" else c[x]
        ax.plot(xs, [scale * v for v in c[curve]], linewidth=0.9, label=label)
        drawn = True
    ax.axhline(0.0, color="0.6", linewidth=0.5)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title, fontsize=9)
    if drawn:
        ax.legend(fontsize=8)
    save(fig, name)


def save(fig, name):
    fig.tight_layout()
    fig.savefig(os.path.join(out, name), bbox_inches="tight")  # no label cut off
    plt.close(fig)


# Every energy term of every run against time (a colour per term, a line style per run), the
# balance error on its own axis below.
TERMS = ["kinetic", "internal", "plastic", "viscous", "friction", "contact", "eroded",
         "mass_scaling", "external"]
fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.4, 6), dpi=120, sharex=True,
                             gridspec_kw={"height_ratios": [3, 1]})
for k, (run, label) in enumerate(runs):
    c = run["curves"]
    energy = c.get("energy", {})
    t_us = [1e6 * t for t in c["time"]]
    style = ["-", "--", ":", "-."][k % 4]
    for n, term in enumerate(TERMS):
        values = energy.get(term)
        if not values or not any(values):
            continue
        a1.plot(t_us, values, style, color="C%d" % n, linewidth=0.9,
                label=term if len(runs) == 1 else "%s: %s" % (label, term))
    if "balance_error" in energy:
        a2.plot(t_us, energy["balance_error"], style, linewidth=0.9, label=label)
a1.set_ylabel("energy [J/m]")
a1.set_title("kinetic + internal + friction + contact + eroded + mass scaling = initial + external",
             fontsize=9)
a1.legend(fontsize=7, ncol=2)
a2.axhline(0.0, color="0.6", linewidth=0.5)
a2.set_ylabel("balance error")
a2.set_xlabel("time [us]")
save(fig, "instability-energy.png")
figure("instability-velocity.png", "speed of the centre of mass, -v_y [m/s]", "velocity_y", -1.0)
figure("instability-axial-force.png", "axial force on the projectile, F_y [kN/m]", "axial_force",
       1e-3)
figure("instability-rotational-momentum.png", "rotational momentum H [kg m^2/s per m]",
       "rotational_momentum", title="H = sum r_i x m_i v_i about the centre of mass (Eq. 3.13)")
figure("instability-lateral-force.png", "lateral force F_x [kN/m]", "lateral_force", 1e-3)
# The impulse and the running average I(t) / t on two axes of one figure.
fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.4, 6), dpi=120, sharex=True)
for run, label in runs:
    c = run["curves"]
    a1.plot(c["scaled_depth"], c["lateral_impulse"], linewidth=0.9, label=label)
    a2.plot(c["scaled_depth"], [1e-3 * v for v in c["average_lateral_force"]], linewidth=0.9,
            label="%s (%.3g kN/m)" % (label, 1e-3 * run["average_lateral_force"]))
a1.set_ylabel("lateral impulse [N s/m]")
a1.set_title("impulse = integral of F_x dt (Eq. 3.14 as printed); average = impulse / time",
             fontsize=9)
a2.set_ylabel("time-averaged lateral force [kN/m]")
a2.set_xlabel("scaled depth (depth / projectile length)")
for a in (a1, a2):
    a.axhline(0.0, color="0.6", linewidth=0.5)
    a.legend(fontsize=8)
save(fig, "instability-lateral-impulse.png")
figure("instability-lateral-displacement.png", "lateral displacement of the centre of mass [um]",
       "lateral_displacement", 1e6)
figure("instability-tilt.png", "tilt of the axis [deg] (counter-clockwise positive)", "tilt",
       180.0 / 3.141592653589793)
figure("instability-depth.png", "scaled depth (depth / projectile length)", "scaled_depth",
       xlabel="time [us]", x="time_us")
figure("instability-radial-momentum.png", "radial (lateral) momentum M v_x [kg m/s per m]",
       "radial_momentum", title="thesis Fig. 5.24")
# The spectra of H against scaled depth, the dominant period marked.
fig, ax = plt.subplots(figsize=(6.4, 4), dpi=120)
for run, label in runs:
    s = run["spectrum_scaled_depth"]
    if not s["frequencies"]:
        continue
    peak = max(s["power"])
    edge = " (band edge: not resolved)" if s.get("peak_at_band_edge") else ""
    line, = ax.plot(s["frequencies"], [p / peak for p in s["power"]], linewidth=0.9,
                    label="%s: %.3f L per cycle%s" % (label, s["period"], edge))
    if s["period"] > 0:
        ax.axvline(1.0 / s["period"], color=line.get_color(), linewidth=0.6, linestyle="--")
ax.set_xlim(0, 30)
ax.set_xlabel("cycles per projectile length of penetration")
ax.set_ylabel("power of H over its peak")
ax.set_title("spectrum of H against depth (trend removed, Hann window)", fontsize=9)
ax.legend(fontsize=8)
save(fig, "instability-spectrum.png")
