"""Planar compaction (shock) test of the granular target: the Hugoniot of the sand in mesopen's
representations (docs/hugoniot.md).

A rigid plate as wide as the box (projectile.shape = "plate") is driven down into the target at a
constant velocity u_p (run.constant_velocity) between frictionless walls (run.smooth_walls:
uniaxial strain). From the run's frames:
  - the compaction front y_f(t): the highest horizontal slab (one mean grain diameter high) below
    the plate whose mass-weighted mean downward velocity is below u_p / 2, interpolated between
    slab centres; U_s = -dy_f/dt, a least-squares line over the frames where the front lies more
    than two grain diameters below the plate and the wave's toe (the lowest slab moving at
    u_p / 20) has not come within two of the bottom;
  - the plate's stress sigma_p = F_y / W over the same times (the grains' force on the plate,
    run.h5 /series/projectile/axial_force), against the Hugoniot stress rho_00 U_s u_p (momentum
    conservation across a steady front);
  - the compacted density behind the front: the mass between the front and the plate (one grain
    diameter off each) over that area, against mass conservation's rho_00 U_s / (U_s - u_p).
rho_00 is the target's mass over its box, W x H. The closed-form bound is the full-compaction
Hugoniot of the grains' solid EOS (Mie-Grueneisen, docs/hugoniot.md), without strength.

    python3 tools/studies/hugoniot.py -o DIR [--representations fe,dem,hybrid:quartz-bulk,...]
        [--velocities 250,500,750,1000,1500] [--seeds 1,2,3] [--porosity 0.3] [--threads 2]
        [--mesopen build/bin/mesopen] [--width 1e-3] [--height 2.5e-3]

A representation may name the disks' preset after a colon (dem.preset: dem:quartz-bulk).
Writes DIR/hugoniot.csv (a row per run), DIR/hugoniot.json (runs, means per representation and
velocity, the bound), DIR/hugoniot.png (U_s against u_p; stress against density) and
DIR/summary.json; each run in DIR/runs/REP-UP-sSEED (a run completed before from the same scene is
kept, not run again). Exit 2 on bad options, 1 if a run failed.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

# Quartz grains (fem/materials/quartz.cpp, thesis Table 3.3): reference density, the EOS's
# K, K1, K2 and Grueneisen Gamma.
QUARTZ = {"rho": 2648.5, "K": 43.19e9, "K1": 156.2e9, "K2": 48.6e9, "gamma": 0.675}

def scene_text(args, rep, up, seed, end_time):
    """The run's scene: the test's keys, then --set's (which override them)."""
    tables = {
        "target": {"width": repr(args.width), "height": repr(args.height),
                   "diameter": "[42e-6, 78e-6]", "porosity": repr(args.porosity),
                   "seed": str(seed), "mesh_size": "10e-6"},
        "projectile": {"shape": '"plate"', "length": "0.1e-3"},
        "run": {"representation": '"%s"' % rep.split(":")[0], "band_half_width": repr(0.25 * args.width),
                "velocity": repr(up), "constant_velocity": "true", "smooth_walls": "true",
                "end_time": repr(end_time), "frame_interval": repr(end_time / 30), "vtk": "false"},
        "materials.projectile": {"preset": '"steel-elastic"'},
    }
    if ":" in rep:
        tables["dem"] = {"preset": '"%s"' % rep.split(":")[1]}
    for table, key, value in args.settings:
        tables.setdefault(table, {})[key] = value
    text = "# Planar compaction test (tools/studies/hugoniot.py)\n"
    for table, keys in tables.items():
        text += "\n[%s]\n" % table + "".join("%s = %s\n" % kv for kv in keys.items())
    return text


def fail_input(message):
    print("hugoniot.py: " + message, file=sys.stderr)
    sys.exit(2)


def numbers(text, name, lo, hi, kind=float):
    try:
        values = [kind(v) for v in text.split(",") if v.strip()]
    except ValueError:
        fail_input("--%s %r: not a comma-separated list of numbers" % (name, text))
    if not values or any(not (lo <= v <= hi) for v in values):
        fail_input("--%s %r: allowed: numbers from %g to %g" % (name, text, lo, hi))
    return values


def full_compaction(rho00, m=QUARTZ, n=200):
    """The porous Hugoniot of the solid EOS compacted to full density and beyond, no strength:
    p = A(mu)(1 - Gamma mu / 2) + Gamma rho0 e with A = K mu + K1 mu^2 + K2 mu^3 and the jump
    e = p (V00 - V) / 2, so p = A (1 - Gamma mu / 2) / (1 - Gamma rho0 (V00 - V) / 2);
    u_p = sqrt(p (V00 - V)), U_s = V00 sqrt(p / (V00 - V)) (Rankine-Hugoniot)."""
    rho0, g = m["rho"], m["gamma"]
    v00 = 1.0 / rho00
    rows = []
    for mu in np.linspace(1e-4, 0.35, n):
        v = 1.0 / (rho0 * (1.0 + mu))
        a = m["K"] * mu + m["K1"] * mu ** 2 + m["K2"] * mu ** 3
        denominator = 1.0 - 0.5 * g * rho0 * (v00 - v)
        if denominator <= 0.0:
            break
        p = a * (1.0 - 0.5 * g * mu) / denominator
        rows.append({"rho": 1.0 / v, "p": p, "up": math.sqrt(p * (v00 - v)),
                     "Us": v00 * math.sqrt(p / (v00 - v))})
    return rows


def read_disks(run_dir):
    """The disks' radii and masses per metre from dem.data, by radius (LIGGGHTS drops a disk that
    leaves the box between its side walls: the frames' disks are found by their radii)."""
    path = os.path.join(run_dir, "dem.data")
    if not os.path.exists(path):
        return None
    radii, masses = [], []
    with open(path) as f:
        atoms = False
        for line in f:
            if line.strip() == "Atoms":
                atoms = True
                continue
            words = line.split()
            if atoms and len(words) >= 7:
                d, rho = float(words[2]), float(words[3])
                radii.append(0.5 * d)
                masses.append(rho * math.pi * d * d / 4.0)
    order = np.argsort(radii)
    return np.array(radii)[order], np.array(masses)[order]


def disk_masses(disks, radius):
    """The masses of the disks of these radii (the nearest radius of dem.data)."""
    radii, masses = disks
    k = np.clip(np.searchsorted(radii, radius), 1, len(radii) - 1)
    k -= (radius - radii[k - 1]) < (radii[k] - radius)
    return masses[k]


def measure(run_dir, up, width, height, diameter):
    """Front, U_s, stresses and densities of one run (see the module's description)."""
    with h5py.File(os.path.join(run_dir, "run.h5"), "r") as h5:
        tri = h5["mesh/triangles"][:].reshape(-1, 3)
        body = h5["mesh/element_body"][:]
        node_body = h5["mesh/node_body"][:]
        x0, y0 = h5["mesh/x"][:], h5["mesh/y"][:]
        grains = body != 0
        area0 = 0.5 * np.abs((x0[tri[:, 1]] - x0[tri[:, 0]]) * (y0[tri[:, 2]] - y0[tri[:, 0]]) -
                             (x0[tri[:, 2]] - x0[tri[:, 0]]) * (y0[tri[:, 1]] - y0[tri[:, 0]]))
        fe_mass = QUARTZ["rho"] * area0[grains]
        disks = read_disks(run_dir)
        mass_total = fe_mass.sum() + (disks[1].sum() if disks is not None else 0.0)
        disks_left = len(disks[0]) if disks is not None else 0
        rho00 = mass_total / (width * height)
        frames = []
        for name in sorted(h5["frames"].keys()):
            fr = h5["frames"][name]
            y, vy = fr["y"][:], fr["vy"][:]
            plate = y[node_body == 0].min()
            ys = [y[tri[grains]].mean(axis=1)]
            vys = [vy[tri[grains]].mean(axis=1)]
            ms = [fe_mass]
            if "disks" in fr and disks is not None:
                ys.append(fr["disks/y"][:])
                vys.append(fr["disks/vy"][:])
                ms.append(disk_masses(disks, fr["disks/radius"][:]))
                disks_left = len(ys[-1])
            frames.append((float(fr.attrs["time"]), plate, np.concatenate(ys),
                           np.concatenate(vys), np.concatenate(ms)))
        t_series = h5["series/time"][:]
        force = h5["series/projectile/axial_force"][:]

    fronts = []
    for t, plate, y, vy, m in frames:
        # slabs of one diameter down from the plate's face
        edges = np.arange(plate, 0.0, -diameter)[::-1]
        if len(edges) < 3:
            continue
        mass, _ = np.histogram(y, bins=edges, weights=m)
        momentum, _ = np.histogram(y, bins=edges, weights=m * vy)
        centres = 0.5 * (edges[1:] + edges[:-1])
        speed = np.where(mass > 0, -momentum / np.maximum(mass, 1e-300), 0.0)
        front = None
        for k in range(len(centres) - 1, 0, -1):  # from the plate down
            if speed[k - 1] < 0.5 * up <= speed[k]:
                w = (speed[k] - 0.5 * up) / (speed[k] - speed[k - 1])
                front = centres[k] - w * (centres[k] - centres[k - 1])
                break
            if speed[k] < 0.5 * up:  # the slab under the plate is not moving yet
                break
        # the wave's toe: the lowest slab set moving at a twentieth of u_p
        moving = np.nonzero(speed >= 0.05 * up)[0]
        toe = edges[moving[0]] if len(moving) else plate
        if front is not None:
            fronts.append((t, plate, front, toe, y, m))
    # frames where the front has formed (two diameters below the plate) and the wave's toe has not
    # reached the bottom (it would come back reflected)
    use = [(t, p, f, y, m) for t, p, f, toe, y, m in fronts
           if p - f > 2 * diameter and toe > 2 * diameter]
    result = {"rho00": rho00, "frames": len(frames), "front_samples": len(use),
              "disks_lost": (len(disks[0]) - disks_left) if disks is not None else 0}
    if len(use) < 4:
        result["error"] = "fewer than 4 frames with a formed front (%d)" % len(use)
        return result
    ts = np.array([u[0] for u in use])
    fs = np.array([u[2] for u in use])
    slope, intercept = np.polyfit(ts, fs, 1)
    residual = fs - (slope * ts + intercept)
    us = -slope
    # the uncertainty of the slope from the fit's residuals
    us_error = math.sqrt(np.sum(residual ** 2) / max(len(ts) - 2, 1) / np.sum((ts - ts.mean()) ** 2))
    window = (t_series >= ts[0]) & (t_series <= ts[-1])
    sigma_p = float(np.mean(force[window]) / width)
    # compacted density: mass between front and plate, a diameter off each, over that area
    rho_behind = []
    for t, p, f, y, m in use:
        lo, hi = f + diameter, p - diameter
        if hi > lo:
            inside = (y >= lo) & (y < hi)
            rho_behind.append(m[inside].sum() / (width * (hi - lo)))
    result.update({
        "Us": us, "Us_error": us_error, "fit_from": float(ts[0]), "fit_to": float(ts[-1]),
        "sigma_plate": sigma_p, "sigma_hugoniot": rho00 * us * up,
        "rho_measured": float(np.mean(rho_behind)) if rho_behind else float("nan"),
        "rho_jump": rho00 * us / (us - up) if us > up else float("nan"),
        "front_t": ts.tolist(), "front_y": fs.tolist(),
    })
    return result


def run_one(args, rep, up, seed):
    name = "%s-%g-s%d" % (rep.replace(":", "-"), up, seed)
    run_dir = os.path.join(args.out, "runs", name)
    os.makedirs(run_dir, exist_ok=True)
    # until a wave of U_s = 1.5 km/s + 1.5 u_p (above every one measured) has crossed the box;
    # frames every 1/30 of that
    end_time = args.height / (1500.0 + 1.5 * up)
    scene = os.path.join(run_dir, "scene.toml")
    text = scene_text(args, rep, up, seed, end_time)
    summary = os.path.join(run_dir, "out", "summary.json")
    # a run completed before from the same scene is kept
    if os.path.exists(summary) and os.path.exists(scene) and open(scene).read() == text:
        with open(summary) as f:
            done = json.load(f)
        if done.get("status") == "completed":
            row = {"representation": rep, "up": up, "seed": seed,
                   "wall_seconds": done["wall_seconds"], "exit_code": 0}
            row.update(measure(os.path.join(run_dir, "out"), up, args.width, args.height, 60e-6))
            return row
    with open(scene, "w") as f:
        f.write(text)
    start = time.time()
    with open(os.path.join(run_dir, "log.txt"), "w") as log:
        code = subprocess.run([args.mesopen, "run", scene, "-o", os.path.join(run_dir, "out"),
                               "--seed", str(seed), "--threads", str(args.threads), "--quiet"],
                              stdout=log, stderr=subprocess.STDOUT).returncode
    row = {"representation": rep, "up": up, "seed": seed, "wall_seconds": time.time() - start,
           "exit_code": code}
    if code != 0:
        row["error"] = "mesopen run exited with %d (%s)" % (code, os.path.join(run_dir, "log.txt"))
        return row
    row.update(measure(os.path.join(run_dir, "out"), up, args.width, args.height, 60e-6))
    return row


def mean_sd(values):
    v = [x for x in values if x is not None and not math.isnan(x)]
    if not v:
        return float("nan"), float("nan")
    return float(np.mean(v)), float(np.std(v, ddof=1)) if len(v) > 1 else 0.0


def plot(path, table, bound):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.5))
    a.plot([r["up"] for r in bound], [r["Us"] for r in bound], "k--", lw=1,
           label="full compaction, solid EOS (bound)")
    b.plot([r["rho"] for r in bound], [1e-9 * r["p"] for r in bound], "k--", lw=1,
           label="full compaction, solid EOS")
    markers = {"fe": "o", "dem": "s", "hybrid": "^"}
    markers.update({k + ":quartz-bulk": v for k, v in list(markers.items())})
    markers.update({k + ":quartz-pair": v for k, v in list(markers.items())})
    for rep in sorted({r["representation"] for r in table}):
        rows = [r for r in table if r["representation"] == rep]
        a.errorbar([r["up"] for r in rows], [r["Us"] for r in rows], yerr=[r["Us_sd"] for r in rows],
                   marker=markers.get(rep, "o"), capsize=3, label=rep)
        b.errorbar([r["rho_measured"] for r in rows], [1e-9 * r["sigma_plate"] for r in rows],
                   xerr=[r["rho_measured_sd"] for r in rows], marker=markers.get(rep, "o"),
                   capsize=3, ls="none", label=rep + " (plate stress, measured density)")
    top = max(r["up"] for r in table)
    a.set_xlim(0, 1.1 * top)
    a.set_ylim(0, 1.2 * max(r["Us"] + r["Us_sd"] for r in table))
    a.set_xlabel("particle velocity u_p [m/s]")
    a.set_ylabel("shock velocity U_s [m/s]")
    a.legend(fontsize=8)
    a.grid(alpha=0.3)
    b.set_xlabel("density behind the front [kg/m^3]")
    b.set_ylabel("stress [GPa]")
    b.set_ylim(0, 1.3e-9 * max(r["sigma_plate"] for r in table))
    b.legend(fontsize=8, loc="upper left")
    b.grid(alpha=0.3)
    fig.tight_layout()
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, path)


def markdown(table, bound, reps, velocities, seeds):
    """The tables of hugoniot.md: U_s, then stress and density, by u_p and representation."""
    cell = {(r["representation"], r["up"]): r for r in table}
    us_bound = lambda up: float(np.interp(up, [b["up"] for b in bound], [b["Us"] for b in bound]))
    lines = ["# Planar compaction test: Hugoniot by representation", "",
             "`python3 tools/studies/hugoniot.py --representations %s --velocities %s --seeds %s`; "
             "mean +- standard deviation over the seeds; rho_00 %.0f kg/m^3." % (
                 ",".join(reps), ",".join("%g" % v for v in velocities),
                 ",".join(str(s) for s in seeds), table[0]["rho00"] if table else float("nan")),
             "", "## Shock velocity U_s [m/s]", "",
             "| u_p [m/s] | full-compaction bound | " + " | ".join(reps) + " |",
             "|---|---|" + "---|" * len(reps)]
    for up in velocities:
        row = ["%g" % up, "%.0f" % us_bound(up) if bound else "-"]
        for rep in reps:
            r = cell.get((rep, up))
            row.append("%.0f +- %.0f" % (r["Us"], r["Us_sd"]) if r and r["runs"] else "-")
        lines.append("| " + " | ".join(row) + " |")
    lines += ["", "## Plate stress against rho_00 U_s u_p [GPa]; density behind the front "
              "against the jump's [kg/m^3]", "",
              "| u_p [m/s] | " + " | ".join(reps) + " |", "|---|" + "---|" * len(reps)]
    for up in velocities:
        row = ["%g" % up]
        for rep in reps:
            r = cell.get((rep, up))
            row.append("%.3g / %.3g; %.0f / %.0f" % (
                1e-9 * r["sigma_plate"], 1e-9 * r["sigma_hugoniot"], r["rho_measured"],
                r["rho_jump"]) if r and r["runs"] else "-")
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines) + "\n"


def write_atomic(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--out", required=True)
    ap.add_argument("--representations", default="fe,dem,hybrid")
    ap.add_argument("--velocities", default="250,500,750,1000,1500")
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--porosity", type=float, default=0.30)
    ap.add_argument("--width", type=float, default=1.0e-3)
    ap.add_argument("--height", type=float, default=2.5e-3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--mesopen", default=os.path.join(ROOT, "build", "bin", "mesopen"))
    ap.add_argument("--no-plot", action="store_true")
    ap.add_argument("--set", action="append", default=[], metavar="TABLE.KEY=VALUE",
                    help="a scene key for every run, e.g. dem.stiffness=1e11 (repeatable)")
    args = ap.parse_args()
    args.settings = []
    for item in args.set:
        key, _, value = item.partition("=")
        table, _, name = key.rpartition(".")
        if not (table and name and value.strip()):
            fail_input("--set %r: allowed: TABLE.KEY=VALUE with a TOML value, e.g. "
                       "dem.stiffness=1e11 (mesopen keys lists the keys)" % item)
        args.settings.append((table.strip(), name.strip(), value.strip()))
    reps = [r for r in args.representations.split(",") if r]
    presets = ("", "quartz-pair", "quartz-bulk")
    if not reps or any(r.split(":")[0] not in ("fe", "dem", "hybrid") or
                       (r + ":").split(":")[1] not in presets or
                       (r.startswith("fe") and ":" in r) for r in reps):
        fail_input("--representations %r: allowed: fe, dem, hybrid, comma-separated; dem and "
                   "hybrid may name a preset (dem:quartz-bulk, hybrid:quartz-pair)" %
                   args.representations)
    velocities = numbers(args.velocities, "velocities", 1.0, 5000.0)
    seeds = numbers(args.seeds, "seeds", 0, 9e15, int)
    if not 0.05 <= args.porosity <= 0.6:
        fail_input("--porosity %g: allowed: 0.05 to 0.6" % args.porosity)
    if not (0.5e-3 <= args.width <= 10e-3 and 1e-3 <= args.height <= 20e-3):
        fail_input("--width %g, --height %g: allowed: 0.5e-3 to 1e-2 and 1e-3 to 2e-2 [m]" %
                   (args.width, args.height))
    if not os.access(args.mesopen, os.X_OK):
        fail_input("--mesopen %s: not an executable" % args.mesopen)
    os.makedirs(args.out, exist_ok=True)

    start = time.time()
    runs = []
    for rep in reps:
        for up in velocities:
            for seed in seeds:
                row = run_one(args, rep, up, seed)
                runs.append(row)
                print("hugoniot: %-6s u_p %6.0f m/s seed %d: %s" % (
                    rep, up, seed, row.get("error") or "U_s %.0f m/s, plate %.3f GPa, "
                    "rho00 Us up %.3f GPa, density %.0f (jump %.0f) kg/m^3, %.0f s" % (
                        row["Us"], 1e-9 * row["sigma_plate"], 1e-9 * row["sigma_hugoniot"],
                        row["rho_measured"], row["rho_jump"], row["wall_seconds"])), flush=True)

    table = []
    for rep in reps:
        for up in velocities:
            rows = [r for r in runs if r["representation"] == rep and r["up"] == up and "Us" in r]
            entry = {"representation": rep, "up": up, "runs": len(rows)}
            for key in ("Us", "sigma_plate", "sigma_hugoniot", "rho_measured", "rho_jump", "rho00",
                        "wall_seconds"):
                entry[key], entry[key + "_sd"] = mean_sd([r[key] for r in rows])
            table.append(entry)
    rho00 = float(np.mean([r["rho00"] for r in runs if "rho00" in r])) if runs else float("nan")
    bound = full_compaction(rho00) if not math.isnan(rho00) else []

    columns = ["representation", "up", "seed", "rho00", "Us", "Us_error", "sigma_plate",
               "sigma_hugoniot", "rho_measured", "rho_jump", "front_samples", "wall_seconds",
               "error"]
    tmp = os.path.join(args.out, "hugoniot.csv.tmp")
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns, extrasaction="ignore")
        w.writeheader()
        for r in runs:
            w.writerow(r)
    os.replace(tmp, os.path.join(args.out, "hugoniot.csv"))
    failed = [r for r in runs if "error" in r]
    write_atomic(os.path.join(args.out, "hugoniot.json"), json.dumps(
        {"runs": runs, "table": table, "full_compaction": bound,
         "porosity_requested": args.porosity, "width": args.width, "height": args.height},
        indent=1, allow_nan=True))
    write_atomic(os.path.join(args.out, "hugoniot.md"), markdown(table, bound, reps, velocities,
                                                                 seeds))
    files = ["hugoniot.csv", "hugoniot.json", "hugoniot.md"]
    if not args.no_plot and any(not math.isnan(r["Us"]) for r in table):
        plot(os.path.join(args.out, "hugoniot.png"), [r for r in table if not math.isnan(r["Us"])],
             bound)
        files.append("hugoniot.png")
    files.append("summary.json")
    write_atomic(os.path.join(args.out, "summary.json"), json.dumps(
        {"command": "hugoniot", "representations": reps, "velocities": velocities,
         "seeds": seeds, "runs": len(runs), "failed": len(failed), "rho00": rho00,
         "table": table, "wall_seconds": time.time() - start, "files": files},
        indent=1, allow_nan=True))
    print("hugoniot: %d runs (%d failed) in %.0f s; tables in %s" % (
        len(runs), len(failed), time.time() - start, os.path.join(args.out, "hugoniot.csv")))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
