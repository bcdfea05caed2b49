"""Benchmark of what sharing a run among MPI ranks costs each rank, per step: the bytes it receives
from the others (and the collective calls and messages that bring them), the active elements it
owns, its halo nodes, the pairs of bodies its contact searches, and its peak memory. The scene is the thesis's run 6 (examples/baseline.toml, every
grain meshed, or --representation dem or hybrid: grains as LIGGGHTS's disks, all or those away
from the projectile's path) on a target --size-factor times as wide and as high (2: 14.152 x 7.076
mm, 4 times the area), run for a fixed number of steps (run.max_steps) without frames, at each
rank count:

    mpirun --allow-run-as-root --oversubscribe -np N mesopen run SCENE -o DIR --threads 1

Every figure is the run's own, from its summary.json `partition` block (docs/solver.md, "The
bodies among MPI ranks"): counts, not seconds. With more ranks than cores the ranks take turns
on them, so wall times say nothing about the decomposition; the bytes and the work do.

    python3 tools/bench/bench_mpi.py [--mesopen build/bin/mesopen] [--out build/bench]
        [--scene examples/baseline.toml] [--representation fe] [--size-factor 2] [--steps 400]
        [--ranks 1,2,4,8] [--mpirun mpirun] [--max-level 0]

--max-level L > 0 runs with multiple time stepping (run.max_level = L) and
adds the element updates computed over those of a single rate.

Writes OUT/bench_mpi.json (OUT/bench_mpi-dem.json, -hybrid.json for the others; -levels2.json
and so on with --max-level); exit 1 if a run
fails, its projectile is still in free flight at the end (more --steps needed), or the ranks
disagree on the projectile's motion (fe: to the bit; with disks, by more than 1e-6 of its speed,
as LIGGGHTS sums a disk's forces in another order on another number of ranks); 2 on bad
arguments.
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def with_key(scene_text, table, key, value):
    """The scene with `key = value` in its [table] (in place of the scene's own)."""
    start = re.search(rf"(?m)^\[{table}\]\s*$", scene_text)
    if not start:
        return scene_text.rstrip("\n") + f"\n\n[{table}]\n{key} = {value}\n"
    end = re.search(r"(?m)^\[", scene_text[start.end():])
    stop = start.end() + end.start() if end else len(scene_text)
    body = re.sub(rf"(?m)^{key}\s*=.*\n?", "", scene_text[start.end():stop])
    return scene_text[:start.end()] + f"\n{key} = {value}" + body + scene_text[stop:]


def key_value(scene_text, table, key):
    """The number `key` of [table] in the scene (None when absent)."""
    start = re.search(rf"(?m)^\[{table}\]\s*$", scene_text)
    if not start:
        return None
    end = re.search(r"(?m)^\[", scene_text[start.end():])
    body = scene_text[start.end():start.end() + end.start() if end else len(scene_text)]
    found = re.search(rf"(?m)^{key}\s*=\s*([^#\s]+)", body)
    return float(found.group(1)) if found else None


def positive_ranks(text):
    try:
        ranks = [int(r) for r in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}': a comma-separated list of rank counts")
    if not ranks or any(not 1 <= r <= 64 for r in ranks):
        raise argparse.ArgumentTypeError(f"'{text}': each rank count from 1 to 64")
    return ranks


def run(args, scene, out, ranks):
    """One run on `ranks` ranks; its summary.json."""
    cmd = [args.mpirun, "--allow-run-as-root", "--oversubscribe", "-np", str(ranks),
           args.mesopen, "run", scene, "-o", out, "--threads", "1", "--quiet"]
    done = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    path = os.path.join(out, "summary.json")
    if done.returncode != 0 or not os.path.exists(path):
        sys.exit(f"bench_mpi: {' '.join(cmd)} ended with exit code {done.returncode}:\n"
                 f"{done.stdout[-4000:]}")
    with open(path) as f:
        return json.load(f)


def per_rank(summary):
    """The partition block's figures, one dict per rank."""
    p = summary["partition"]
    rows = []
    for r in range(summary["ranks"]):
        memory = p["peak_memory_bytes"][r]
        rows.append({
            "rank": r,
            "bytes_received_per_step": p["bytes_received_per_step"][r],
            "max_bytes_received_in_a_step": p["max_bytes_received_in_a_step"][r],
            "bytes_received_outside_steps_per_step": p["bytes_received_outside_steps_per_step"][r],
            "collectives_per_step": p["collectives_per_step"][r],
            "messages_per_step": p["messages_per_step"][r],
            "active_elements_owned_per_step": p["active_elements_per_step"][r],
            "active_nodes_owned_per_step": p["active_nodes_per_step"][r],
            "halo_nodes_per_step": p["halo_nodes_per_step"][r],
            "contact_pairs_per_step": p["contact_pairs_per_step"][r],
            "peak_memory_mib": memory / 2**20 if memory is not None else None,
            "bodies_owned": p["bodies"][r],
        })
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mesopen", default=os.path.join(ROOT, "build", "bin", "mesopen"))
    ap.add_argument("--out", default=os.path.join(ROOT, "build", "bench"))
    ap.add_argument("--scene", default=os.path.join(ROOT, "examples", "baseline.toml"))
    ap.add_argument("--representation", choices=["fe", "dem", "hybrid"], default="fe",
                    help="the grains meshed (fe), disks (dem) or both (hybrid); default fe")
    ap.add_argument("--size-factor", type=float, default=2.0,
                    help="the target's width and height times the scene's (default 2: 4x the area)")
    ap.add_argument("--steps", type=int, default=400, help="run.max_steps (default 400)")
    ap.add_argument("--ranks", type=positive_ranks, default=[1, 2, 4, 8],
                    help="rank counts, comma-separated (default 1,2,4,8)")
    ap.add_argument("--mpirun", default="mpirun")
    ap.add_argument("--max-level", type=int, default=0,
                    help="run.max_level: multiple time stepping's largest level (default 0: none)")
    args = ap.parse_args()
    if not 0 <= args.max_level <= 3:
        ap.error(f"--max-level {args.max_level}: allowed 0 to 3")
    if not 0.25 <= args.size_factor <= 4.0:
        ap.error(f"--size-factor {args.size_factor}: allowed 0.25 to 4")
    if not 1 <= args.steps <= 100000:
        ap.error(f"--steps {args.steps}: allowed 1 to 100000")
    if not os.access(args.mesopen, os.X_OK):
        ap.error(f"--mesopen {args.mesopen}: not an executable (build first: tools/test.sh)")
    if shutil.which(args.mpirun) is None:
        ap.error(f"--mpirun {args.mpirun}: not found (Debian: openmpi-bin)")
    try:
        with open(args.scene) as f:
            text = f.read()
    except OSError as e:
        ap.error(f"--scene {args.scene}: {e.strerror}")
    width, height = key_value(text, "target", "width"), key_value(text, "target", "height")
    if width is None or height is None:
        ap.error(f"--scene {args.scene}: no [target] width and height")
    width, height = width * args.size_factor, height * args.size_factor
    for table, key, value in [("target", "width", repr(width)), ("target", "height", repr(height)),
                              ("run", "representation", f'"{args.representation}"'),
                              ("run", "max_steps", args.steps), ("run", "frame_interval", 0),
                              ("run", "vtk", "false"), ("run", "max_level", args.max_level)]:
        text = with_key(text, table, key, value)
    os.makedirs(args.out, exist_ok=True)

    results = []
    with tempfile.TemporaryDirectory() as tmp:
        scene = os.path.join(tmp, "scene.toml")
        with open(scene, "w") as f:
            f.write(text)
        for ranks in args.ranks:
            s = run(args, scene, os.path.join(tmp, f"np{ranks}"), ranks)
            results.append({"np": ranks, "status": s["status"], "ended_by": s.get("ended_by"),
                            "steps": s["steps"], "model": s["model"],
                            "projectile_vy": s["projectile"]["vy"],
                            "projectile_depth": s["projectile"]["depth"],
                            "velocity": s["run"]["velocity"],
                            "rebalances": s["partition"]["rebalances"],
                            "imbalance": s["partition"]["imbalance"],
                            "element_update_share":
                                s.get("multiple_time_stepping", {}).get("element_update_share", 1.0),
                            "per_rank": per_rank(s)})

    first = results[0]
    problems = []
    for r in results:
        if r["status"] != "completed" or r["ended_by"] != "max_steps":
            problems.append(f"np {r['np']}: {r['status']}, ended by {r['ended_by']}")
        if not -r["projectile_vy"] < r["velocity"]:
            problems.append(f"np {r['np']}: the projectile was not slowed in {r['steps']} steps "
                            f"(vy {r['projectile_vy']} m/s): no contact yet; raise --steps")
        tolerance = 0.0 if args.representation == "fe" else 1e-6 * first["velocity"]
        if abs(r["projectile_vy"] - first["projectile_vy"]) > tolerance or \
                r["steps"] != first["steps"] or \
                r["element_update_share"] != first["element_update_share"]:
            problems.append(f"np {r['np']}: the projectile's vy {r['projectile_vy']} m/s after "
                            f"{r['steps']} steps, against {first['projectile_vy']} after "
                            f"{first['steps']} on np {first['np']}")

    m = first["model"]
    print(f"mesopen run {os.path.relpath(args.scene, ROOT)} on a {width * 1e3:.3f} x "
          f"{height * 1e3:.3f} mm target ({args.size_factor ** 2:g} x the area), "
          f"{args.representation}{f', max_level {args.max_level}' if args.max_level else ''}: "
          f"{m['bodies']} bodies, {m['elements']} elements, {m['nodes']} nodes; "
          f"{first['steps']} steps, no frames, --threads 1")
    spread = max(abs(r["projectile_vy"] - first["projectile_vy"]) for r in results)
    print(f"  the projectile slowed from {first['velocity']:g} to {-first['projectile_vy']:.2f} "
          f"m/s, {first['projectile_depth'] * 1e6:.1f} um deep (the same on every np: "
          f"{'yes, to the bit' if spread == 0.0 else f'within {spread:.2g} m/s'})")
    if args.max_level:
        print("  element updates over a single rate's: " +
              ", ".join(f"np {r['np']} {r['element_update_share']:.3f}" for r in results))
    print("  Counts per rank per step, not seconds: with more ranks than cores the ranks take turns on\n"
          "  them, so wall times do not measure the decomposition.\n"
          "  KB/step: bytes received from the other ranks within a step (a reduction counted as a\n"
          "    gather; KB = 1000 bytes), the mean over the steps; max: the most in one step;\n"
          "    outside: in the time loop between steps (series, frames); calls: MPI collectives a step;\n"
          "    msgs: point-to-point messages it received a step\n"
          "  elements: active elements owned (bodies at rest are skipped); nodes: the nodes it moves\n"
          "    (its moving bodies'); halo: nodes of moving bodies the rank does not own, whose\n"
          "    position and velocity it receives every step;\n"
          "    pairs: pairs of bodies its contact searched; MiB: peak memory (VmHWM, set-up included)")
    print(f"  {'np':>3} {'rank':>4} {'KB/step':>9} {'max':>7} {'outside':>8} {'calls':>6} "
          f"{'msgs':>6} "
          f"{'elements':>9} {'nodes':>7} {'halo':>7} {'pairs':>6} {'MiB':>6}")
    for r in results:
        for row in r["per_rank"]:
            mem = row["peak_memory_mib"]
            print(f"  {r['np']:>3} {row['rank']:>4} {row['bytes_received_per_step'] / 1e3:>9.1f} "
                  f"{row['max_bytes_received_in_a_step'] / 1e3:>7.1f} "
                  f"{row['bytes_received_outside_steps_per_step'] / 1e3:>8.2f} "
                  f"{row['collectives_per_step']:>6.2f} {row['messages_per_step']:>6.1f} "
                  f"{row['active_elements_owned_per_step']:>9.0f} "
                  f"{row['active_nodes_owned_per_step']:>7.0f} "
                  f"{row['halo_nodes_per_step']:>7.0f} {row['contact_pairs_per_step']:>6.0f} "
                  f"{mem if mem is not None else float('nan'):>6.0f}")
        received = [row["bytes_received_per_step"] for row in r["per_rank"]]
        r["bytes_received_per_step_all_ranks"] = sum(received)
        print(f"  {r['np']:>3}  all {sum(received) / 1e3:>9.1f}  (the ranks together; the most "
              f"on one: {max(received) / 1e3:.1f})")

    result = {"scene": os.path.relpath(args.scene, ROOT), "size_factor": args.size_factor,
              "max_level": args.max_level,
              "width": width, "height": height, "representation": args.representation,
              "threads": 1,
              "steps": args.steps, "ranks": args.ranks,
              "note": "counts per rank per step, not seconds: the ranks are oversubscribed",
              "runs": results, "problems": problems}
    name = "bench_mpi" + ("" if args.representation == "fe" else f"-{args.representation}") + \
        (f"-levels{args.max_level}" if args.max_level else "")
    path = os.path.join(args.out, name + ".json")
    with open(path + ".tmp", "w") as f:
        json.dump(result, f, indent=1)
    os.replace(path + ".tmp", path)
    print("written:", path)
    if problems:
        print("bench_mpi: " + "\n  ".join(problems), file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
