"""Benchmark of multiple time stepping (run.max_level): a scene at a single rate (max_level 0)
beside the same scene with levels, timed side by side and compared seed by seed.

    python3 tools/bench/bench_levels.py [--mesopen build/bin/mesopen] [--out build/bench]
        [--scene examples/thesis/run-06.toml] [--level 2] [--gap 1] [--threads 2] [--runs 3]
        [--seeds 1,1001,2001,3001,4001] [--baseline OTHER_MESOPEN]

Timing: the first seed at max_level 0 and at --level, alternately, --runs times each (the machine
drifts within an hour: only ratios measured side by side mean something); the table gives the
median time loop of each and the median of the pairs' ratios. With --baseline (a mesopen built
from another commit, e.g. the one before multiple time stepping) that program's single rate runs
first in each round, on the scene without the levels' keys (which an older program does not know),
and a line gives the levels' time over the baseline's, round by round. Accuracy: every seed once at
each setting (a run is the same on any thread count, so one run per seed and setting is its answer),
and per measure the single rate's mean and seed-to-seed range beside the levels' mean and their
largest difference seed by seed. The measures are those of the convergence study
(tools/studies/convergence.py: time to the end depth, speed there, peak |H|, lateral displacement,
tilt) and from summary.json the plastic work, the energy balance error and the deepest contact,
and with disks the work on them, the deepest FE-DEM overlap and the disks found touching an FE
body between its steps.
Frames are off. Writes OUT/bench_levels.json (atomically) for the default scene, and
OUT/bench_levels-NAME.json for another (NAME the scene file's stem, e.g. baseline-hybrid: the same
measures for a hybrid target, whose FE bodies near disks step at the base step).
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(ROOT, "tools", "studies"))
from bench_run import with_run_key, without_frames  # noqa: E402
from convergence import MEASURES, measures  # noqa: E402

# summary.json figures: (label, unit, scale, getter)
SUMMARY = {
    "plastic_work": ("plastic work", "J/m", 1.0, lambda s: s["energy"]["plastic"]),
    "balance_error": ("energy balance error", "", 1.0, lambda s: s["energy"]["balance_error"]),
    "deepest_contact": ("deepest contact / element", "", 1.0,
                        lambda s: s["contact"]["deepest_penetration_over_element_size"]),
}
DEFAULT_SCENE = os.path.join(ROOT, "examples", "thesis", "run-06.toml")

# with disks (dem and hybrid), from summary.json's dem table
SUMMARY_DEM = {
    "work_on_disks": ("work on the disks", "J/m", 1.0, lambda s: s["dem"]["work_on_disks"]),
    "deepest_fe_dem": ("deepest FE-DEM overlap / element", "", 1.0,
                       lambda s: s["dem"]["deepest_fe_dem_overlap_over_element_size"]),
    "between_steps": ("disks touching between steps", "", 1.0,
                      lambda s: s["dem"].get("fe_dem_contacts_between_steps", 0)),
}


def with_target_key(scene_text, key, value):
    """The scene with `key = value` in its [target] table (in place of the scene's first `key =`
    line, which the scenes of examples/thesis have in [target])."""
    text = re.sub(rf"(?m)^{key}\s*=.*$", "", scene_text, count=1)
    return re.sub(r"(?m)^\[target\]\s*$", f"[target]\n{key} = {value}", text, count=1)


def run(mesopen, text, tmp, threads):
    scene = os.path.join(tmp, "scene.toml")
    with open(scene, "w") as f:
        f.write(text)
    out = os.path.join(tmp, "out")
    subprocess.run([mesopen, "run", scene, "-o", out, "--threads", str(threads), "--quiet"],
                   check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    figures = measures(os.path.join(out, "run.h5"))
    for key, (_, _, _, get) in SUMMARY.items():
        figures[key] = get(s)
    if "dem" in s:
        for key, (_, _, _, get) in SUMMARY_DEM.items():
            figures[key] = get(s)
    mts = s.get("multiple_time_stepping", {})
    return {"loop_seconds": s["loop_seconds"], "steps": s["steps"], "status": s["status"],
            "element_update_share": mts.get("element_update_share", 1.0), "figures": figures}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mesopen", default=os.path.join(ROOT, "build", "bin", "mesopen"))
    ap.add_argument("--out", default=os.path.join(ROOT, "build", "bench"))
    ap.add_argument("--scene", default=DEFAULT_SCENE)
    ap.add_argument("--level", type=int, default=2)
    ap.add_argument("--gap", type=int, default=1, help="run.level_gap of the runs with levels")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--seeds", default="1,1001,2001,3001,4001")
    ap.add_argument("--baseline", help="another mesopen whose single rate is timed in the series")
    args = ap.parse_args()
    if not 1 <= args.level <= 3:
        ap.error(f"--level {args.level}: allowed 1 <= level <= 3 (run.max_level)")
    if not 0 <= args.gap <= 3:
        ap.error(f"--gap {args.gap}: allowed 0 <= gap <= 3 (run.level_gap)")
    if not 1 <= args.runs <= 100:
        ap.error(f"--runs {args.runs}: allowed 1 <= runs <= 100")
    try:
        seeds = [int(s) for s in args.seeds.split(",")]
    except ValueError:
        ap.error(f"--seeds {args.seeds}: a comma-separated list of integers")
    if not os.access(args.mesopen, os.X_OK):
        ap.error(f"--mesopen {args.mesopen}: not an executable (build first: tools/test.sh)")
    if args.baseline is not None and not os.access(args.baseline, os.X_OK):
        ap.error(f"--baseline {args.baseline}: not an executable")
    os.makedirs(args.out, exist_ok=True)
    with open(args.scene) as f:
        base = without_frames(f.read())
    levels = {0: 0, 1: args.level}

    def scene(seed, which):
        text = with_run_key(with_target_key(base, "seed", seed), "max_level", levels[which])
        return with_run_key(text, "level_gap", args.gap) if which else text

    times = {0: [], 1: []}
    results = {0: {}, 1: {}}
    baseline_times = []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.runs):
            if args.baseline is not None:
                text = with_target_key(base, "seed", seeds[0])
                baseline_times.append(run(args.baseline, text, tmp, args.threads)["loop_seconds"])
            for which in (0, 1):
                r = run(args.mesopen, scene(seeds[0], which), tmp, args.threads)
                times[which].append(r["loop_seconds"])
                results[which][seeds[0]] = r
        for seed in seeds[1:]:
            for which in (0, 1):
                results[which][seed] = run(args.mesopen, scene(seed, which), tmp, args.threads)

    ratios = [b / a for a, b in zip(times[0], times[1])]
    print(f"mesopen run {os.path.relpath(args.scene, ROOT)}, {args.threads} threads, no frames: "
          f"max_level 0 beside {args.level} (level gap {args.gap})")
    print(f"  timing (seed {seeds[0]}, {args.runs} runs each, alternately): time loop median "
          f"{statistics.median(times[0]):.2f} s vs {statistics.median(times[1]):.2f} s, ratio "
          f"{statistics.median(ratios):.3f} (pairs {', '.join(f'{r:.3f}' for r in ratios)}); "
          f"element updates {results[1][seeds[0]]['element_update_share']:.3f} of the single rate's")
    baseline = None
    if baseline_times:
        over = [b / a for a, b in zip(baseline_times, times[1])]
        single_over = [b / a for a, b in zip(baseline_times, times[0])]
        baseline = {"program": args.baseline, "loop_seconds": baseline_times,
                    "levels_over_baseline": over, "levels_over_baseline_median": statistics.median(over),
                    "single_rate_over_baseline": single_over,
                    "single_rate_over_baseline_median": statistics.median(single_over)}
        print(f"  against the baseline's single rate ({args.baseline}), round by round: time loop "
              f"median {statistics.median(baseline_times):.2f} s; levels {statistics.median(over):.3f} "
              f"of it (rounds {', '.join(f'{r:.3f}' for r in over)}), this program's single rate "
              f"{statistics.median(single_over):.3f}")
    print(f"  accuracy over seeds {', '.join(map(str, seeds))}:")
    print(f"  {'measure':32s} {'L=0 mean':>11s} {'L=0 range':>23s} {'L mean':>11s}  within "
          f"{'largest |diff| by seed':>22s}")
    table = {}
    labels = {k: (v[0], v[1], v[2]) for k, v in MEASURES.items()}
    labels.update({k: (v[0], v[1], v[2]) for k, v in SUMMARY.items()})
    if "work_on_disks" in results[0][seeds[0]]["figures"]:
        labels.update({k: (v[0], v[1], v[2]) for k, v in SUMMARY_DEM.items()})
    for key, (label, unit, scale) in labels.items():
        single = [results[0][s]["figures"][key] * scale for s in seeds]
        multi = [results[1][s]["figures"][key] * scale for s in seeds]
        diff = max(abs(a - b) for a, b in zip(single, multi))
        mean0, mean1 = statistics.mean(single), statistics.mean(multi)
        within = min(single) <= mean1 <= max(single)
        table[key] = {"label": label, "unit": unit, "single_rate": single, "levels": multi,
                      "single_rate_mean": mean0, "levels_mean": mean1, "within_range": within,
                      "largest_difference": diff}
        name = f"{label}" + (f" [{unit}]" if unit else "")
        print(f"  {name:32s} {mean0:11.4g} {min(single):11.4g}-{max(single):<11.4g} {mean1:11.4g}  "
              f"{'yes' if within else 'NO ':6s} {diff:22.4g}")
    result = {"scene": os.path.relpath(args.scene, ROOT), "threads": args.threads,
              "level": args.level, "level_gap": args.gap, "seeds": seeds, "runs": args.runs,
              "loop_seconds": {"single_rate": times[0], "levels": times[1]},
              "ratio_median": statistics.median(ratios), "ratios": ratios, "baseline": baseline,
              "steps": {"single_rate": [results[0][s]["steps"] for s in seeds],
                        "levels": [results[1][s]["steps"] for s in seeds]},
              "element_update_share": [results[1][s]["element_update_share"] for s in seeds],
              "status": {"single_rate": [results[0][s]["status"] for s in seeds],
                         "levels": [results[1][s]["status"] for s in seeds]},
              "measures": table}
    stem = os.path.splitext(os.path.basename(args.scene))[0]
    name = "bench_levels" if os.path.abspath(args.scene) == DEFAULT_SCENE else f"bench_levels-{stem}"
    path = os.path.join(args.out, name + ".json")
    with open(path + ".tmp", "w") as f:
        json.dump(result, f, indent=1)
    os.replace(path + ".tmp", path)
    print("written:", path)


if __name__ == "__main__":
    main()
