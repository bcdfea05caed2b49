"""Tessellation study: power (Laguerre, the default) against the thesis's radius-matched
Voronoi tessellation (Eq. 4.4), on grain-size and porosity fidelity.

The three validation scenes of the thesis (section 4.2.4 and 4.2.5; examples/targets/
thesis-60um-uniform.toml, thesis-45-75um-clustered.toml, thesis-45-75um-regular.toml: 5 x 5 mm,
30 % porosity, 6189 grains), each with tessellation = power and voronoi, seeds 1, 2 and 3, and
calibrate_porosity true (default) and false. Writes tessellations.json (every run),
tessellations.md (means over the seeds beside the thesis's values, then every run) and
tessellations.png (grain-size histograms of power and voronoi, 60 um uniform, seed 1,
calibrated porosity).

    python3 tools/studies/tessellations.py [--mesopen build/bin/mesopen] [--out docs/figures]
        [--seeds 1 2 3]
"""
import argparse
import json
import os
import subprocess
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

SCENES = ["thesis-60um-uniform", "thesis-45-75um-clustered", "thesis-45-75um-regular"]
TESSELLATIONS = ["power", "voronoi"]
CALIBRATE = [True, False]
# Thesis section 4.2.4 (Figs. 4.14, 4.16) and 4.2.5 (Fig. 4.18): grains, porosity [%],
# mean and std of the equivalent diameter [um]. The regular target's grain count is not given.
THESIS = {
    "thesis-60um-uniform": (6189, 30.32, 59.87, 1.73),
    "thesis-45-75um-clustered": (6189, 29.84, 60.07, 8.7),
    "thesis-45-75um-regular": (None, 29.5, 60.19, 8.6),
}


def run(mesopen, tmp, scene, tessellation, calibrate, seed):
    """Run one case: the example scene with the tessellation and calibration keys appended."""
    with open(os.path.join(ROOT, "examples", "targets", scene + ".toml")) as f:
        text = f.read()
    head, sep, tail = text.partition("[projectile]")
    head = head.rstrip() + "\ntessellation = %s\ncalibrate_porosity = %s\n\n" % (
        json.dumps(tessellation), "true" if calibrate else "false")
    name = "%s-%s-%s-seed%d" % (scene, tessellation, "cal" if calibrate else "nocal", seed)
    path = os.path.join(tmp, name + ".toml")
    out = os.path.join(tmp, name)
    with open(path, "w") as f:
        f.write(head + sep + tail)
    proc = subprocess.run([mesopen, "target", path, "-o", out, "--no-plot", "--seed", str(seed),
                           "--threads", "1"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True)
    if proc.returncode != 0:
        return None, (proc.stderr or proc.stdout).strip()
    with open(os.path.join(out, "target.json")) as f:
        return json.load(f), None


def mean(values):
    values = [v for v in values if v is not None]
    return sum(values) / len(values) if values else None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mesopen", default=os.path.join(ROOT, "build", "bin", "mesopen"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "figures"))
    ap.add_argument("--seeds", nargs="*", type=int, default=[1, 2, 3])
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    runs, histograms = [], {}
    with tempfile.TemporaryDirectory() as tmp:
        for scene in SCENES:
            for calibrate in CALIBRATE:
                for tessellation in TESSELLATIONS:
                    for seed in args.seeds:
                        t, error = run(args.mesopen, tmp, scene, tessellation, calibrate, seed)
                        r = {"scene": scene, "tessellation": tessellation,
                             "calibrate_porosity": calibrate, "seed": seed, "error": error}
                        if t is not None:
                            r.update({
                                "grains": t["grains"],
                                "grain_sites": t["sites"]["grains"],
                                "void_sites": t["sites"]["voids"],
                                "porosity": t["porosity"],
                                "mean_diameter": t["mean_diameter"],
                                "std_diameter": t["std_diameter"],
                                "min_diameter": t["min_diameter"],
                                "max_diameter": t["max_diameter"],
                                "local_porosity_std": t["clustering"]["local_porosity_std"],
                                "tessellation_report": t["tessellation"],
                                "void_factor": t["porosity_control"]["void_factor"],
                                "porosity_trials": [
                                    [f, p] for f, p in zip(
                                        t["porosity_control"]["trial_factors"],
                                        t["porosity_control"]["trial_porosities"])],
                                "placement_iterations": t["placement"]["iterations"],
                                "seconds": t["seconds"],
                                "seconds_by_phase": t["seconds_by_phase"],
                            })
                            if scene == SCENES[0] and calibrate and seed == args.seeds[0]:
                                histograms[tessellation] = t
                        runs.append(r)
                        print("%-26s %-7s %-5s seed %d: %s" % (
                            scene, tessellation, calibrate, seed, error or
                            "%d grains, porosity %.2f %%, mean %.2f um, std %.2f um, %.1f s" % (
                                r["grains"], 100 * r["porosity"], 1e6 * r["mean_diameter"],
                                1e6 * r["std_diameter"], r["seconds"])), flush=True)

    # Means over the seeds.
    summary = []
    for scene in SCENES:
        for calibrate in CALIBRATE:
            for tessellation in TESSELLATIONS:
                rs = [r for r in runs if r["scene"] == scene and r["tessellation"] == tessellation
                      and r["calibrate_porosity"] == calibrate]
                ok = [r for r in rs if r["error"] is None]
                s = {"scene": scene, "tessellation": tessellation, "calibrate_porosity": calibrate,
                     "seeds": len(rs), "failed": len(rs) - len(ok)}
                for key in ("grains", "porosity", "mean_diameter", "std_diameter",
                            "local_porosity_std", "void_factor", "seconds"):
                    s[key] = mean([r[key] for r in ok])
                    s[key + "_range"] = ([min(r[key] for r in ok), max(r[key] for r in ok)]
                                         if ok else None)
                for key in ("merged_grains", "removed_voids", "restored_points", "lost_grains",
                            "merged_vertices", "kept_short_edges"):
                    s[key] = mean([r["tessellation_report"][key] for r in ok])
                summary.append(s)

    with open(os.path.join(args.out, "tessellations.json"), "w") as f:
        json.dump({"thesis": {k: dict(zip(("grains", "porosity_percent", "mean_um", "std_um"), v))
                              for k, v in THESIS.items()},
                   "means_over_seeds": summary, "runs": runs}, f, indent=1)

    def fmt(v, f):
        return "-" if v is None else f % v

    seeds = " ".join(str(s) for s in args.seeds)
    lines = [
        "# Tessellation study: power vs voronoi",
        "",
        "Written by `tools/studies/tessellations.py`. Thesis validation scenes (5 x 5 mm, 30 %% "
        "porosity), seeds %s, no mesh. Means over the seeds (min-max in brackets for the "
        "porosity and the std); repairs are per target: merged grain pairs / removed voids / "
        "restored points / lost grains; vertices merged (short edges kept). Seconds: one thread, "
        "whole run." % seeds,
        "",
        "| scene | tessellation | calibrated | grains | porosity % | mean D um | std D um "
        "| local porosity std | void factor | repairs | merged vertices (kept) | s |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for scene in SCENES:
        g, p, m, sd = THESIS[scene]
        lines.append("| %s | thesis | - | %s | %.2f | %.2f | %.2f | - | - | - | - | - |" % (
            scene, g if g else "-", p, m, sd))
        for s in (s for s in summary if s["scene"] == scene):
            if s["failed"] == s["seeds"]:
                lines.append("| %s | %s | %s | failed (%d of %d) | | | | | | | | |" % (
                    scene, s["tessellation"], "yes" if s["calibrate_porosity"] else "no",
                    s["failed"], s["seeds"]))
                continue
            pr, sr = s["porosity_range"], s["std_diameter_range"]
            lines.append(
                "| %s | %s | %s | %.0f | %.2f (%.2f-%.2f) | %.2f | %.2f (%.2f-%.2f) | %.4f | %.3f "
                "| %s/%s/%s/%s | %.0f (%.0f) | %.1f |%s" % (
                    scene, s["tessellation"], "yes" if s["calibrate_porosity"] else "no",
                    s["grains"], 100 * s["porosity"], 100 * pr[0], 100 * pr[1],
                    1e6 * s["mean_diameter"], 1e6 * s["std_diameter"], 1e6 * sr[0], 1e6 * sr[1],
                    s["local_porosity_std"], s["void_factor"],
                    fmt(s["merged_grains"], "%.1f"), fmt(s["removed_voids"], "%.1f"),
                    fmt(s["restored_points"], "%.1f"), fmt(s["lost_grains"], "%.1f"),
                    s["merged_vertices"], s["kept_short_edges"], s["seconds"],
                    " %d failed |" % s["failed"] if s["failed"] else ""))
    lines += [
        "",
        "## Every run",
        "",
        "| scene | tessellation | calibrated | seed | grains | porosity % | mean D um | std D um "
        "| local porosity std | void factor | merged grains | removed voids | restored points "
        "| lost grains | s |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in runs:
        head = "| %s | %s | %s | %d |" % (r["scene"], r["tessellation"],
                                          "yes" if r["calibrate_porosity"] else "no", r["seed"])
        if r["error"]:
            lines.append(head + " failed: %s |||||||||||" % r["error"].replace("|", "/"))
            continue
        t = r["tessellation_report"]
        lines.append(head + (" %d | %.2f | %.2f | %.2f | %.4f | %.3f | %d | %d | %d | %d | %.1f |" % (
            r["grains"], 100 * r["porosity"], 1e6 * r["mean_diameter"], 1e6 * r["std_diameter"],
            r["local_porosity_std"], r["void_factor"], t["merged_grains"], t["removed_voids"],
            t["restored_points"], t["lost_grains"], r["seconds"])))
    with open(os.path.join(args.out, "tessellations.md"), "w") as f:
        f.write("\n".join(lines) + "\n")

    # Grain-size histograms, 60 um uniform, seed 1, calibrated.
    fig, ax = plt.subplots(figsize=(7, 4), dpi=120)
    styles = {"power": ("#b08850", 0.55), "voronoi": ("#3b6ea8", 0.45)}
    for tessellation in TESSELLATIONS:
        t = histograms.get(tessellation)
        if t is None:
            continue
        edges = [1e6 * e for e in t["histogram"]["edges"]]
        colour, alpha = styles[tessellation]
        ax.stairs(t["histogram"]["counts"], edges, fill=True, color=colour, alpha=alpha,
                  label="%s: %d grains, porosity %.2f %%, mean %.2f um, std %.2f um" % (
                      tessellation, t["grains"], 100 * t["porosity"], 1e6 * t["mean_diameter"],
                      1e6 * t["std_diameter"]))
    g, p, m, sd = THESIS[SCENES[0]]
    ax.axvline(m, color="k", lw=0.8, ls="--",
               label="thesis: mean %.2f um, std %.2f um, porosity %.2f %%" % (m, sd, p))
    ax.set_xlabel("equivalent diameter D = sqrt(4A/pi) [um]")
    ax.set_ylabel("grains per 1 um bin")
    ax.set_title("60 um uniform, 5 x 5 mm, 30 %% porosity, clustered, seed %d" % args.seeds[0],
                 fontsize=10)
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "tessellations.png"))


if __name__ == "__main__":
    main()
