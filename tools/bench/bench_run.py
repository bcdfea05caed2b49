"""Benchmark of a whole penetration run: the thesis's run 6 (examples/baseline.toml, every grain
meshed) until the projectile is one length deep, without frames. Figures from each run's
summary.json: wall time, steps, the cost per element-step all in (solver time over the
element-steps computed), the share of the step spent in contact, and the saving from grains at
rest (element-steps computed over elements x steps). Each run is its own process; with more than
one the table gives the median (min-max), since the machine may be shared.

    python3 tools/bench/bench_run.py [--mesopen build/bin/mesopen] [--out build/bench]
        [--scene examples/baseline.toml] [--threads 2] [--runs 1] [--omp-wait-policy ACTIVE|PASSIVE]
        [--end-depth LENGTHS] [--mass-scaling RATIO]

On this shared machine two-thread timings drift with its load (run 6 from about 60 to 95 s within
a day), and so does the contact's share of them; on one thread the share is steady (within 0.003
over three runs): `--threads 1 --end-depth 0.4 --runs 3` compares two builds' contact cost.
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

FIGURES = [
    ("wall_seconds", "wall time [s]", lambda s: s["wall_seconds"]),
    ("loop_seconds", "time loop [s]", lambda s: s["loop_seconds"]),
    ("steps", "steps", lambda s: s["steps"]),
    ("depth_over_length", "depth / length", lambda s: s["projectile"]["depth"] / s["length"]),
    ("ns_per_element_step", "ns per element-step, all in", lambda s: s["ns_per_element_step"]),
    ("contact_share", "contact share of the steps", lambda s: s["contact"]["share_of_steps"]),
    ("active_element_share", "element-steps computed / all", lambda s: s["active_element_share"]),
    ("deepest_penetration", "deepest penetration / element",
     lambda s: s["contact"]["deepest_penetration_over_element_size"]),
    ("balance_error", "energy balance error", lambda s: s["energy"]["balance_error"]),
]


def with_run_key(scene_text, key, value):
    """The scene with `key = value` in its [run] table (in place of the scene's own)."""
    text = re.sub(rf"(?m)^{key}\s*=.*$", "", scene_text)
    return re.sub(r"(?m)^\[run\]\s*$", f"[run]\n{key} = {value}", text, count=1)


def without_frames(scene_text):
    """The scene with frame_interval = 0 in its [run] table."""
    return with_run_key(scene_text, "frame_interval", 0)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mesopen", default=os.path.join(ROOT, "build", "bin", "mesopen"))
    ap.add_argument("--out", default=os.path.join(ROOT, "build", "bench"))
    ap.add_argument("--scene", default=os.path.join(ROOT, "examples", "baseline.toml"))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--runs", type=int, default=1)
    # OpenMP's own waiting (spin, then sleep) unless given: PASSIVE sleeps at once, which costs
    # run 6 about 45 % on two threads (86 s against 59 s), ACTIVE spins.
    ap.add_argument("--omp-wait-policy", choices=["ACTIVE", "PASSIVE"])
    ap.add_argument("--end-depth", type=float,
                    help="run.end_depth, in projectile lengths (default: the scene's)")
    ap.add_argument("--mass-scaling", type=float,
                    help="run.mass_scaling_step_ratio (default: the scene's; 0: off)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    with open(args.scene) as f:
        text = without_frames(f.read())
    if args.end_depth is not None:
        if not 0.0 < args.end_depth <= 10.0:
            ap.error(f"--end-depth {args.end_depth}: allowed 0 < end depth <= 10 projectile lengths")
        text = with_run_key(text, "end_depth", args.end_depth)
    if args.mass_scaling is not None:
        if not 0.0 <= args.mass_scaling <= 1.0:
            ap.error(f"--mass-scaling {args.mass_scaling}: allowed 0 <= ratio <= 1")
        text = with_run_key(text, "mass_scaling_step_ratio", args.mass_scaling)
    length = float(re.search(r"(?m)^length\s*=\s*(\S+)", text).group(1))

    summaries = []
    with tempfile.TemporaryDirectory() as tmp:
        scene = os.path.join(tmp, "scene.toml")
        with open(scene, "w") as f:
            f.write(text)
        env = dict(os.environ)
        if args.omp_wait_policy:
            env["OMP_WAIT_POLICY"] = args.omp_wait_policy
        for _ in range(args.runs):
            out = os.path.join(tmp, "out")
            subprocess.run([args.mesopen, "run", scene, "-o", out, "--threads", str(args.threads),
                            "--quiet"], check=True, stdout=subprocess.DEVNULL,
                           env=env)
            with open(os.path.join(out, "summary.json")) as f:
                s = json.load(f)
            s["length"] = length
            summaries.append(s)

    policy = env.get("OMP_WAIT_POLICY", "the runtime's default")
    print(f"mesopen run {os.path.relpath(args.scene, ROOT)}, {args.threads} threads "
          f"(OMP_WAIT_POLICY {policy}), {args.runs} run(s), no frames; median (min-max)")
    found = re.search(r"(?m)^mass_scaling_step_ratio\s*=\s*(\S+)", text)
    ratio = float(found.group(1)) if found else 0.0
    print(f"  (mass scaling: {ratio if ratio > 0.0 else 'off'})")
    result = {"scene": os.path.relpath(args.scene, ROOT), "threads": args.threads,
              "mass_scaling_step_ratio": ratio,
              "runs": args.runs, "omp_wait_policy": policy, "elements": summaries[0]["model"]["elements"],
              "status": [s["status"] for s in summaries]}
    for key, label, get in FIGURES:
        values = [get(s) for s in summaries]
        result[key] = {"median": statistics.median(values), "min": min(values), "max": max(values),
                       "values": values}
        print(f"  {label:34s} {statistics.median(values):12.4g}  ({min(values):.4g} - {max(values):.4g})")
    path = os.path.join(args.out, "bench_run.json")
    with open(path, "w") as f:
        json.dump(result, f, indent=1)
    print("written:", path)


if __name__ == "__main__":
    main()
