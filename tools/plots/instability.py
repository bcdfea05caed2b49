"""Plots of the projectile's measures of instability, every run overlaid, against scaled depth
(thesis Figs 5.3, 5.4, 5.8, 5.24): instability.py OUT_DIR RUN.json LABEL [RUN.json LABEL ...],
with the instability.json files `mesopen analyze` writes."""
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
    fig.tight_layout()
    fig.savefig(os.path.join(out, name))
    plt.close(fig)


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
fig.tight_layout()
fig.savefig(os.path.join(out, "instability-lateral-impulse.png"))
plt.close(fig)
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
    line, = ax.plot(s["frequencies"], [p / peak for p in s["power"]], linewidth=0.9,
                    label="%s: %.3f L per cycle" % (label, s["period"]))
    if s["period"] > 0:
        ax.axvline(1.0 / s["period"], color=line.get_color(), linewidth=0.6, linestyle="--")
ax.set_xlim(0, 30)
ax.set_xlabel("cycles per projectile length of penetration")
ax.set_ylabel("power of H (detrended, Hann window), over its peak")
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(os.path.join(out, "instability-spectrum.png"))
plt.close(fig)
