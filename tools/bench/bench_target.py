"""Benchmark of the target generator: seconds and peak memory for 1e4, 1e5 and 1e6 grains
(sites, placement, porosity control, tessellation, void removal; no mesh), and the baseline
target of the runs with its 10 um mesh. Each case runs as its own process several times; the
table gives the median (min-max), since the machine may be shared.

    python3 tools/bench/bench_target.py [--mesopen build/bin/mesopen] [--out build/bench]
        [--runs 3] [--sizes 1e4 1e5 1e6]
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def scene_for(grains):
    """A square box holding `grains` grains of 42-78 um at 30 % porosity, regular placement."""
    d = 60e-6
    side = math.sqrt(grains * math.pi * d * d / 4 / 0.7)
    return (f"[target]\nwidth = {side!r}\nheight = {side!r}\ndiameter = [42e-6, 78e-6]\n"
            "porosity = 0.30\nplacement = \"regular\"\nmesh = \"none\"\n\n[projectile]\nenabled = false\n")


def run(mesopen, scene_path, out):
    subprocess.run([mesopen, "target", scene_path, "-o", out, "--no-plot"], check=True,
                   stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "target.json")) as f:
        return json.load(f)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mesopen", default=os.path.join(ROOT, "build", "bin", "mesopen"))
    ap.add_argument("--out", default=os.path.join(ROOT, "build", "bench"))
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--sizes", nargs="*", type=float, default=[1e4, 1e5, 1e6])
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    cases = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.sizes:
            path = os.path.join(tmp, "grains-%d.toml" % n)
            with open(path, "w") as f:
                f.write(scene_for(int(n)))
            cases.append(("%.0e grains, no mesh" % n, path))
        cases.append(("baseline target + 10 um mesh", os.path.join(ROOT, "examples", "targets", "baseline.toml")))
        rows = []
        for name, path in cases:
            results = [run(args.mesopen, path, os.path.join(tmp, "out")) for _ in range(args.runs)]
            secs = [r["seconds"] for r in results]
            mem = [r["peak_memory_bytes"] / 2**20 for r in results]
            phases = {k: statistics.median(r["seconds_by_phase"][k] for r in results)
                      for k in results[0]["seconds_by_phase"]}
            rows.append({"case": name, "grains": results[0]["grains"],
                         "triangles": results[0]["mesh"]["triangles"],
                         "seconds_median": statistics.median(secs), "seconds_min": min(secs),
                         "seconds_max": max(secs), "peak_memory_mib_median": statistics.median(mem),
                         "microseconds_per_grain": 1e6 * statistics.median(secs) / results[0]["grains"],
                         "phases_median": phases, "runs": args.runs})
            print("  done: %s" % name, file=sys.stderr)

    head = "%-32s %9s %9s %22s %10s %12s" % ("case", "grains", "triangles", "seconds median (range)",
                                              "peak MiB", "us / grain")
    print(head)
    print("-" * len(head))
    for r in rows:
        print("%-32s %9d %9d %8.2f (%5.2f-%6.2f) %10.0f %12.1f" % (
            r["case"], r["grains"], r["triangles"], r["seconds_median"], r["seconds_min"], r["seconds_max"],
            r["peak_memory_mib_median"], r["microseconds_per_grain"]))
    print("\nphases (median seconds):")
    for r in rows:
        print("  %-30s %s" % (r["case"], "  ".join("%s %.2f" % kv for kv in r["phases_median"].items())))
    if len(rows) >= 3:
        growth = rows[2]["seconds_median"] / rows[1]["seconds_median"]
        print("\ngrowth 1e5 -> 1e6 grains: x%.1f (linear: x10)" % growth)
    with open(os.path.join(args.out, "bench_target.json"), "w") as f:
        json.dump({"benchmark": "target generator", "cores": os.cpu_count(), "rows": rows}, f, indent=2)
    print("written: %s" % os.path.join(args.out, "bench_target.json"))


if __name__ == "__main__":
    main()
