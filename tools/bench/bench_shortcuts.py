#!/usr/bin/python3
"""Run time against error: every shortcut a user can take on the thesis's run 6, against the
converged reference.

Runs one campaign (`mesopen campaign`, resumable: a finished run is kept) of run 6
(examples/thesis/run-06.toml, no frames) with each shortcut, on the same target layouts as the
reference (seeds 1, 1001, 2001, ...), one after another on the same machine so that the wall times
compare:

  fe-10-plain      10 um mesh, safety 0.9, no mass scaling (no shortcut: the wall times' unit)
  fe-20, fe-14     coarser meshes (no mass scaling)
  fe-10-s0.5       a shorter step (safety 0.5; the opposite of a shortcut, for the step's error)
  fe-10-ms0.1/0.22/0.4   mass scaling at run.mass_scaling_step_ratio 0.1, 0.22 (run 6's
                   default) and 0.4
  hybrid-b0.25/0.44/0.66 the hybrid target with band half-widths 0.25, 0.44 and 0.66 mm
  dem              every grain a disk
  hybrid-b0.66-d0.6, dem-d0.6   the disks' step (dem.step) at 0.6 ns, a quarter of their stable
                   step (2.37 ns in run 6), which the others take: the DEM step's error is the
                   difference
(the hybrid and dem runs on fe-10-plain's mesh, step and no mass scaling).

The reference is a convergence campaign (examples/convergence-run-6.toml, read through
tools/studies/convergence.py's convergence.json in --reference DIR): for each seed, its run at the
finest mesh there at the safety given (--reference-safety, 0.5 by default, else 0.9); the measures
are those of convergence.py at one projectile length deep (time to it, speed there, peak |H|,
lateral displacement, final tilt). For each shortcut it tabulates the median wall time over the
seeds and its ratio to fe-10-plain's, and for each measure the mean over the seeds of the error
against the same seed's reference with its standard deviation; the error in seed spreads is that
mean error over the reference's seed-to-seed standard deviation (below 1: smaller than what the
layout alone changes), the largest over the measures giving the plot's error axis: wall time
against it, with the Pareto front (no other shortcut both faster and closer). A mean error whose
95 % interval over the seeds (Student's t) excludes 0 is named: with few seeds, the others are
not told apart from no error.

    /usr/bin/python3 tools/bench/bench_shortcuts.py --mesopen build/bin/mesopen --out DIR
        --reference CONVERGENCE_DIR [--seeds 3] [--threads 2] [--only NAME,...]
Writes DIR/shortcuts.md, DIR/shortcuts.json and DIR/shortcuts.png (each under a temporary name,
then renamed). Exit code 2 on bad arguments, 1 when a run fails or no reference is found.
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools", "studies"))
from convergence import MEASURES, T95, measures  # noqa: E402

PLAIN = {"run.mass_scaling_step_ratio": 0.0, "run.safety": 0.9, "target.mesh_size": 10e-6}
SHORTCUTS = [  # name, label, keys on top of run 6 (no frames)
    ("fe-10-plain", "fe, 10 um, no shortcut", PLAIN),
    ("fe-20", "fe, 20 um mesh", {**PLAIN, "target.mesh_size": 20e-6}),
    ("fe-14", "fe, 14 um mesh", {**PLAIN, "target.mesh_size": 14e-6}),
    ("fe-10-s0.5", "fe, safety 0.5", {**PLAIN, "run.safety": 0.5}),
    ("fe-10-ms0.1", "fe, mass scaling 0.1", {**PLAIN, "run.mass_scaling_step_ratio": 0.1}),
    ("fe-10-ms0.22", "fe, mass scaling 0.22", {**PLAIN, "run.mass_scaling_step_ratio": 0.22}),
    ("fe-10-ms0.4", "fe, mass scaling 0.4", {**PLAIN, "run.mass_scaling_step_ratio": 0.4}),
    ("hybrid-b0.25", "hybrid, band 0.25 mm",
     {**PLAIN, "run.representation": "hybrid", "run.band_half_width": 0.25e-3}),
    ("hybrid-b0.44", "hybrid, band 0.44 mm",
     {**PLAIN, "run.representation": "hybrid", "run.band_half_width": 0.44e-3}),
    ("hybrid-b0.66", "hybrid, band 0.66 mm",
     {**PLAIN, "run.representation": "hybrid", "run.band_half_width": 0.66e-3}),
    ("dem", "dem", {**PLAIN, "run.representation": "dem"}),
    ("hybrid-b0.66-d0.6", "hybrid, band 0.66 mm, DEM step 0.6 ns",
     {**PLAIN, "run.representation": "hybrid", "run.band_half_width": 0.66e-3,
      "dem.step": 0.6e-9}),
    ("dem-d0.6", "dem, DEM step 0.6 ns",
     {**PLAIN, "run.representation": "dem", "dem.step": 0.6e-9}),
]
PLAIN_NAME = SHORTCUTS[0][0]


def fail(message, code):
    print("bench_shortcuts: " + message, file=sys.stderr)
    sys.exit(code)


def write_atomically(path, text, mode="w"):
    with open(path + ".tmp", mode, **({} if "b" in mode else {"encoding": "utf-8"})) as f:
        f.write(text)
    os.replace(path + ".tmp", path)


def toml_value(v):
    return '"%s"' % v if isinstance(v, str) else repr(v)


def campaign_text(chosen, seeds):
    lines = ["# Written by tools/bench/bench_shortcuts.py: run 6 with each shortcut.",
             "[campaign]", 'name = "Run 6: run time against error"',
             'base = "%s"' % os.path.join(ROOT, "examples", "thesis", "run-06.toml"),
             "replicates = %d" % seeds, ""]
    for name, label, keys in chosen:
        lines += ["[[run]]", 'name = "%s"' % name, 'label = "%s"' % label]
        lines += ["%s = %s" % (k, toml_value(v)) for k, v in keys.items()] + [""]
    return "\n".join(lines)


def reference(directory, safety):
    """Per seed, the measures of its run at the finest mesh that the most seeds reached, at
    `safety` (else the other safety): (safety, mesh, {seed: row})."""
    path = os.path.join(directory, "convergence.json")
    if not os.path.exists(path):
        fail("%s: no convergence.json (run tools/studies/convergence.py on it first)" % path, 1)
    with open(path, encoding="utf-8") as f:
        rows = json.load(f)["rows"]
    for s in (safety, 0.9 if safety != 0.9 else 0.5):
        by_mesh = {}
        for r in rows:
            if r["safety"] == s:
                by_mesh.setdefault(r["mesh"], {})[r["seed"]] = r
        if by_mesh:
            most = max(len(v) for v in by_mesh.values())
            mesh = min(m for m, v in by_mesh.items() if len(v) == most)
            return s, mesh, by_mesh[mesh]
    fail("%s: no rows" % path, 1)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--mesopen", default=os.path.join(ROOT, "build", "bin", "mesopen"))
    p.add_argument("--out", required=True)
    p.add_argument("--reference", default="",
                   help="a convergence campaign's directory (default: this bench's fe-10-s0.5)")
    p.add_argument("--reference-safety", type=float, default=0.5)
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--only", default="", help="comma-separated shortcut names")
    a = p.parse_args()
    names = [s[0] for s in SHORTCUTS]
    only = [n for n in a.only.split(",") if n]
    for n in only:
        if n not in names:
            fail("--only %s: no such shortcut; known: %s" % (n, ", ".join(names)), 2)
    if not 1 <= a.seeds <= 20:
        fail("--seeds %d: allowed 1 to 20" % a.seeds, 2)
    if not os.access(a.mesopen, os.X_OK):
        fail("--mesopen %s: not an executable" % a.mesopen, 2)
    chosen = [s for s in SHORTCUTS if not only or s[0] in only]
    if a.reference:
        ref_safety, ref_mesh, ref = reference(a.reference, a.reference_safety)
        ref_text = "the convergence campaign %s, per seed, at %g um and safety %g" % (
            a.reference, 1e6 * ref_mesh, ref_safety)
    elif "fe-10-s0.5" not in [c[0] for c in chosen]:
        fail("without --reference, fe-10-s0.5 is the reference: --only must name it", 2)

    os.makedirs(a.out, exist_ok=True)
    campaign = os.path.join(a.out, "shortcuts.toml")
    write_atomically(campaign, campaign_text(chosen, a.seeds))
    done = subprocess.run([a.mesopen, "campaign", campaign, "-o", a.out, "--threads",
                           str(a.threads)], stdout=subprocess.DEVNULL)
    if done.returncode not in (0,):
        fail("mesopen campaign exited with %d (see %s)" % (done.returncode, a.out), 1)

    table = []
    for name, label, keys in chosen:
        runs = []
        for k in range(a.seeds):
            d = os.path.join(a.out, "runs", name, "r%d" % (k + 1))
            with open(os.path.join(d, "summary.json"), encoding="utf-8") as f:
                s = json.load(f)
            if s.get("status") != "completed":
                fail("%s: %s" % (d, s.get("status")), 1)
            runs.append({"seed": s["seed"], "wall": s["wall_seconds"],
                         **measures(os.path.join(d, "run.h5"))})
        table.append({"name": name, "label": label, "keys": keys, "runs": runs})
    if not a.reference:
        ref = {r["seed"]: r for row in table if row["name"] == "fe-10-s0.5" for r in row["runs"]}
        ref_text = "this bench's fe-10-s0.5, per seed (not a converged answer: a convergence " \
                   "campaign's directory in --reference gives one)"

    plain_wall = None
    for row in table:
        row["wall"] = statistics.median(r["wall"] for r in row["runs"])
        if row["name"] == PLAIN_NAME:
            plain_wall = row["wall"]
    spreads = {}
    for m in MEASURES:
        values = [r[m] for r in ref.values()]
        spreads[m] = statistics.stdev(values) if len(values) > 1 else float("nan")
    for row in table:
        row["ratio"] = row["wall"] / plain_wall if plain_wall else float("nan")
        row["errors"] = {}
        worst = 0.0
        for m in MEASURES:
            e = [r[m] - ref[r["seed"]][m] for r in row["runs"] if r["seed"] in ref]
            if not e:
                continue
            mean = statistics.fmean(e)
            sd = statistics.stdev(e) if len(e) > 1 else float("nan")
            in_spreads = abs(mean) / spreads[m] if spreads[m] > 0 else float("nan")
            # the mean error's 95 % interval excludes 0 (Student's t over the seeds)
            significant = len(e) > 1 and abs(mean) > T95[len(e) - 1] * sd / math.sqrt(len(e))
            row["errors"][m] = {"mean": mean, "sd": sd, "seeds": len(e), "in_spreads": in_spreads,
                                "significant": significant}
            if not math.isnan(in_spreads):
                worst = max(worst, in_spreads)
        row["error"] = worst
    for row in table:
        row["pareto"] = not any(o["wall"] <= row["wall"] and o["error"] <= row["error"] and
                                (o["wall"] < row["wall"] or o["error"] < row["error"])
                                for o in table if o is not row)

    md = ["# Run 6: run time against error", "",
          "Reference: %s; seeds %s." % (ref_text, ", ".join(str(s) for s in sorted(ref))),
          "Wall times: median over %d seeds, %d threads, one series." % (a.seeds, a.threads), "",
          "| shortcut | wall [s] | x no shortcut | " +
          " | ".join("%s error [%s]" % (MEASURES[m][0].replace("|", "\\|"), MEASURES[m][1])
                     for m in MEASURES) +
          " | error in seed spreads | errors outside their 95 % interval of 0 | Pareto |",
          "|---|---|---|" + "---|" * len(MEASURES) + "---|---|---|"]
    for row in table:
        cells = []
        for m in MEASURES:
            e = row["errors"].get(m)
            scale = MEASURES[m][2]
            cells.append("%+.3g ± %.2g" % (scale * e["mean"], scale * e["sd"]) if e else "-")
        significant = [MEASURES[m][0].replace("|", "\\|") for m, e in row["errors"].items()
                       if e["significant"]]
        md.append("| %s | %.1f | %.2f | %s | %.2f | %s | %s |" % (
            row["label"], row["wall"], row["ratio"], " | ".join(cells), row["error"],
            ", ".join(significant) or "none", "yes" if row["pareto"] else ""))
    md.append("")
    md.append("Seed-to-seed standard deviation of the reference: " + ", ".join(
        "%s %.3g %s" % (MEASURES[m][0], MEASURES[m][2] * spreads[m], MEASURES[m][1])
        for m in MEASURES) + ".")
    text = "\n".join(md) + "\n"
    print(text)
    write_atomically(os.path.join(a.out, "shortcuts.md"), text)
    write_atomically(os.path.join(a.out, "shortcuts.json"), json.dumps(
        {"reference": ref_text, "seeds": a.seeds, "threads": a.threads,
         "reference_spread": spreads, "shortcuts": table}, indent=1))
    plot(table, os.path.join(a.out, "shortcuts.png"))
    return 0


def plot(table, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    # Each point numbered (by wall time), the names in a key beside the axes: the shortcuts near
    # the plain run lie too close for their names.
    fig, ax = plt.subplots(figsize=(9, 4.5))
    fig.subplots_adjust(left=0.09, right=0.66, bottom=0.12, top=0.9)
    key = []
    for k, row in enumerate(sorted(table, key=lambda r: r["wall"]), start=1):
        ax.plot(row["wall"], row["error"], "o", color="C0" if row["pareto"] else "0.6")
        ax.annotate(str(k), (row["wall"], row["error"]), fontsize=7,
                    xytext=(3, 3 if k % 2 else -8), textcoords="offset points")
        key.append("%2d  %s" % (k, row["label"]))
    fig.text(0.68, 0.9, "\n".join(key), fontsize=7, va="top", family="monospace")
    front = sorted((r for r in table if r["pareto"]), key=lambda r: r["wall"])
    ax.plot([r["wall"] for r in front], [r["error"] for r in front], "-", color="C0",
            label="Pareto front")
    ax.axhline(1.0, color="0.8", lw=0.8, ls="--", label="one seed spread")
    ax.set_xscale("log")
    ax.set_xlabel("wall time on 2 cores [s] (median over seeds)")
    ax.set_ylabel("largest error over the measures\n[reference seed spreads]")
    ax.set_title("Run 6: run time against error")
    ax.legend(fontsize=8)
    fig.savefig(path + ".tmp.png", dpi=120)
    os.replace(path + ".tmp.png", path)


if __name__ == "__main__":
    sys.exit(main())
