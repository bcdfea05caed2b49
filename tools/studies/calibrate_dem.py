"""Calibrates the DEM disks on the bulk against the fully meshed grains (docs/coupling.md,
"Disks calibrated on the bulk").

1. The Hugoniot of the meshed grains (tools/studies/hugoniot.py, fe) and of equal-area disks with
   the Hertzian law at each --lengths value of dem.hertz_length; the length whose shock velocities
   U_s lie closest to fe's (the least of the largest relative difference over u_p) is chosen.
2. Run 6's projectile driven at constant velocity (run.constant_velocity) to one length: the
   resisting force (the grains' axial force on the projectile) averaged over the time to one
   length, per seed, and its mean. At the lowest --driven velocity, dem with each --rolling value
   of dem.rolling_friction: the value whose force lies closest to fe's is chosen, if its Hugoniot
   stays within 5 % of fe's (else the next closest). Then at every --driven velocity: fe, dem with
   the chosen disks and dem with the disks calibrated on a pair (the defaults).

    python3 tools/studies/calibrate_dem.py -o DIR [--seeds 1,2,3] [--velocities 250,...]
        [--lengths 6e-6,7e-6,8e-6,9e-6,10e-6] [--rolling 0,0.1,0.3] [--driven 500,1500]
        [--threads 2] [--docs DIR]
        [--mesopen build/bin/mesopen]

Writes DIR/calibration.json, DIR/calibration.md, DIR/calibration.png and DIR/summary.json (and
copies the first three to --docs as dem-calibration.*). Runs already made in DIR are reused.
Exit 2 on bad options, 1 if a run failed.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import time
import tomllib

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
from hugoniot import mean_sd, write_atomic  # noqa: E402

BULK = ['dem.disk_size="equal_area"', 'dem.normal_law="hertz"']


def fail_input(message):
    print("calibrate_dem.py: " + message, file=sys.stderr)
    sys.exit(2)


def numbers(text, name, kind=float):
    try:
        values = [kind(v) for v in text.split(",") if v.strip()]
    except ValueError:
        values = []
    if not values or any(not v > 0 for v in values):
        fail_input("--%s %r: allowed: a comma-separated list of positive numbers" % (name, text))
    return values


def hugoniot(args, out, representation, settings):
    """The Hugoniot table of one representation (hugoniot.py; reused when made before)."""
    table = os.path.join(out, "hugoniot.json")
    if not os.path.exists(table):
        words = [sys.executable, os.path.join(HERE, "hugoniot.py"), "-o", out,
                 "--representations", representation, "--velocities", args.velocities,
                 "--seeds", args.seeds, "--threads", str(args.threads), "--mesopen", args.mesopen,
                 "--no-plot"]
        for s in settings:
            words += ["--set", s]
        if subprocess.run(words, stdout=subprocess.DEVNULL).returncode != 0:
            return None
    with open(table) as f:
        return json.load(f)["table"]


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    return repr(v)


def driven_scene(up, seed, settings):
    """Run 6 (examples/baseline.toml) with the projectile held at u_p, no frames, and the
    settings (TABLE.KEY=VALUE) over it."""
    with open(os.path.join(ROOT, "examples", "baseline.toml"), "rb") as f:
        scene = tomllib.load(f)
    scene["target"]["seed"] = seed
    scene["run"].update({"velocity": float(up), "constant_velocity": True, "frame_interval": 0.0,
                         "vtk": False, "end_time": 1.5 * 1.7e-3 / up})
    for s in settings:
        key, _, value = s.partition("=")
        table, _, name = key.rpartition(".")
        node = scene
        for part in table.split("."):
            node = node.setdefault(part, {})
        node[name] = tomllib.loads("v = " + value)["v"]
    text = ""

    def write(prefix, table):
        nonlocal text
        plain = {k: v for k, v in table.items() if not isinstance(v, dict)}
        if plain:
            text += "\n[%s]\n" % prefix + "".join("%s = %s\n" % (k, toml_value(v))
                                                  for k, v in plain.items())
        for k, v in table.items():
            if isinstance(v, dict):
                write(prefix + "." + k if prefix else k, v)

    write("", scene)
    return text


def driven(args, name, up, seed, settings):
    """The mean resisting force on run 6's projectile held at u_p, to one length."""
    run_dir = os.path.join(args.out, "driven", "%s-%g-s%d" % (name, up, seed))
    out = os.path.join(run_dir, "out")
    if not os.path.exists(os.path.join(out, "summary.json")):
        os.makedirs(run_dir, exist_ok=True)
        scene = os.path.join(run_dir, "scene.toml")
        with open(scene, "w") as f:
            f.write(driven_scene(up, seed, settings))
        with open(os.path.join(run_dir, "log.txt"), "w") as log:
            subprocess.run([args.mesopen, "run", scene, "-o", out, "--threads", str(args.threads),
                            "--quiet"], stdout=log, stderr=subprocess.STDOUT)
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    row = {"name": name, "up": up, "seed": seed, "status": summary["status"],
           "wall_seconds": summary["wall_seconds"]}
    if summary["status"] != "completed":
        row["error"] = summary.get("failure", summary["status"])
        return row
    with h5py.File(os.path.join(out, "run.h5"), "r") as h5:
        t = h5["series/time"][:]
        force = h5["series/projectile/axial_force"][:]
    # time average (trapezoids) over the run: the work on the projectile over its path
    row["force"] = float(np.trapz(force, t) / (t[-1] - t[0]))
    row["time"] = float(t[-1])
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--out", required=True)
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--velocities", default="250,500,750,1000,1500")
    ap.add_argument("--lengths", default="6e-6,7e-6,8e-6,9e-6,10e-6")
    ap.add_argument("--driven", default="500,1500")
    ap.add_argument("--rolling", default="0,0.1,0.3")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--docs", default="")
    ap.add_argument("--mesopen", default=os.path.join(ROOT, "build", "bin", "mesopen"))
    args = ap.parse_args()
    seeds = numbers(args.seeds, "seeds", int)
    numbers(args.velocities, "velocities")
    lengths = numbers(args.lengths, "lengths")
    drives = numbers(args.driven, "driven")
    try:
        rollings = [float(v) for v in args.rolling.split(",") if v.strip()]
    except ValueError:
        rollings = []
    if not rollings or any(not 0 <= v <= 10 for v in rollings):
        fail_input("--rolling %r: allowed: comma-separated numbers from 0 to 10" % args.rolling)
    if not os.access(args.mesopen, os.X_OK):
        fail_input("--mesopen %s: not an executable" % args.mesopen)
    os.makedirs(args.out, exist_ok=True)
    start = time.time()

    # 1. Hugoniot: fe, then the disks at each Hertzian length
    fe = hugoniot(args, os.path.join(args.out, "hugoniot-fe"), "fe", [])
    if fe is None:
        print("calibrate_dem.py: the fe Hugoniot failed (%s)" % args.out, file=sys.stderr)
        return 1
    fe_us = {r["up"]: r["Us"] for r in fe}
    candidates = []
    pair = hugoniot(args, os.path.join(args.out, "hugoniot-dem-pair"), "dem", [])
    for h in lengths:
        table = hugoniot(args, os.path.join(args.out, "hugoniot-dem-h%g" % h), "dem",
                         BULK + ["dem.hertz_length=%r" % h])
        if table is None:
            continue
        errors = {r["up"]: r["Us"] / fe_us[r["up"]] - 1.0 for r in table}
        candidates.append({"hertz_length": h, "table": table, "errors": errors,
                           "worst": max(abs(e) for e in errors.values())})
        print("calibrate_dem: hertz_length %g m: U_s against fe %s" % (
            h, ", ".join("%g m/s %+.1f %%" % (u, 100 * e) for u, e in errors.items())), flush=True)
    if not candidates:
        return 1
    best = min(candidates, key=lambda c: c["worst"])
    print("calibrate_dem: chosen hertz_length %g m (largest U_s difference %.1f %%)" % (
        best["hertz_length"], 100 * best["worst"]), flush=True)

    # 2. the projectile driven at constant velocity: the rolling resistance at the lowest velocity
    lengths_set = BULK + ["dem.hertz_length=%r" % best["hertz_length"]]
    low = min(drives)
    fe_low = mean_sd([driven(args, "fe", low, seed, []).get("force", float("nan"))
                      for seed in seeds])[0]
    rolling_rows = []
    for mu_r in rollings:
        settings = ['run.representation="dem"'] + lengths_set + ["dem.rolling_friction=%r" % mu_r]
        force = mean_sd([driven(args, "dem-bulk-r%g" % mu_r, low, seed, settings).get(
            "force", float("nan")) for seed in seeds])[0]
        rolling_rows.append({"rolling_friction": mu_r, "force": force, "error": force / fe_low - 1})
        print("calibrate_dem: rolling friction %g: resisting force at %g m/s %+.1f %% against fe" %
              (mu_r, low, 100 * (force / fe_low - 1)), flush=True)
    chosen_rolling, rolling_hugoniot = None, None
    for row in sorted(rolling_rows, key=lambda r: abs(r["error"])):
        table = hugoniot(args, os.path.join(args.out, "hugoniot-dem-h%g-r%g" % (
            best["hertz_length"], row["rolling_friction"])), "dem",
            lengths_set + ["dem.rolling_friction=%r" % row["rolling_friction"]])
        errors = {r["up"]: r["Us"] / fe_us[r["up"]] - 1.0 for r in table} if table else {}
        row["hugoniot_errors"] = errors
        if errors and max(abs(e) for e in errors.values()) <= 0.05:
            chosen_rolling, rolling_hugoniot = row["rolling_friction"], table
            break
    if chosen_rolling is None:
        chosen_rolling = 0.0
    print("calibrate_dem: chosen rolling friction %g" % chosen_rolling, flush=True)
    chosen = lengths_set + ["dem.rolling_friction=%r" % chosen_rolling]
    rows = []
    for up in drives:
        for name, settings in (("fe", []),
                               ("dem-bulk-r%g" % chosen_rolling, ['run.representation="dem"'] + chosen),
                               ("dem-pair", ['run.representation="dem"'])):
            for seed in seeds:
                row = driven(args, name, up, seed, settings)
                rows.append(row)
                print("calibrate_dem: driven %s %g m/s seed %d: %s" % (
                    name, up, seed, row.get("error") or "%.4g N/m over %.3g s" % (
                        row["force"], row["time"])), flush=True)
    forces = []
    for up in drives:
        entry = {"up": up}
        for name in ("fe", "dem-bulk", "dem-pair"):
            key = "dem-bulk-r%g" % chosen_rolling if name == "dem-bulk" else name
            entry[name], entry[name + "_sd"] = mean_sd(
                [r.get("force", float("nan")) for r in rows if r["name"] == key and r["up"] == up])
        entry["dem-bulk_error"] = entry["dem-bulk"] / entry["fe"] - 1.0
        entry["dem-pair_error"] = entry["dem-pair"] / entry["fe"] - 1.0
        forces.append(entry)

    result = {"seeds": seeds, "velocities": args.velocities, "fe": fe, "dem_pair": pair,
              "candidates": candidates, "chosen_hertz_length": best["hertz_length"],
              "rolling": rolling_rows, "chosen_rolling_friction": chosen_rolling,
              "chosen_hugoniot": rolling_hugoniot, "driven": rows, "forces": forces}
    write_atomic(os.path.join(args.out, "calibration.json"),
                 json.dumps(result, indent=1, allow_nan=True))
    write_markdown(os.path.join(args.out, "calibration.md"), result, args)
    plot(os.path.join(args.out, "calibration.png"), result)
    failed = [r for r in rows if "error" in r]
    write_atomic(os.path.join(args.out, "summary.json"), json.dumps(
        {"command": "calibrate_dem", "chosen_hertz_length": best["hertz_length"],
         "chosen_rolling_friction": chosen_rolling, "largest_Us_difference": best["worst"],
         "forces": forces, "failed": len(failed), "wall_seconds": time.time() - start,
         "files": ["calibration.json", "calibration.md", "calibration.png"]},
        indent=1, allow_nan=True))
    if args.docs:
        os.makedirs(args.docs, exist_ok=True)
        for ext in ("json", "md", "png"):
            shutil.copyfile(os.path.join(args.out, "calibration." + ext),
                            os.path.join(args.docs, "dem-calibration." + ext))
    print("calibrate_dem: done in %.0f s; %s" % (time.time() - start,
                                                os.path.join(args.out, "calibration.md")))
    return 1 if failed else 0


def write_markdown(path, r, args):
    fe = {x["up"]: x for x in r["fe"]}
    pair = {x["up"]: x for x in (r["dem_pair"] or [])}
    lines = ["# DEM disks calibrated on the bulk against fe", "",
             "`python3 tools/studies/calibrate_dem.py -o DIR --seeds %s` (seeds %s; mean +- "
             "standard deviation over them)." % (",".join(map(str, r["seeds"])),
                                                 ", ".join(map(str, r["seeds"]))), "",
             "## Shock velocity U_s [m/s] of the planar compaction test, 30 % porosity", "",
             "| u_p [m/s] | fe | dem, pair-calibrated disks | " +
             " | ".join("dem, equal-area Hertzian, h = %g um" % (1e6 * c["hertz_length"])
                        for c in r["candidates"]) + " |",
             "|---|---|---|" + "---|" * len(r["candidates"])]
    for up in sorted(fe):
        cells = ["%.0f +- %.0f" % (fe[up]["Us"], fe[up]["Us_sd"])]
        p = pair.get(up)
        cells.append("%.0f (%+.1f %%)" % (p["Us"], 100 * (p["Us"] / fe[up]["Us"] - 1))
                     if p else "-")
        for c in r["candidates"]:
            row = next(x for x in c["table"] if x["up"] == up)
            cells.append("%.0f (%+.1f %%)" % (row["Us"], 100 * c["errors"][up]))
        lines.append("| %g | %s |" % (up, " | ".join(cells)))
    lines += ["", "Chosen: dem.hertz_length = %g m (the least of the largest difference)." %
              r["chosen_hertz_length"], "",
              "## Rolling resistance: run 6's projectile driven at %g m/s" % min(
                  f["up"] for f in r["forces"]), "",
              "| dem.rolling_friction | resisting force against fe | Hugoniot U_s against fe "
              "(by u_p) |", "|---|---|---|"]
    for row in r["rolling"]:
        hug = ", ".join("%g: %+.1f %%" % (float(u), 100 * e)
                        for u, e in row.get("hugoniot_errors", {}).items()) or "not run"
        lines.append("| %g | %+.1f %% | %s |" % (row["rolling_friction"], 100 * row["error"], hug))
    lines += ["", "Chosen: dem.rolling_friction = %g." % r["chosen_rolling_friction"], "",
              "## Run 6's projectile driven at constant velocity to one length: the resisting "
              "force [kN/m], time-averaged", "",
              "| u_p [m/s] | fe | dem, bulk-calibrated | difference | dem, pair-calibrated | "
              "difference |", "|---|---|---|---|---|---|"]
    for f in r["forces"]:
        lines.append("| %g | %.1f +- %.1f | %.1f +- %.1f | %+.1f %% | %.1f +- %.1f | %+.1f %% |" % (
            f["up"], 1e-3 * f["fe"], 1e-3 * f["fe_sd"], 1e-3 * f["dem-bulk"],
            1e-3 * f["dem-bulk_sd"], 100 * f["dem-bulk_error"], 1e-3 * f["dem-pair"],
            1e-3 * f["dem-pair_sd"], 100 * f["dem-pair_error"]))
    write_atomic(path, "\n".join(lines) + "\n")


def plot(path, r):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.5))
    fe = sorted(r["fe"], key=lambda x: x["up"])
    a.errorbar([x["up"] for x in fe], [x["Us"] for x in fe], yerr=[x["Us_sd"] for x in fe],
               color="k", marker="o", capsize=3, lw=2, label="fe (meshed grains)")
    if r["dem_pair"]:
        p = sorted(r["dem_pair"], key=lambda x: x["up"])
        a.plot([x["up"] for x in p], [x["Us"] for x in p], "s--", color="tab:red",
               label="dem, pair-calibrated disks")
    for c in r["candidates"]:
        t = sorted(c["table"], key=lambda x: x["up"])
        chosen = c["hertz_length"] == r["chosen_hertz_length"]
        a.plot([x["up"] for x in t], [x["Us"] for x in t], "^-" if chosen else ":",
               lw=2 if chosen else 1, alpha=1 if chosen else 0.6,
               label="dem, equal-area Hertzian, h = %g um%s" % (1e6 * c["hertz_length"],
                                                                 " (chosen)" if chosen else ""))
    a.set_xlabel("particle velocity u_p [m/s]")
    a.set_ylabel("shock velocity U_s [m/s]")
    a.grid(alpha=0.3)
    a.legend(fontsize=7)
    names = [("fe", "fe"), ("dem-bulk", "dem, bulk"), ("dem-pair", "dem, pair")]
    width = 0.25
    for k, (key, label) in enumerate(names):
        xs = np.arange(len(r["forces"])) + (k - 1) * width
        b.bar(xs, [1e-3 * f[key] for f in r["forces"]], width,
              yerr=[1e-3 * f[key + "_sd"] for f in r["forces"]], capsize=3, label=label)
    b.set_xticks(np.arange(len(r["forces"])))
    b.set_xticklabels(["%g m/s" % f["up"] for f in r["forces"]])
    b.set_ylabel("resisting force, mean to one length [kN/m]")
    b.set_title("run 6's projectile driven at constant velocity", fontsize=9)
    b.legend(fontsize=8)
    b.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    fig.savefig(path + ".tmp.png", dpi=110)
    os.replace(path + ".tmp.png", path)


if __name__ == "__main__":
    sys.exit(main())
