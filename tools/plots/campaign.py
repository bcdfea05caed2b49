"""Plots of a campaign (`mesopen campaign`): campaign.py SUMMARY.json OUT_DIR.
  campaign-rotational-momentum.png: one panel per run, the rotational momentum of each completed
    replicate against scaled depth (the thesis's rotational-momentum figures, e.g. Figs 5.4, 5.7);
  campaign-trends.png: one panel per trend, the magnitude of its measure per replicate against the
    parameter, with each run's mean and 95 % interval (from the summary), and the verdict;
  campaign-trend-curves.png: one panel per trend, the rotational momentum of its runs overlaid, a
    colour per run (as the thesis's Figs 5.4 and 5.7 overlay simulations 1-3 and 4-6)."""
import json
import math
import os
import sys
import textwrap

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

summary_path, out = sys.argv[1], sys.argv[2]
with open(summary_path) as f:
    summary = json.load(f)
root = os.path.dirname(summary_path)
trends = summary.get("trends", [])

runs = {}  # name -> [(replicate, curves)] of its completed replicates
labels = {}
magnitudes = {}  # (run, measure) -> |value| of each completed replicate
for r in summary["runs"]:
    labels[r["run"]] = r.get("label", "")
    runs.setdefault(r["run"], [])
    if r["status"] != "completed":
        continue
    with open(os.path.join(root, r["dir"], "instability.json")) as f:
        runs[r["run"]].append((r["replicate"], json.load(f)["curves"]))
    for m, v in r["measures"].items():
        if isinstance(v, (int, float)):
            magnitudes.setdefault((r["run"], m), []).append(abs(v))


def panels(n, cols, width, height, **shared):
    """A figure of n panels in rows of `cols`; the unused places are hidden."""
    cols = min(cols, n)
    rows = math.ceil(n / cols)
    fig, grid = plt.subplots(rows, cols, figsize=(width * cols, height * rows), dpi=110,
                             squeeze=False, **shared)
    axes = [ax for row in grid for ax in row]
    for ax in axes[n:]:
        ax.axis("off")
    for ax in axes[:n]:
        ax.tick_params(labelsize=6)
    return fig, axes[:n]


def save(fig, name):
    fig.tight_layout()
    fig.savefig(os.path.join(out, name))
    plt.close(fig)


def plot_h(ax, curves, **style):
    ax.plot(curves["scaled_depth"], [1e6 * h for h in curves["rotational_momentum"]],
            linewidth=0.7, **style)


H_LABEL = "H [1e-6 kg m^2/s per m]"

names = list(runs)
fig, axes = panels(len(names), 4, 3.4, 2.7, sharey=True)
for k, (ax, name) in enumerate(zip(axes, names)):
    for replicate, c in runs[name]:
        plot_h(ax, c, label="r%d" % replicate)
    ax.axhline(0.0, color="0.6", linewidth=0.5)
    ax.set_title(textwrap.fill(name + (": " + labels[name] if labels[name] else ""), 50),
                 fontsize=6)
    ax.set_xlabel("depth / length", fontsize=7)
    if k % 4 == 0:
        ax.set_ylabel(H_LABEL, fontsize=7)
save(fig, "campaign-rotational-momentum.png")

if trends:
    fig, axes = panels(len(trends), 3, 3.6, 2.8)
    for ax, t in zip(axes, trends):
        for x, name, mean, err in zip(t["x"], t["runs"], t["abs_means"], t["abs_ci95"]):
            v = magnitudes.get((name, t["measure"]), [])
            ax.plot([x] * len(v), v, ".", color="0.5", markersize=4)
            if mean is not None:
                ax.errorbar([x], [mean], yerr=[err or 0.0], fmt="o", color="C0", capsize=3,
                            markersize=4)
        ax.set_xticks(t["x"])
        ax.set_xticklabels(t["runs"], fontsize=6, rotation=30)
        ax.set_ylabel("|%s|" % t["measure"], fontsize=6)
        ax.set_title("%s\nexpected %s: %s" % (t["name"], t["expect"], t["verdict"]), fontsize=7)
    save(fig, "campaign-trends.png")

    fig, axes = panels(len(trends), 3, 3.6, 2.8)
    for ax, t in zip(axes, trends):
        for colour, name in enumerate(t["runs"]):
            for i, (replicate, c) in enumerate(runs.get(name, [])):
                plot_h(ax, c, color="C%d" % (colour % 10), label=name if i == 0 else None)
        ax.axhline(0.0, color="0.6", linewidth=0.5)
        ax.set_title(t["name"], fontsize=7)
        ax.set_xlabel("depth / length", fontsize=6)
        ax.set_ylabel(H_LABEL, fontsize=6)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=6)
    save(fig, "campaign-trend-curves.png")
