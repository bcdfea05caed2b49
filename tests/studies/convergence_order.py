#!/usr/bin/python3
"""tools/studies/convergence.py on made-up runs whose measures follow f = f0 + C h^p exactly
(p = 1.5, meshes 7, 10, 14 and 20 um, unevenly refined; three seeds, each its own f0): the
observed order is p and the value at h = 0 the seeds' mean f0, to 1e-9 (the procedure is exact on
a power law; the tolerance is round-off); a measure whose differences change sign is oscillatory,
with no order; a seed whose own sequence is not monotonic is counted so. Also its exit codes: 2 on
a directory that is no campaign's, 1 with fewer than three meshes.

    /usr/bin/python3 tests/studies/convergence_order.py SCRATCH_DIR
"""
import json
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tools", "studies"))
import convergence  # noqa: E402

P, C = 1.5, 2.0e6
MESHES = [20e-6, 14e-6, 10e-6, 7e-6]
SEEDS = [1, 1001, 2001]
F0 = {"time_to_end": 1.3e-6, "speed_at_end": 1200.0, "peak_abs_H": 2e-6,
      "lateral_displacement": 5e-6, "tilt": 0.01}
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print("FAILED: " + what)


def value(key, h, k):
    # each seed its own f0; tilt oscillates with the mesh for seed 2001 only
    v = F0[key] * (1.0 + 0.01 * k) + F0[key] * C * h ** P
    if key == "tilt" and k == 2:
        v += F0[key] * (0.5 if h in (14e-6, 7e-6) else 0.0)
    return v


def write_run(d, h, k, seed):
    os.makedirs(d)
    n = 50
    t = np.linspace(0.0, value("time_to_end", h, k), n)
    speed = value("speed_at_end", h, k)
    with h5py.File(os.path.join(d, "run.h5"), "w") as f:
        s = f.create_group("series")
        s["time"] = t
        s["projectile/vx"] = np.zeros(n)
        s["projectile/vy"] = np.linspace(-1500.0, -speed, n)
        s["projectile/rotational_momentum"] = -value("peak_abs_H", h, k) * np.linspace(0, 1, n) ** 2
        s["projectile/com_x"] = np.linspace(1e-3, 1e-3 + value("lateral_displacement", h, k), n)
        s["projectile/tilt"] = np.linspace(0.0, value("tilt", h, k), n)
    with open(os.path.join(d, "scene.toml"), "w") as f:
        f.write("[target]\nmesh_size = %r\nseed = %d\n[run]\nsafety = 0.9\n" % (h, seed))
    with open(os.path.join(d, "summary.json"), "w") as f:
        json.dump({"status": "completed", "wall_seconds": 1.0}, f)


def main(scratch):
    shutil.rmtree(scratch, ignore_errors=True)
    # the formulas alone
    h = [7e-6, 10e-6, 14e-6]
    kind, p = convergence.observed_order(h, [3.0 + C * x ** P for x in h])
    check(kind == "monotonic" and abs(p - P) < 1e-9, "order of a power law: %s %s" % (kind, p))
    f0 = convergence.extrapolate(h[0], h[1], 3.0 + C * h[0] ** P, 3.0 + C * h[1] ** P, P)
    check(abs(f0 - 3.0) < 1e-9, "extrapolated %r" % f0)
    check(convergence.observed_order(h, [1.0, 2.0, 1.5])[0] == "oscillatory", "oscillatory")
    check(convergence.observed_order(h, [1.0, 1.0, 1.0])[0] == "converged", "converged")
    # a made-up campaign
    camp = os.path.join(scratch, "campaign")
    for h_ in MESHES:
        for k, seed in enumerate(SEEDS):
            write_run(os.path.join(camp, "runs", "mesh-%g" % (1e6 * h_), "r%d" % k), h_, k, seed)
    code = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "studies", "convergence.py"),
                           camp], capture_output=True, text=True)
    check(code.returncode == 0, "exit code %d: %s" % (code.returncode, code.stderr))
    with open(os.path.join(camp, "convergence.json")) as f:
        result = json.load(f)["analysis"]["0.9"]["measures"]
    for key in ["time_to_end", "speed_at_end", "peak_abs_H", "lateral_displacement"]:
        m = result[key]
        mean_f0 = F0[key] * 1.01
        check(m["kind"] == "monotonic" and abs(m["order"] - P) < 1e-9, "%s order %s" % (key, m["order"]))
        check(abs(m["extrapolated"] - mean_f0) < 1e-9 * abs(mean_f0), "%s at h = 0: %r against %r"
              % (key, m["extrapolated"], mean_f0))
        check(list(m["seed_kinds"].values()).count("monotonic") == 3, "%s seeds" % key)
        check(m["seed_interval"] > 0.0, "%s seed interval" % key)
    kinds = result["tilt"]["seed_kinds"]
    check(kinds["2001"] == "oscillatory" and kinds["1"] == "monotonic", "tilt's seeds %s" % kinds)
    for name in ["convergence.md", "convergence.png"]:
        check(os.path.getsize(os.path.join(camp, name)) > 0, name)
    # a seed missing at the finest mesh: the order from the seeds run at every mesh (the means of
    # different layouts at different meshes mix the seeds' spread into the order)
    shutil.rmtree(os.path.join(camp, "runs", "mesh-7", "r2"))
    code = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "studies", "convergence.py"),
                           camp], capture_output=True, text=True)
    check(code.returncode == 0, "a seed missing: exit code %d" % code.returncode)
    with open(os.path.join(camp, "convergence.json")) as f:
        m = json.load(f)["analysis"]["0.9"]["measures"]["speed_at_end"]
    check(abs(m["order"] - P) < 1e-9, "a seed missing: order %s" % m["order"])
    check(abs(m["extrapolated"] - F0["speed_at_end"] * 1.005) < 1e-6,
          "a seed missing: at h = 0 %r" % m["extrapolated"])
    # exit codes
    code = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "studies", "convergence.py"),
                           scratch], capture_output=True, text=True)
    check(code.returncode == 2, "not a campaign: exit %d" % code.returncode)
    for h_ in MESHES[:2]:
        shutil.rmtree(os.path.join(camp, "runs", "mesh-%g" % (1e6 * h_)))
    code = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "studies", "convergence.py"),
                           camp], capture_output=True, text=True)
    check(code.returncode == 1, "two meshes: exit %d" % code.returncode)
    print("convergence_order: %s" % ("FAILED" if failures else "passed"))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/convergence_order"))
