#!/usr/bin/python3
"""tools/studies/scaling_model.py against figures worked by hand: one rank's step is the unit costs
times run 6's counts; today's design receives 48 bytes per halo node and 40 per body of them,
and every moving body's 40 at a search for pairs; the
spatial design's halo falls as 1/sqrt(P); bad arguments (a rank count of 0, an infinite latency,
a JSON file in no directory) exit with 2.

    /usr/bin/python3 tests/studies/scaling_model.py WORKDIR
"""
import json
import math
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TOOL = os.path.join(ROOT, "tools", "studies", "scaling_model.py")


def close(a, b, what):
    if not math.isclose(a, b, rel_tol=1e-9):
        sys.exit("scaling_model: %s is %r, expected %r" % (what, a, b))


def main():
    work = sys.argv[1]
    os.makedirs(work, exist_ok=True)
    out = os.path.join(work, "model.json")
    subprocess.run([sys.executable, TOOL, "--elements", "446558", "--ranks", "1,4,16",
                    "--c-e", "30e-9", "--c-n", "20e-9", "--c-p", "500e-9", "--latency", "1e-6",
                    "--search-every", "50", "--json", out], check=True, stdout=subprocess.DEVNULL)
    m = json.load(open(out))
    # run 6 itself: 124,306 moving elements, 82,395 nodes, 3,089 pairs a step
    one = 124306 * 30e-9 + 82395 * 20e-9 + 3089 * 500e-9
    close(m["serial_step_s"], one, "one rank's step")
    rows = {r["today"]["ranks"]: r for r in m["rows"]}
    close(rows[1]["spatial"]["step_s"], one, "the spatial design on one rank")
    today4 = rows[4]["today"]
    halo4 = rows[4]["spatial"]["halo_nodes"]
    close(today4["halo_nodes"], halo4, "today's halo at 4 ranks")
    # the halo nodes and their bodies' boxes; every moving body's box at a search, every 50 steps
    close(today4["bytes_received"],
          (48 + 40 * 6199 / 303205) * halo4 + 40 * 6199 * 82395 / 303205 * 3 / 4 / 50,
          "today's bytes at 4 ranks")
    close(today4["compute_s"], 124306 / 4 * 30e-9 + 82395 / 4 * 20e-9 + 3089 / 4 * 500e-9,
          "today's compute at 4 ranks")
    close(today4["comm_s"], (3 / 50 + 3 * 0.15 + 9) * 1e-6 + today4["bytes_received"] / 10e9 +
          2 * 2 * 1e-6,
          "today's communication at 4 ranks")
    close(rows[4]["spatial"]["halo_nodes"] / rows[16]["spatial"]["halo_nodes"], 2.0,
          "the halo from 4 to 16 ranks")
    # (at 16 ranks today's design is the faster on run 6: the spatial one moves its halo's nodes
    # too; it communicates less and holds a sixteenth of the model)
    for key in ("comm_s", "memory_bytes"):
        if not rows[16]["spatial"][key] < rows[16]["today"][key]:
            sys.exit("scaling_model: the spatial design's %s is not the smaller at 16 ranks" % key)
    for args, key in ((["--ranks", "0"], "--ranks"), (["--latency", "inf"], "--latency"),
                      (["--json", os.path.join(work, "no", "such.json")], "--json")):
        bad = subprocess.run([sys.executable, TOOL] + args, stdout=subprocess.DEVNULL,
                             stderr=subprocess.PIPE, text=True)
        if bad.returncode != 2 or key not in bad.stderr:
            sys.exit("scaling_model: %s gave %d: %s" % (" ".join(args), bad.returncode,
                                                        bad.stderr))
    print("scaling_model: one rank %.4g ms a step; the halo halves from 4 to 16 ranks"
          % (1e3 * one))


if __name__ == "__main__":
    main()
