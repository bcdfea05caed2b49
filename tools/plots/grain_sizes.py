"""Grain-size histogram of a target: grain_sizes.py target.json out.png (thesis Figs 4.14, 4.16)."""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

with open(sys.argv[1]) as f:
    t = json.load(f)
edges = [1e6 * e for e in t["histogram"]["edges"]]
counts = t["histogram"]["counts"]
fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
ax.bar(edges[:-1], counts, width=[b - a for a, b in zip(edges[:-1], edges[1:])], align="edge",
       color="#b08850", edgecolor="#5a4020", linewidth=0.4)
ax.set_xlabel("equivalent diameter D = sqrt(4A/pi) [um]")
ax.set_ylabel("grains")
ax.set_title("%d grains, porosity %.2f %%, mean %.2f um, std %.2f um" % (
    t["grains"], 100 * t["porosity"], 1e6 * t["mean_diameter"], 1e6 * t["std_diameter"]),
    fontsize=9)
fig.tight_layout()
fig.savefig(sys.argv[2])
