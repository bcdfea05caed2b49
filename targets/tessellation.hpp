// From sites to convex grain polygons (thesis section 4.2.2).
//
// voronoi: the thesis's modified Voronoi tessellation. Every Voronoi point (VP) of a grain cell is
//   moved to the least-squares match of its sites' radii, min sum_k (|VP - GS_k| - r_k)^2
//   (Eq. 4.4, solved by Gauss-Newton from the circumcentre); sites whose relaxed cells overlap are
//   merged (two grains into one of the same total area) or, for a void, removed; a void site that
//   makes a grain concave is removed; where three grains meet at a concave point the point goes
//   back to its Voronoi position. Void cells are dropped.
// power: the Laguerre (power) tessellation with weights r^2, whose cells are convex by
//   construction and need no relaxation; a grain whose cell is empty is lost (and counted).
// Both: the box walls act as mirrors (cells end exactly on the walls), and vertices closer than
// the mesh size are merged where the grains stay convex (up to a slight dent).
// Equations: docs/models.md §10.3.
#pragma once

#include "target.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mesopen {

// A short polygon edge is collapsed even where a grain then turns inward by a little: by at most
// asin(max_dent_turn) (17 degrees) at a vertex. Leaving it would force sub-micron triangles on
// the mesh, and so a tiny time step on the solver (baseline: shortest altitude 0.02 um kept,
// 2.2 um collapsed).
constexpr double max_dent_turn = 0.3;

struct TessellationReport {
  std::size_t merged_grains = 0;    // grain pairs merged because their cells overlapped
  std::size_t removed_voids = 0;    // void sites removed (overlap or concavity)
  std::size_t restored_points = 0;  // VPs put back at their Voronoi position
  std::size_t lost_grains = 0;      // power: grains with an empty cell
  std::size_t merged_vertices = 0;  // short edges collapsed
  std::size_t kept_short_edges = 0; // short edges left because collapsing would dent a grain
  int passes = 0;
  double delaunay_seconds = 0.0;
};

// Grain polygons inside [0, W] x [0, H]. `sites` is updated (merged and removed sites are
// taken out); `grain_site[g]` is the index in the updated sites of the grain polygon g. The void
// sites' radii are taken `void_factor` times their own (the generator's porosity control).
Polygons tessellate(Sites &sites, const TargetSpec &spec, double void_factor,
                    std::vector<std::uint32_t> &grain_site, TessellationReport &report);

} // namespace mesopen
