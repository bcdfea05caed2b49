#!/usr/bin/python3
"""A model of a step's wall time on P MPI ranks, from unit costs measured on one rank.

Two designs of the FE decomposition (docs/solver.md, "A scaling model"):

  today    every rank holds the whole model; the element updates, the node loops (each rank moves
           the nodes of its bodies) and the FE-FE contact (the pairs of its own bodies) are
           shared; every rank receives the box and travel of every moving body (40 bytes, an
           all-gather) at each search for pairs (every `search_every` steps) and between them of
           the bodies its pairs hold, the halo nodes' position and velocity (32 bytes) from the
           ranks it shares pairs with (messages whose sizes every rank knows) and the reactions on
           its nodes (16 bytes) from the same ranks; at the steps where contacts woke bodies at
           rest (the share `woken`) an all-gather of them, as every rank must know them; one
           reduction for the step;
  spatial  a rank owns the bodies of its region (a near-square block of the moving region, as
           recursive coordinate bisection gives) and holds a halo, the other ranks' bodies within
           the contact margin: each step it receives the halo nodes' position and velocity
           (32 bytes) from its neighbours and sends back the reactions on them (16 bytes); each
           contact pair is computed once; one reduction for the step.

A step on one rank costs c_e per element update, c_n per node-step (kick, drift, force assembly)
and c_p per pair of bodies searched (the contact); the defaults are run 6's
(examples/baseline.toml to one length on one thread: 126.1 s, 2.18e9 element updates, the element
pass 51 % of the time, the node loops 20 %, the contact 25.7 s over 5.4e7 pair-steps). A message
costs `latency + bytes / bandwidth`; a reduction 2 log2(P) latencies; today's design's
all-gather of the boxes P - 1 latencies (a ring) at a search, that of the woken bodies P - 1 at
their steps, its messages (the boxes, the halo, the reactions) one latency per neighbour each (at
most 8), and its reduction.
The scene scales as run 6: moving elements the share
`active` of all, nodes and pairs per moving element as in run 6, the halo a band `band` wide around
each block of the moving region at run 6's node density. Memory per rank: bytes per element (run
6's peak over its elements) times the elements it holds.

    /usr/bin/python3 tools/studies/scaling_model.py [--elements 40e6] [--ranks 1,8,64,512]
        [--bandwidth 10e9] [--latency 2e-6] [--json FILE]
Prints a table per design; --json writes the figures (under a temporary name, then renamed).
Exit code 2 on bad arguments.
"""
import argparse
import json
import math
import os
import sys

RUN6 = {  # examples/baseline.toml, one projectile length, one thread (docs/solver.md)
    "elements": 446558, "nodes": 303205, "area_mm2": 7.076 * 3.538,
    "active_elements": 124306, "active_nodes": 82395, "pairs": 3089,
    "peak_bytes": 224710656, "bodies": 6199, "steps": 17501, "searches": 389,
}


def scene(a):
    """The target's moving elements, nodes, pairs and region per step, scaled from run 6."""
    density = RUN6["elements"] / RUN6["area_mm2"]          # elements per mm^2
    moving = a.active * a.elements
    return {"moving": moving,
            "nodes": moving * RUN6["active_nodes"] / RUN6["active_elements"],
            "pairs": moving * RUN6["pairs"] / RUN6["active_elements"],
            "area_mm2": moving / density,
            "node_density": RUN6["nodes"] / RUN6["area_mm2"],
            "bytes_per_element": RUN6["peak_bytes"] / RUN6["elements"]}


def figures(p, compute, comm, received, halo, memory, serial):
    step = compute + comm
    return {"ranks": p, "compute_s": compute, "comm_s": comm, "step_s": step,
            "bytes_received": received, "halo_nodes": halo, "memory_bytes": memory,
            "speedup": serial / step, "efficiency": serial / step / p}


def halo_nodes(s, p, band):
    """The nodes in a band `band` wide around a near-square block of the moving region."""
    return 4.0 * math.sqrt(s["area_mm2"] / p) * band * s["node_density"] if p > 1 else 0.0


def today(a, s, p, serial):
    """Elements, nodes and contact shared; a halo by pair; the moving bodies' boxes all-gathered."""
    halo = halo_nodes(s, p, a.band)
    bodies_per_node = RUN6["bodies"] / RUN6["nodes"]
    bodies = s["nodes"] * bodies_per_node
    # halo nodes' state and reactions; the boxes of the bodies they belong to; all boxes at a search
    received = ((48.0 + 40.0 * bodies_per_node) * halo +
                40.0 * bodies * (p - 1) / p / a.search_every)
    comm = (((p - 1) / a.search_every + (p - 1) * a.woken + 3 * min(8, p - 1)) * a.latency +
            received / a.bandwidth + 2 * math.log2(p) * a.latency)
    compute = s["moving"] / p * a.c_e + s["nodes"] / p * a.c_n + s["pairs"] / p * a.c_p
    return figures(p, compute, comm, received, halo, s["bytes_per_element"] * a.elements, serial)


def spatial(a, s, p, serial):
    """A block of the moving region per rank, its halo a band around it; one reduction."""
    halo = halo_nodes(s, p, a.band)
    received = 48.0 * halo
    comm = (min(8, p - 1) * a.latency + received / a.bandwidth + 2 * math.log2(p) * a.latency)
    compute = s["moving"] / p * a.c_e + (s["nodes"] / p + halo) * a.c_n + s["pairs"] / p * a.c_p
    held = a.elements / p + halo * RUN6["elements"] / RUN6["nodes"]
    return figures(p, compute, comm, received, halo, s["bytes_per_element"] * held, serial)


def model(a):
    """Per rank count, both designs; where the spatial one's efficiency falls below one half."""
    s = scene(a)
    serial = s["moving"] * a.c_e + s["nodes"] * a.c_n + s["pairs"] * a.c_p
    rows = [{"today": today(a, s, p, serial), "spatial": spatial(a, s, p, serial)}
            for p in a.ranks]
    stop = next((1 << k for k in range(1, 25) if spatial(a, s, 1 << k, serial)["efficiency"] < 0.5),
                None)
    return {"serial_step_s": serial, "moving_elements": s["moving"], "moving_nodes": s["nodes"],
            "pairs": s["pairs"], "rows": rows, "spatial_half_efficiency_ranks": stop}


def table(result, design):
    lines = ["| ranks | step [ms] | compute [ms] | communication [ms] | KB received | halo nodes "
             "| memory [MB] | speed-up | efficiency |", "|---|---|---|---|---|---|---|---|---|"]
    for row in result["rows"]:
        d = row[design]
        lines.append("| %d | %.3g | %.3g | %.3g | %.4g | %.4g | %.4g | %.3g | %.2f |" % (
            d["ranks"], 1e3 * d["step_s"], 1e3 * d["compute_s"], 1e3 * d["comm_s"],
            d["bytes_received"] / 1e3, d["halo_nodes"], d["memory_bytes"] / 1e6, d["speedup"],
            d["efficiency"]))
    return "\n".join(lines)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--elements", type=float, default=40e6, help="elements of the target")
    p.add_argument("--ranks", default="1,8,64,512", help="comma-separated rank counts")
    p.add_argument("--bandwidth", type=float, default=10e9, help="bytes per second per rank")
    p.add_argument("--latency", type=float, default=2e-6, help="seconds per message")
    p.add_argument("--active", type=float, default=RUN6["active_elements"] / RUN6["elements"],
                   help="share of the elements moving in a step")
    p.add_argument("--band", type=float, default=0.07, help="halo band width [mm]")
    p.add_argument("--search-every", dest="search_every", type=float,
                   default=RUN6["steps"] / RUN6["searches"], help="steps per search for pairs")
    p.add_argument("--woken", type=float, default=0.15,
                   help="share of the steps whose contacts wake bodies at rest")
    p.add_argument("--c-e", dest="c_e", type=float, default=29.6e-9, help="s per element update")
    p.add_argument("--c-n", dest="c_n", type=float, default=17.5e-9, help="s per node-step")
    p.add_argument("--c-p", dest="c_p", type=float, default=475e-9, help="s per pair-step")
    p.add_argument("--json", default="", help="write the figures to this file")
    a = p.parse_args()
    try:
        a.ranks = [int(r) for r in a.ranks.split(",")]
    except ValueError:
        print("scaling_model.py: --ranks %s: comma-separated whole numbers expected" % a.ranks,
              file=sys.stderr)
        sys.exit(2)
    for name in ("elements", "bandwidth", "latency", "active", "woken", "band", "search_every",
                 "c_e", "c_n", "c_p"):
        value = getattr(a, name)
        share = name in ("active", "woken")
        if not (value > 0 and math.isfinite(value)) or (share and value > 1):
            print("scaling_model.py: --%s %g: allowed finite and > 0%s" % (
                name.replace("_", "-"), value, " and <= 1" if share else ""),
                file=sys.stderr)
            sys.exit(2)
    if any(r < 1 for r in a.ranks):
        print("scaling_model.py: --ranks: each at least 1", file=sys.stderr)
        sys.exit(2)
    if a.json and not os.path.isdir(os.path.dirname(os.path.abspath(a.json))):
        print("scaling_model.py: --json %s: no such directory" % a.json, file=sys.stderr)
        sys.exit(2)
    result = model(a)
    print("%.3g elements, %.3g moving a step, %.3g moving nodes, %.3g pairs; one rank: %.3g s a "
          "step" % (a.elements, result["moving_elements"], result["moving_nodes"], result["pairs"],
                    result["serial_step_s"]))
    for design in ("today", "spatial"):
        print("\n## %s\n\n%s" % (design, table(result, design)))
    stop = result["spatial_half_efficiency_ranks"]
    print("\nThe spatial design's efficiency falls below one half at %d ranks." % stop if stop else
          "\nThe spatial design's efficiency stays above one half up to %d ranks." % (1 << 24))
    if a.json:
        tmp = a.json + ".tmp"
        with open(tmp, "w") as f:
            json.dump({"arguments": {k: v for k, v in vars(a).items() if k != "json"},
                       **result}, f, indent=1)
        os.replace(tmp, a.json)


if __name__ == "__main__":
    main()
