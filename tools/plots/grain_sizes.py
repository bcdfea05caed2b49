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
# The sites' diameters are drawn in the requested range; each grain is its site's cell of the
# tessellation, whose area depends on its neighbours and voids: the cells' diameters spread past it.
req = t.get("requested", {})
ratio = t.get("cell_over_site_diameter")
if "diameter_min" in req and "diameter_max" in req:
    for d in (req["diameter_min"], req["diameter_max"]):
        ax.axvline(1e6 * d, color="0.3", linestyle="--", linewidth=0.8)
    note = "dashed: the sites' diameters, %.0f-%.0f um" % (1e6 * req["diameter_min"],
                                                         1e6 * req["diameter_max"])
    if ratio and ratio["median"] > 0:
        note += ("\ngrains are the sites' tessellation cells: D / site diameter\n"
                 "%.2f-%.2f (1-99 %%), %.2f-%.2f (all)" % (ratio["p01"], ratio["p99"],
                                                           ratio["min"], ratio["max"]))
    ax.text(0.02, 0.97, note, transform=ax.transAxes, fontsize=7, va="top",
            bbox={"facecolor": "white", "alpha": 0.85, "edgecolor": "none"})
ax.set_xlabel("equivalent diameter D = sqrt(4A/pi) [um]")
ax.set_ylabel("grains")
ax.set_title("%d grains, porosity %.2f %%, mean %.2f um, std %.2f um" % (
    t["grains"], 100 * t["porosity"], 1e6 * t["mean_diameter"], 1e6 * t["std_diameter"]),
    fontsize=9)
fig.tight_layout()
fig.savefig(sys.argv[2], bbox_inches="tight")
