"""Multiple time stepping by body, what it would save (docs/solver.md, "Multiple time stepping:
levels"): a run with the census of levels on (run.level_census_interval), then, for each largest
level L, the active elements by level over the run (the bodies' own levels, and the rings the
contacts across levels promote), the pairs of bodies by their two levels, and the projected cost
of the run against single rate,
    R = (1 - s_c) W_e,MTS / W_e + s_c W_p,MTS / W_p
(s_c the contact's share of the steps' wall time; W_e the element updates, W_p the pair updates).
Build only if R <= 0.5 (the criterion of the plan's stage 0).

    python3 tools/studies/mts_levels.py [--scene examples/baseline.toml] [--end-depth D]
        [--interval 20] [--out DIR] [--mesopen build/bin/mesopen] [--threads 2] [--analyse DIR]

--analyse DIR reads a run already made (its run.h5 and summary.json) instead of running one.
Prints the tables and writes DIR/mts-levels.json.
"""
import argparse
import json
import os
import re
import subprocess
import sys

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
CRITERION = 0.5


def scene_with(text, keys):
    """The scene text with `keys` (name -> TOML value) set in its [run] table."""
    lines = [k for k in text.split("\n")
             if not any(re.match(r"\s*%s\s*=" % name, k) for name in keys)]
    out = []
    for line in lines:
        out.append(line)
        if line.strip() == "[run]":
            out.extend("%s = %s" % (name, value) for name, value in keys.items())
    if "[run]" not in (x.strip() for x in lines):
        out.append("[run]")
        out.extend("%s = %s" % (name, value) for name, value in keys.items())
    return "\n".join(out)


def run(args):
    os.makedirs(args.out, exist_ok=True)
    keys = {"level_census_interval": args.interval, "frame_interval": 0.0, "vtk": "false"}
    if args.end_depth is not None:
        keys["end_depth"] = args.end_depth
    scene = os.path.join(args.out, "scene-levels.toml")
    with open(args.scene) as f:
        text = f.read()
    with open(scene, "w") as f:
        f.write(scene_with(text, keys))
    run_dir = os.path.join(args.out, "run")
    subprocess.run([args.mesopen, "run", scene, "-o", run_dir, "--quiet", "--threads",
                    str(args.threads)], check=True)
    return run_dir


def analyse(run_dir, windows):
    with open(os.path.join(run_dir, "summary.json")) as f:
        summary = json.load(f)
    figures = summary["levels"]
    out = {"run": run_dir, "steps": summary["steps"], "ended_by": summary.get("ended_by"),
           "depth": summary["projectile"]["depth"], "summary": figures, "windows": {}}
    with h5py.File(os.path.join(run_dir, "run.h5"), "r") as h5:
        lv = h5["levels"]
        step = lv["step"][()]
        active = lv["active_elements"][()]
        base = lv["base_dt"][()]
        edges = np.linspace(0, step[-1] + 1, windows + 1)
        print("run %s: %d steps, ended by %s, depth %.3f mm, %d samples"
              % (run_dir, summary["steps"], summary.get("ended_by"), 1e3 * out["depth"],
                 len(step)))
        print("contact share of the steps' wall time: %.3f" % figures["contact_share_of_steps"])
        for L in sorted(int(k[1:]) for k in lv if re.fullmatch(r"L\d+", k)):
            g = lv["L%d" % L]
            rec = {}
            print("\nL = %d" % L)
            print("  steps          " + " ".join("lvl%-5d" % l for l in range(L + 1))
                  + " ring    proj  e_work p_work")
            for w in range(windows):
                sel = (step >= edges[w]) & (step < edges[w + 1])
                if not sel.any():
                    continue
                n = active[sel].sum()
                shares = [g["elements_level_%d" % l][()][sel].sum() / n for l in range(L + 1)]
                ring = g["ring_elements"][()][sel].sum() / n
                e_ratio = g["element_work"][()][sel].sum() / n
                pairs = lv["pairs"][()][sel].sum()
                p_ratio = g["pair_work"][()][sel].sum() / max(pairs, 1.0)
                proj = g["projectile_level"][()][sel]
                label = "%6d-%-6d" % (edges[w], edges[w + 1])
                print("  %s  %s %.4f  %.1f  %.3f  %.3f"
                      % (label, " ".join("%.4f " % s for s in shares), ring,
                         proj.mean(), e_ratio, p_ratio))
                rec[label] = {"element_share_by_level": shares, "ring_share": ring,
                              "projectile_level_mean": proj.mean(), "element_work_ratio": e_ratio,
                              "pair_work_ratio": p_ratio,
                              "base_dt_mean": float(base[sel].mean())}
            f = figures["L%d" % L]
            print("  whole run: elements by level %s, ring %.4f (mean %.0f elements)"
                  % (" ".join("%.4f" % s for s in f["element_share_by_level"]),
                     sum(f["ring_share_by_level"]), f["mean_ring_elements"]))
            print("  pairs by levels: %s" % ", ".join(
                "%s %.4f" % (k, v) for k, v in f["pair_share_by_levels"].items() if v > 0))
            print("  element work %.3f, pair work %.3f of single rate: projected cost %.3f -> %s"
                  % (f["element_work_ratio"], f["pair_work_ratio"], f["projected_cost_ratio"],
                     "go" if f["projected_cost_ratio"] <= CRITERION else "no-go"))
            if "whole_body_element_work_ratio" in f:  # (runs made before the census had them)
                print("  levels by whole body: element work %.3f, node work %.3f of single rate"
                      % (f["whole_body_element_work_ratio"], f["whole_body_node_work_ratio"]))
            if "pair_promoted_element_work_ratio" in f:
                print("  promoted by overlapping boxes: element work %.3f, node work %.3f"
                      % (f["pair_promoted_element_work_ratio"], f["pair_promoted_node_work_ratio"]))
            out["windows"]["L%d" % L] = rec
    with open(os.path.join(run_dir, "mts-levels.json"), "w") as f:
        json.dump(out, f, indent=1)
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--scene", default=os.path.join(ROOT, "examples", "baseline.toml"))
    p.add_argument("--end-depth", type=float, default=None)
    p.add_argument("--interval", type=int, default=20, help="steps between census samples")
    p.add_argument("--out", default="mts-levels")
    p.add_argument("--mesopen", default=os.path.join(ROOT, "build", "bin", "mesopen"))
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--windows", type=int, default=8, help="step windows of the tables")
    p.add_argument("--analyse", help="a run directory made already")
    args = p.parse_args()
    run_dir = args.analyse or run(args)
    analyse(run_dir, args.windows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
