"""Plots of a campaign (`mesopen campaign`): campaign.py SUMMARY.json OUT_DIR.
  campaign-rotational-momentum.png: one panel per run, the rotational momentum of each completed
    replicate against scaled depth (the thesis's rotational-momentum figures, e.g. Figs 5.4, 5.7);
  campaign-trends.png: one panel per trend, the magnitude of its measure per replicate against the
    parameter, with each run's mean and 95 % interval (from the summary), and the verdict."""
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

summary_path, out = sys.argv[1], sys.argv[2]
with open(summary_path) as f:
    summary = json.load(f)
root = os.path.dirname(summary_path)

runs = {}  # name -> list of (replicate, curves)
labels = {}
for r in summary["runs"]:
    labels[r["run"]] = r.get("label", "")
    runs.setdefault(r["run"], [])
    if r["status"] != "completed":
        continue
    with open(os.path.join(root, r["dir"], "instability.json")) as f:
        runs[r["run"]].append((r["replicate"], json.load(f)["curves"]))

names = list(runs)
cols = min(4, len(names))
rows = math.ceil(len(names) / cols)
fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.4 * rows), dpi=110, squeeze=False,
                         sharex=True, sharey=True)
for k, name in enumerate(names):
    ax = axes[k // cols][k % cols]
    for replicate, c in runs[name]:
        ax.plot(c["scaled_depth"], [1e6 * h for h in c["rotational_momentum"]], linewidth=0.7,
                label="r%d" % replicate)
    ax.axhline(0.0, color="0.6", linewidth=0.5)
    ax.set_title(name + (": " + labels[name] if labels[name] else ""), fontsize=7)
    ax.tick_params(labelsize=6)
for k in range(len(names), rows * cols):
    axes[k // cols][k % cols].axis("off")
for ax in axes[-1]:
    ax.set_xlabel("depth / length", fontsize=7)
for row in axes:
    row[0].set_ylabel("H [1e-6 kg m^2/s per m]", fontsize=7)
fig.suptitle("%s: rotational momentum of each replicate" % (summary.get("name") or "campaign"),
             fontsize=9)
fig.tight_layout()
fig.savefig(os.path.join(out, "campaign-rotational-momentum.png"))
plt.close(fig)

trends = summary.get("trends", [])
if trends:
    values = {}  # (run, measure) -> magnitudes
    for r in summary["runs"]:
        if r["status"] == "completed":
            for m, v in r["measures"].items():
                if isinstance(v, (int, float)):
                    values.setdefault((r["run"], m), []).append(abs(v))
    cols = min(3, len(trends))
    rows = math.ceil(len(trends) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols, 2.8 * rows), dpi=110,
                             squeeze=False)
    for k, t in enumerate(trends):
        ax = axes[k // cols][k % cols]
        for x, name, mean, err in zip(t["x"], t["runs"], t["abs_means"], t["abs_ci95"]):
            v = values.get((name, t["measure"]), [])
            ax.plot([x] * len(v), v, ".", color="0.5", markersize=4)
            if mean is not None:
                ax.errorbar([x], [mean], yerr=[err or 0.0], fmt="o", color="C0", capsize=3,
                            markersize=4)
        ax.set_xticks(t["x"])
        ax.set_xticklabels(t["runs"], fontsize=6, rotation=30)
        ax.tick_params(labelsize=6)
        ax.set_ylabel("|%s|" % t["measure"], fontsize=6)
        ax.set_title("%s\nexpected %s: %s" % (t["name"], t["expect"], t["verdict"]), fontsize=7)
    for k in range(len(trends), rows * cols):
        axes[k // cols][k % cols].axis("off")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "campaign-trends.png"))
    plt.close(fig)
