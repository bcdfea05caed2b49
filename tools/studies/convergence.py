#!/usr/bin/python3
"""Mesh convergence of a campaign's runs: the observed order and the answer at a zero mesh size.

Reads a campaign made of the same scene at several mesh sizes (target.mesh_size) and time-step
safeties (run.safety), each on the same target layouts, such as examples/convergence-run-6.toml:

    build/bin/mesopen campaign examples/convergence-run-6.toml -o DIR
    /usr/bin/python3 tools/studies/convergence.py DIR

For every completed replicate (DIR/runs/NAME/rK/run.h5) it measures, at the run's end (one
projectile length deep for run 6): the time to that depth, the projectile's speed there, the peak
|H| (rotational momentum, Eq. 3.13 of the thesis), the lateral displacement of its centre of mass
and its tilt. For each safety and each measure, from the three finest meshes h1 < h2 < h3:

  - the observed order p of the mean over the seeds run at every mesh, from e21 = f2 - f1 and e32 = f3 - f2 (Celik et al.,
    J. Fluids Eng. 130, 078001, 2008, Eqs. 3-4):
        p = |ln|e32 / e21| + q(p)| / ln r21,  q(p) = ln((r21^p - s) / (r32^p - s)),  s = sign(e32 / e21)
    with r21 = h2 / h1, r32 = h3 / h2; the differences changing sign is oscillatory convergence
    (no order);
  - the value extrapolated to h = 0 (Richardson), f0 = (r21^p f1 - f2) / (r21^p - 1), taken seed
    by seed with the mean's p; its uncertainty combines the grid convergence index
    GCI = 1.25 |f1 - f2| / (r21^p - 1) (Roache's safety factor for three meshes) and the 95 %
    interval of the seeds' extrapolated values (Student's t), added in quadrature;
  - whether each seed's own sequence converges monotonically (0 < e21 / e32 < 1), or only the
    mean over seeds does.

Writes DIR/convergence.json, DIR/convergence.md and DIR/convergence.png (atomically). Exit code 2
on a bad directory, 1 if a safety has fewer than three meshes completed.
"""
import json
import math
import os
import sys
import tomllib

import numpy as np

# measure: (label, unit, scale to the unit shown)
MEASURES = {
    "time_to_end": ("time to the end depth", "us", 1e6),
    "speed_at_end": ("speed at the end depth", "m/s", 1.0),
    "peak_abs_H": ("peak |H|", "mg mm^2/us per m", 1e6),
    "lateral_displacement": ("lateral displacement", "um", 1e6),
    "tilt": ("final tilt", "mrad", 1e3),
}
# two-sided 95 % Student t by degrees of freedom
T95 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306, 9: 2.262}


def measures(run_h5):
    """The measures of one run from its run.h5 series, at its end."""
    import h5py
    with h5py.File(run_h5, "r") as h5:
        s = h5["series"]
        t = s["time"][:]
        vx, vy = s["projectile/vx"][:], s["projectile/vy"][:]
        h = s["projectile/rotational_momentum"][:]
        com_x, tilt = s["projectile/com_x"][:], s["projectile/tilt"][:]
    return {
        "time_to_end": float(t[-1]),
        "speed_at_end": float(math.hypot(vx[-1], vy[-1])),
        "peak_abs_H": float(np.max(np.abs(h))),
        "lateral_displacement": float(com_x[-1] - com_x[0]),
        "tilt": float(tilt[-1] - tilt[0]),
    }


def observed_order(h, f):
    """Order p and the convergence kind of values f at mesh sizes h (three, finest first):
    ("monotonic", p), ("oscillatory", None) or ("converged", None) when f1 = f2 = f3."""
    (h1, h2, h3), (f1, f2, f3) = h, f
    e21, e32 = f2 - f1, f3 - f2
    if e21 == 0.0 and e32 == 0.0:
        return "converged", None
    if e21 == 0.0 or e32 == 0.0 or e21 * e32 < 0.0:
        return "oscillatory", None
    r21, r32 = h2 / h1, h3 / h2
    s = 1.0 if e32 / e21 > 0 else -1.0
    p = abs(math.log(abs(e32 / e21))) / math.log(r21)
    for _ in range(200):  # fixed point of Celik's Eq. 3-4
        q = math.log((r21 ** p - s) / (r32 ** p - s))
        p_new = abs(math.log(abs(e32 / e21)) + q) / math.log(r21)
        if abs(p_new - p) < 1e-12 * max(1.0, p):
            p = p_new
            break
        p = p_new
    return "monotonic", p


def extrapolate(h1, h2, f1, f2, p):
    """Richardson's value at h = 0 from the two finest meshes at order p."""
    r = (h2 / h1) ** p
    return (r * f1 - f2) / (r - 1.0)


def gci(h1, h2, f1, f2, p):
    """Roache's grid convergence index of the finest mesh, as an absolute band (safety 1.25)."""
    return 1.25 * abs(f1 - f2) / ((h2 / h1) ** p - 1.0)


def analyse(rows):
    """rows: dicts with safety, mesh, seed, and the measures. Per safety and measure: the means
    per mesh, the order, the extrapolated value and its uncertainty, the seeds' verdicts."""
    out = {}
    for safety in sorted({r["safety"] for r in rows}, reverse=True):
        mine = [r for r in rows if r["safety"] == safety]
        meshes = sorted({r["mesh"] for r in mine})
        seeds = sorted({r["seed"] for r in mine})
        # the seeds completed at every mesh, for seed-by-seed sequences
        full = [s for s in seeds if all(any(r["seed"] == s and r["mesh"] == m for r in mine)
                                        for m in meshes)]
        entry = {"meshes": meshes, "seeds": seeds, "seeds_at_every_mesh": full, "measures": {}}
        out["%g" % safety] = entry
        for key in MEASURES:
            per_mesh = []
            for m in meshes:
                v = [r[key] for r in mine if r["mesh"] == m]
                per_mesh.append({"mesh": m, "n": len(v), "mean": float(np.mean(v)),
                                 "sd": float(np.std(v, ddof=1)) if len(v) > 1 else 0.0,
                                 "values": {str(r["seed"]): r[key] for r in mine
                                            if r["mesh"] == m}})
            m = {"per_mesh": per_mesh}
            if len(meshes) >= 3 and full:
                h = meshes[:3]
                # the order from the seeds run at every mesh (the same layouts at each mesh)
                f = [float(np.mean([per_mesh[i]["values"][str(s)] for s in full]))
                     for i in range(3)]
                kind, p = observed_order(h, f)
                m["kind"], m["order"] = kind, p
                seed_kinds = {}
                for s in full:
                    fs = [next(r[key] for r in mine if r["seed"] == s and r["mesh"] == hm)
                          for hm in h]
                    seed_kinds[str(s)] = observed_order(h, fs)[0]
                m["seed_kinds"] = seed_kinds
                if kind == "monotonic":
                    f0 = [extrapolate(h[0], h[1],
                                      next(r[key] for r in mine if r["seed"] == s and r["mesh"] == h[0]),
                                      next(r[key] for r in mine if r["seed"] == s and r["mesh"] == h[1]), p)
                          for s in full]
                    band = gci(h[0], h[1], f[0], f[1], p)
                    spread = (T95.get(len(f0) - 1, 1.96) * float(np.std(f0, ddof=1)) / math.sqrt(len(f0))
                              if len(f0) > 1 else 0.0)
                    m["extrapolated"] = extrapolate(h[0], h[1], f[0], f[1], p)
                    m["gci"], m["seed_interval"] = band, spread
                    m["uncertainty"] = math.hypot(band, spread)
                else:
                    # no order: the finest mean, within the spread of the three finest means
                    m["extrapolated"] = None
                    m["uncertainty"] = float(max(f) - min(f))
            entry["measures"][key] = m
    return out


def read_campaign(directory):
    """The rows of every completed replicate under DIR/runs, with its mesh size, safety and seed
    from its composed scene."""
    runs = os.path.join(directory, "runs")
    if not os.path.isdir(runs):
        raise ValueError("%s: no runs/ directory (not a campaign's output)" % directory)
    rows = []
    for name in sorted(os.listdir(runs)):
        for rep in sorted(os.listdir(os.path.join(runs, name))):
            d = os.path.join(runs, name, rep)
            try:
                with open(os.path.join(d, "summary.json")) as f:
                    summary = json.load(f)
                with open(os.path.join(d, "scene.toml"), "rb") as f:
                    scene = tomllib.load(f)
            except (OSError, ValueError):
                continue
            if summary.get("status") != "completed":
                continue
            row = {"run": name, "replicate": rep, "mesh": scene["target"]["mesh_size"],
                   "safety": scene["run"]["safety"], "seed": scene["target"]["seed"],
                   "wall_seconds": summary.get("wall_seconds")}
            row.update(measures(os.path.join(d, "run.h5")))
            rows.append(row)
    return rows


def markdown(result):
    lines = ["# Mesh convergence", ""]
    for safety, entry in result.items():
        lines += ["## Safety %s" % safety, "",
                  "Seeds: %s (at every mesh: %s)." % (entry["seeds"], entry["seeds_at_every_mesh"]), ""]
        head = "| measure | " + " | ".join("%g um" % (1e6 * m) for m in entry["meshes"]) + \
               " | order | at h = 0 | seeds converging |"
        lines += [head, "|" + "---|" * (len(entry["meshes"]) + 4)]
        for key, m in entry["measures"].items():
            label, unit, scale = MEASURES[key]
            cells = ["%.4g ± %.2g" % (scale * c["mean"], scale * c["sd"]) for c in m["per_mesh"]]
            if "kind" not in m:
                tail = ["(fewer than 3 meshes, or no seed at every mesh)", "", ""]
            else:
                order = "%.2f" % m["order"] if m["order"] is not None else m["kind"]
                at0 = ("%.4g ± %.2g" % (scale * m["extrapolated"], scale * m["uncertainty"])
                       if m["extrapolated"] is not None
                       else "none (finest means within %.2g)" % (scale * m["uncertainty"]))
                kinds = list(m["seed_kinds"].values())
                tail = [order, at0, "%d of %d monotonic" % (kinds.count("monotonic"), len(kinds))]
            label = label.replace("|", "\\|")  # a bar inside a table's cell
            lines.append("| %s [%s] | " % (label, unit) + " | ".join(cells + tail) + " |")
        lines.append("")
    return "\n".join(lines)


def plot(path, result):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(MEASURES), figsize=(4 * len(MEASURES), 3.6))
    for ax, key in zip(axes, MEASURES):
        label, unit, scale = MEASURES[key]
        for safety, entry in result.items():
            m = entry["measures"][key]
            h = [1e6 * c["mesh"] for c in m["per_mesh"]]
            line = ax.errorbar(h, [scale * c["mean"] for c in m["per_mesh"]],
                               yerr=[scale * c["sd"] for c in m["per_mesh"]], marker="o", capsize=3,
                               label="safety %s" % safety)
            for c in m["per_mesh"]:
                ax.plot([1e6 * c["mesh"]] * len(c["values"]),
                        [scale * v for v in c["values"].values()], ".", color=line[0].get_color(),
                        alpha=0.4)
            if m.get("extrapolated") is not None:
                ax.errorbar([0.0], [scale * m["extrapolated"]], yerr=[scale * m["uncertainty"]],
                            marker="*", color=line[0].get_color(), capsize=3)
        ax.set_xlabel("mesh size [um]")
        ax.set_ylabel("%s [%s]" % (label, unit))
        ax.set_xlim(left=-1.0)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110)
    plt.close(fig)
    os.replace(tmp, path)


def write_atomic(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, path)


def main(argv):
    if len(argv) != 1:
        print(__doc__, file=sys.stderr)
        return 2
    directory = argv[0]
    try:
        rows = read_campaign(directory)
    except (OSError, ValueError) as e:
        print("convergence: %s" % e, file=sys.stderr)
        return 2
    if not rows:
        print("convergence: %s: no completed run" % directory, file=sys.stderr)
        return 1
    result = analyse(rows)
    write_atomic(os.path.join(directory, "convergence.json"),
                 json.dumps({"rows": rows, "analysis": result}, indent=1))
    text = markdown(result)
    write_atomic(os.path.join(directory, "convergence.md"), text)
    plot(os.path.join(directory, "convergence.png"), result)
    print(text)
    short = [s for s, e in result.items() if len(e["meshes"]) < 3]
    if short:
        print("convergence: safety %s: fewer than three meshes completed" % ", ".join(short),
              file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
