"""Placement step study (thesis Fig. 4.6): which step scale makes the Gaussian overlap
minimisation (Eq. 4.1) converge fastest, with the thesis's fixed step (step_decay = 1) and with
mesopen's default decaying step (step_decay = 0.7: the step shrinks by 0.7 each time the overlap
energy rises).

A 2.5 x 2.5 mm box of 60 um grains at 30 % porosity (the thesis-60um-uniform scene, smaller),
clustered placement, no mesh, at most 300 placement iterations, seeds 1, 2 and 3. Writes
placement-steps.png (overlap energy against iteration, seed 1) and placement-steps.json (per
run: energy ratios, iterations to reach 1e-3, 1e-4 and 1e-5 of the initial energy, grain sizes,
porosity; and the means over the seeds).

    python3 tools/studies/placement_steps.py [--mesopen build/bin/mesopen] [--out docs/figures]
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

STEP_SCALES = [0.01, 0.03, 0.1, 0.3, 1.0, 3.0]
STEP_DECAYS = [1.0, 0.7]
SCENE = """[target]
width = 2.5e-3
height = 2.5e-3
diameter = 60e-6
porosity = 0.30
placement = "clustered"
seed = {seed}
mesh = "none"
max_iterations = 300
step_scale = {scale!r}
step_decay = {decay!r}

[projectile]
enabled = false
"""


def run(mesopen, tmp, scale, decay, seed):
    name = "scale%g-decay%g-seed%d" % (scale, decay, seed)
    scene = os.path.join(tmp, name + ".toml")
    out = os.path.join(tmp, name)
    with open(scene, "w") as f:
        f.write(SCENE.format(scale=scale, decay=decay, seed=seed))
    subprocess.run([mesopen, "target", scene, "-o", out, "--no-plot", "--threads", "1"],
                   check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "target.json")) as f:
        return json.load(f)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mesopen", default=os.path.join(ROOT, "build", "bin", "mesopen"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "figures"))
    ap.add_argument("--seeds", nargs="*", type=int, default=[1, 2, 3])
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    cases = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed, decay, scale in [(s, d, c) for s in args.seeds for d in STEP_DECAYS
                                   for c in STEP_SCALES]:
            t = run(args.mesopen, tmp, scale, decay, seed)
            e = t["placement"]["energy"]
            cases.append({
                "seed": seed,
                "step_scale": scale,
                "step_decay": decay,
                "energy": e,
                "initial_energy": e[0],
                "final_energy": e[-1],
                "final_over_initial": e[-1] / e[0],
                "lowest_over_initial": min(e) / e[0],
                "iterations": t["placement"]["iterations"],
                "converged": t["placement"]["converged"],
                "grains": t["grains"],
                "porosity": t["porosity"],
                "void_factor": t["porosity_control"]["void_factor"],
                "mean_diameter": t["mean_diameter"],
                "std_diameter": t["std_diameter"],
                "local_porosity_std": t["clustering"]["local_porosity_std"],
                "seconds_sites": t["seconds_by_phase"]["sites"],
            })
            for x in (1e-3, 1e-4, 1e-5):
                cases[-1]["iterations_to_%g" % x] = next(
                    (k for k, v in enumerate(e) if v <= x * e[0]), None)
            print("seed %d decay %.1f scale %-5g final/initial %.3e  iterations %3d  "
                  "std %.2f um  porosity %.2f %%" % (
                      seed, decay, scale, e[-1] / e[0], cases[-1]["iterations"],
                      1e6 * t["std_diameter"], 100 * t["porosity"]), flush=True)

    # Means over the seeds (None when a seed never reached the level: counted as not reached).
    means = []
    for decay in STEP_DECAYS:
        for scale in STEP_SCALES:
            runs = [c for c in cases if c["step_scale"] == scale and c["step_decay"] == decay]
            m = {"step_scale": scale, "step_decay": decay, "seeds": len(runs)}
            for key in ("final_over_initial", "iterations", "porosity", "mean_diameter",
                        "std_diameter", "void_factor", "seconds_sites"):
                m[key] = sum(c[key] for c in runs) / len(runs)
            for x in (1e-3, 1e-4, 1e-5):
                its = [c["iterations_to_%g" % x] for c in runs]
                m["iterations_to_%g" % x] = (sum(its) / len(its)) if None not in its else None
                m["seeds_reaching_%g" % x] = sum(i is not None for i in its)
            means.append(m)

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), dpi=120, sharey=True)
    colours = plt.cm.viridis([i / (len(STEP_SCALES) - 1) for i in range(len(STEP_SCALES))])
    for ax, decay in zip(axes, STEP_DECAYS):
        for colour, scale in zip(colours, STEP_SCALES):
            c = next(c for c in cases if c["step_scale"] == scale and c["step_decay"] == decay
                     and c["seed"] == args.seeds[0])
            ax.semilogy(c["energy"], color=colour, lw=1.2, label="step scale %g" % scale)
        ax.set_xlabel("iteration")
        ax.set_title("fixed step (thesis)" if decay == 1.0 else
                     "step x %g when the energy rises (default)" % decay, fontsize=10)
        ax.grid(True, which="both", lw=0.3, alpha=0.5)
    axes[0].set_ylabel("overlap energy (Eq. 4.1 summed)")
    axes[1].legend(fontsize=8)
    fig.suptitle("Site placement, 2.5 x 2.5 mm, 60 um grains, 30 %% porosity, clustered, seed %d"
                 % args.seeds[0], fontsize=10)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "placement-steps.png"))

    summary = {
        "scene": SCENE.format(scale="STEP_SCALE", decay="STEP_DECAY", seed="SEED"),
        "means_over_seeds": means,
        "cases": [{k: v for k, v in c.items() if k != "energy"} for c in cases],
        "energy": [{"seed": c["seed"], "step_scale": c["step_scale"],
                    "step_decay": c["step_decay"], "energy": c["energy"]} for c in cases],
    }
    with open(os.path.join(args.out, "placement-steps.json"), "w") as f:
        json.dump(summary, f, indent=1)


if __name__ == "__main__":
    main()
