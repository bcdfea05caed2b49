"""The comparison the coupling exists for: the thesis's run 6 with every grain meshed (fe), every
grain a LIGGGHTS disk (dem) and the hybrid target (meshed grains in a band around the path, disks
beyond), over several target seeds each. Runs examples/baseline.toml, baseline-dem.toml and
baseline-hybrid.toml without frames (resumable: a finished run of the same scene and seed is
kept), `mesopen analyze` on each, then prints and writes a table (Markdown and JSON) of wall time
and the instability measures (mean, standard deviation and range over the seeds), the speed-ups
over fe, whether each representation's mean lies within fe's seed-to-seed range, and one plot of
the rotational momentum and lateral displacement histories. With --bands, also the hybrid target
with each of those band half-widths (run.band_half_width, m), and a table of the band's width
against its speed and its agreement with fe (bands.md, bands.json).

    python3 tools/bench/compare_representations.py [--mesopen build/bin/mesopen]
        [--out build/compare] [--seeds 5] [--threads 2] [--docs docs/figures]
        [--bands 0.25e-3,0.44e-3,0.66e-3]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
from bench_run import without_frames  # noqa: E402

SCENES = {"fe": "baseline.toml", "dem": "baseline-dem.toml", "hybrid": "baseline-hybrid.toml"}
MEASURES = [  # instability.json key, label, unit scale, unit
    ("average_lateral_force", "average lateral force", 1e-3, "kN/m"),
    ("lateral_displacement", "lateral displacement", 1e6, "um"),
    ("max_abs_rotational_momentum", "max abs rotational momentum", 1e6, "mg m^2/s per m"),
    ("tilt", "tilt", 1.0, "rad"),
    ("duration", "time to one length", 1e6, "us"),
]


def run_one(args, representation, seed, band=None):
    name = representation if band is None else f"{representation}-band{band}"
    out = os.path.join(args.out, f"{name}-seed{seed}")
    summary = os.path.join(out, "summary.json")
    scene_path = os.path.join(ROOT, "examples", SCENES[representation])
    if os.path.exists(summary):
        with open(summary) as f:
            s = json.load(f)
        if s.get("status") == "completed" and s.get("seed") == seed and \
                os.path.exists(os.path.join(out, "instability.json")):
            return out
    os.makedirs(args.out, exist_ok=True)
    scene = os.path.join(args.out, f"{name}.toml")
    with open(scene_path) as f, open(scene, "w") as g:
        text = without_frames(f.read())
        if band is not None:
            text = text.replace("[run]\n", f"[run]\nband_half_width = {band}\n", 1)
        g.write(text)
    print(f"  {name} seed {seed} ...", flush=True)
    subprocess.run([args.mesopen, "run", scene, "-o", out, "--seed", str(seed), "--threads",
                    str(args.threads), "--quiet"], check=True, stdout=subprocess.DEVNULL)
    subprocess.run([args.mesopen, "analyze", out, "--no-plot"], check=True,
                   stdout=subprocess.DEVNULL)
    return out


def read_runs(dirs):
    """Each run's summary.json and instability.json."""
    summaries, measures = [], []
    for d in dirs:
        with open(os.path.join(d, "summary.json")) as f:
            summaries.append(json.load(f))
        with open(os.path.join(d, "instability.json")) as f:
            measures.append(json.load(f))
    return summaries, measures


def describe(values):
    return {"mean": statistics.mean(values),
            "std": statistics.stdev(values) if len(values) > 1 else 0.0,
            "min": min(values), "max": max(values), "values": values}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mesopen", default=os.path.join(ROOT, "build", "bin", "mesopen"))
    ap.add_argument("--out", default=os.path.join(ROOT, "build", "compare"))
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--docs", default=None, help="also write the table and plot here")
    ap.add_argument("--bands", default="",
                    help="hybrid band half-widths [m], comma-separated, for the table of bands")
    args = ap.parse_args()
    bands = [float(b) for b in args.bands.split(",") if b.strip()]

    runs = {r: [run_one(args, r, seed) for seed in range(1, args.seeds + 1)] for r in SCENES}
    result = {"seeds": args.seeds, "threads": args.threads, "representations": {}}
    for r, dirs in runs.items():
        summaries, measures = read_runs(dirs)
        entry = {"wall_seconds": describe([s["wall_seconds"] for s in summaries]),
                 "steps": describe([s["steps"] for s in summaries]),
                 "elements": summaries[0]["model"]["elements"],
                 "disks": summaries[0].get("dem", {}).get("disks", 0)}
        for key, _, _, _ in MEASURES:
            entry[key] = describe([m[key] for m in measures])
        result["representations"][r] = entry
    fe = result["representations"]["fe"]
    for r, entry in result["representations"].items():
        entry["speedup_over_fe"] = fe["wall_seconds"]["mean"] / entry["wall_seconds"]["mean"]
        entry["within_fe_range"] = {
            key: fe[key]["min"] <= entry[key]["mean"] <= fe[key]["max"] for key, _, _, _ in MEASURES}

    lines = [f"run 6 (one projectile length), {args.seeds} target seeds per representation, "
             f"{args.threads} threads; mean +- standard deviation [min, max] over the seeds",
             "", "| | " + " | ".join(SCENES) + " |", "|---|" + "---|" * len(SCENES)]

    def cell(d, scale, digits=3):
        return (f"{d['mean'] * scale:.{digits}g} +- {d['std'] * scale:.2g} "
                f"[{d['min'] * scale:.{digits}g}, {d['max'] * scale:.{digits}g}]")
    reps = result["representations"]
    lines.append("| model | " + " | ".join(
        f"{reps[r]['elements']:,} elements, {reps[r]['disks']:,} disks" for r in SCENES) + " |")
    lines.append("| wall time [s] | " + " | ".join(cell(reps[r]["wall_seconds"], 1) for r in SCENES) + " |")
    lines.append("| speed-up over fe | " + " | ".join(f"{reps[r]['speedup_over_fe']:.1f}x" for r in SCENES) + " |")
    lines.append("| steps | " + " | ".join(cell(reps[r]["steps"], 1, 5) for r in SCENES) + " |")
    for key, label, scale, unit in MEASURES:
        lines.append(f"| {label} [{unit}] | " + " | ".join(
            cell(reps[r][key], scale) + ("" if r == "fe" else
                                         (" (in fe's range)" if reps[r]["within_fe_range"][key]
                                          else " (outside fe's range)"))
            for r in SCENES) + " |")
    table = "\n".join(lines)
    print(table)
    os.makedirs(args.out, exist_ok=True)
    targets = [args.out] + ([args.docs] if args.docs else [])
    for t in targets:
        os.makedirs(t, exist_ok=True)
        with open(os.path.join(t, "representations.json"), "w") as f:
            json.dump(result, f, indent=1)
        with open(os.path.join(t, "representations.md"), "w") as f:
            f.write(table + "\n")
    plot(runs, [os.path.join(t, "representations.png") for t in targets])
    print("written: " + ", ".join(os.path.join(t, "representations.{md,json,png}") for t in targets))
    if bands:
        band_table(args, bands, fe, targets)


def band_table(args, bands, fe, targets):
    """The hybrid target with each band half-width: its size, time, speed-up over fe's mean, and
    how many of the measures' means lie within fe's seed-to-seed range."""
    rows = []
    for band in bands:
        dirs = [run_one(args, "hybrid", seed, band) for seed in range(1, args.seeds + 1)]
        summaries, measures = read_runs(dirs)
        wall = describe([s["wall_seconds"] for s in summaries])
        row = {"band_half_width": band, "elements": summaries[0]["model"]["elements"],
               "wall_seconds": wall, "speedup_over_fe": fe["wall_seconds"]["mean"] / wall["mean"]}
        for key, _, _, _ in MEASURES:
            row[key] = describe([m[key] for m in measures])
        row["within_fe_range"] = {key: fe[key]["min"] <= row[key]["mean"] <= fe[key]["max"]
                                  for key, _, _, _ in MEASURES}
        rows.append(row)
    lines = [f"hybrid run 6 by band half-width, {args.seeds} target seeds each, {args.threads} "
             f"threads; fe's time to one length {fe['duration']['mean'] * 1e6:.4g} us "
             f"[{fe['duration']['min'] * 1e6:.4g}, {fe['duration']['max'] * 1e6:.4g}], lateral "
             "displacement by seed " + ", ".join(f"{v * 1e6:.1f}" for v in
                                                  fe["lateral_displacement"]["values"]) + " um",
             "", "| half-width [mm] | elements | wall time [s] | speed-up over fe | time to one length "
             "[us] | measures within fe's range | lateral displacement by seed [um] |",
             "|---|---|---|---|---|---|---|"]
    for row in rows:
        inside = sum(row["within_fe_range"].values())
        lines.append(
            f"| {row['band_half_width'] * 1e3:.3g} | {row['elements']:,} | "
            f"{row['wall_seconds']['mean']:.3g} | {row['speedup_over_fe']:.1f}x | "
            f"{row['duration']['mean'] * 1e6:.4g} | {inside} of {len(MEASURES)} | " +
            ", ".join(f"{v * 1e6:.1f}" for v in row["lateral_displacement"]["values"]) + " |")
    table = "\n".join(lines)
    print(table)
    for t in targets:
        with open(os.path.join(t, "bands.json"), "w") as f:
            json.dump({"seeds": args.seeds, "threads": args.threads, "bands": rows}, f, indent=1)
        with open(os.path.join(t, "bands.md"), "w") as f:
            f.write(table + "\n")
    print("written: " + ", ".join(os.path.join(t, "bands.{md,json}") for t in targets))


def plot(runs, paths):
    """Rotational momentum and lateral displacement against depth, every run, by representation."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("no plot: needs /usr/bin/python3 with matplotlib", file=sys.stderr)
        return
    colours = {"fe": "tab:blue", "dem": "tab:red", "hybrid": "tab:green"}
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for r, dirs in runs.items():
        for k, d in enumerate(dirs):
            with open(os.path.join(d, "instability.json")) as f:
                c = json.load(f)["curves"]
            label = r if k == 0 else None
            axes[0].plot(c["scaled_depth"], [1e6 * h for h in c["rotational_momentum"]],
                         color=colours[r], lw=0.8, label=label)
            axes[1].plot(c["scaled_depth"], [1e6 * x for x in c["lateral_displacement"]],
                         color=colours[r], lw=0.8, label=label)
    axes[0].set_ylabel("rotational momentum H [mg m^2/s per m]")
    axes[1].set_ylabel("lateral displacement [um]")
    for ax in axes:
        ax.set_xlabel("depth / projectile length")
        ax.grid(alpha=0.3)
        ax.legend()
    fig.suptitle("run 6: every grain meshed (fe), disks (dem), hybrid; one line per target seed")
    fig.tight_layout()
    for p in paths:
        fig.savefig(p, dpi=120)


if __name__ == "__main__":
    main()
