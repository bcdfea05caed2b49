"""CTest hugoniot_momentum (label verification): the planar compaction test's measures close the
Rankine-Hugoniot jump conditions they do not use.

tools/studies/hugoniot.py on one target (0.8 x 2 mm, 30 % porosity, seed 1), fe and the disks of
dem:quartz-bulk, with the plate held at u_p = 500 m/s. Checks, on fe:
  - the plate moved at exactly u_p (run.constant_velocity), every series sample;
  - the walls are smooth (run.smooth_walls): the grain nodes on the side edges behind the front
    slide down with the rest, at more than half u_p on average, and none moves across its edge;
  - momentum: the plate's measured stress equals rho_00 U_s u_p within 8 % (the front's speed
    and the force are measured independently; a steady front makes them equal. The granular
    front is not quite steady: it broadens as it runs, the material behind it still gaining
    speed, and the plate's stress comes out 2-5 % below rho_00 U_s u_p in every run measured
    (docs/hugoniot.md); a wrong force, area, density or front would miss by far more);
  - mass: the density measured behind the front equals rho_00 U_s / (U_s - u_p) within 10 %
    (the measuring window, a grain off the front, still holds some of the front's ramp);
  - U_s lies above the full-compaction bound of the solid EOS at that porosity, and below the
    solid's longitudinal sound speed;
  - the disks of the preset quartz-bulk, calibrated on this test (docs/coupling.md), stay
    calibrated: their U_s within 8 % of fe's on the same target (4 % over three seeds when
    calibrated; a single seed adds its own 3-4 %). The pair-calibrated disks miss by 41 %.

    hugoniot_momentum.py MESOPEN SCRATCH_DIR
"""
import json
import math
import os
import subprocess
import sys

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tools", "studies"))
import hugoniot  # noqa: E402


def main():
    mesopen, out = sys.argv[1], sys.argv[2]
    up = 500.0
    code = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "studies", "hugoniot.py"),
                           "-o", out, "--representations", "fe,dem:quartz-bulk",
                           "--velocities", str(up),
                           "--seeds", "1", "--width", "0.8e-3", "--height", "2e-3",
                           "--mesopen", mesopen, "--no-plot"]).returncode
    failures = []
    if code != 0:
        print("hugoniot.py exited with %d" % code)
        return 1
    with open(os.path.join(out, "hugoniot.json")) as f:
        runs = json.load(f)["runs"]
    run = next(r for r in runs if r["representation"] == "fe")
    disks = next(r for r in runs if r["representation"] == "dem:quartz-bulk")
    if "Us" not in run:
        print("no front measured: %s" % run.get("error"))
        return 1
    with h5py.File(os.path.join(out, "runs", "fe-500-s1", "out", "run.h5"), "r") as h5:
        vy = h5["series/projectile/vy"][:]
        x0, node_body = h5["mesh/x"][:], h5["mesh/node_body"][:]
        last = h5["frames"][sorted(h5["frames"].keys())[-1]]
        x, y, fvx, fvy = last["x"][:], last["y"][:], last["vx"][:], last["vy"][:]
    if np.max(np.abs(vy + up)) > 1e-9 * up:
        failures.append("plate velocity left -u_p by %g m/s" % np.max(np.abs(vy + up)))
    width = 0.8e-3
    side = (node_body != 0) & ((x0 <= 1e-8) | (x0 >= width - 1e-8))
    behind = side & (y > run["front_y"][-1] + 60e-6)
    slide = -np.mean(fvy[behind]) if behind.any() else 0.0
    print("side-edge nodes behind the front: %d, mean downward speed %.0f m/s, largest |vx| %g m/s"
          % (behind.sum(), slide, np.max(np.abs(fvx[side]))))
    if not behind.any() or slide < 0.5 * up:
        failures.append("smooth walls: side-edge nodes behind the front slide at %.0f m/s" % slide)
    if np.max(np.abs(fvx[side])) != 0.0 or np.max(np.abs(x[side] - x0[side])) > 1e-15:
        failures.append("smooth walls: side-edge nodes moved across their edge")
    momentum = run["sigma_plate"] / run["sigma_hugoniot"] - 1.0
    mass = run["rho_measured"] / run["rho_jump"] - 1.0
    print("U_s %.0f m/s; plate stress %.4g Pa against rho00 Us up %.4g Pa (%+.2f %%); density "
          "%.0f against the jump's %.0f kg/m^3 (%+.2f %%)" % (
              run["Us"], run["sigma_plate"], run["sigma_hugoniot"], 100 * momentum,
              run["rho_measured"], run["rho_jump"], 100 * mass))
    if abs(momentum) > 0.08:
        failures.append("momentum: plate stress off rho00 Us up by %.1f %% (allowed 8 %%)" %
                        (100 * momentum))
    if abs(mass) > 0.10:
        failures.append("mass: density off the jump's by %.1f %% (allowed 10 %%)" % (100 * mass))
    bound = hugoniot.full_compaction(run["rho00"])
    us_bound = np.interp(up, [b["up"] for b in bound], [b["Us"] for b in bound])
    q = hugoniot.QUARTZ
    c_l = math.sqrt((q["K"] + 4.0 / 3.0 * 46.92e9) / q["rho"])
    print("full-compaction bound %.0f m/s, solid longitudinal sound speed %.0f m/s" % (us_bound, c_l))
    if not us_bound < run["Us"] < c_l:
        failures.append("U_s %.0f m/s outside (%.0f, %.0f)" % (run["Us"], us_bound, c_l))
    if "Us" not in disks:
        failures.append("quartz-bulk disks: no front measured (%s)" % disks.get("error"))
    else:
        calibration = disks["Us"] / run["Us"] - 1.0
        print("quartz-bulk disks: U_s %.0f m/s (%+.1f %% against fe)" % (disks["Us"], 100 * calibration))
        if abs(calibration) > 0.08:
            failures.append("quartz-bulk disks' U_s off fe's by %.1f %% (allowed 8 %%)" %
                            (100 * calibration))
    for f in failures:
        print("FAIL: " + f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
