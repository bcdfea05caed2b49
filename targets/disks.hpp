// The grains as DEM disks: one disk per grain at the polygon's centroid with the grain's mass.
// Disks of the grains' equal area, sqrt(A / pi), would overlap their neighbours (in the baseline
// target 6,483 pairs, a quarter of a radius on average, up to 0.85): a DEM target built from them
// would burst at the first step. So a disk's radius is the equal-area radius, or less where it
// would overlap: two disks share the distance between their centres in proportion to their
// equal-area radii, a disk keeps out of the meshed grains' polygons and of the other FE bodies
// (the projectile), and inside the box's walls (left x = 0, right x = width, bottom y = 0; the top
// is open). At t = 0 no disk then presses on anything: a target at rest stays at rest. Its
// density is rho A / (pi r^2), which keeps its mass per metre rho A (baseline: radii 0.86 of the
// equal-area ones on average, none below 0.70; the disks cover 52 % of the box).
// Equations: docs/models.md §9.1.
#pragma once

#include "projectile.hpp"
#include "target.hpp"

#include <cstdint>
#include <vector>

namespace mesopen {

struct Disks {
  std::vector<std::uint32_t> grain; // the grain each disk stands for
  std::vector<double> x, y, radius, density;
  std::size_t size() const { return grain.size(); }
};

// A disk's size: `inscribed`, at its grain's centroid, the equal-area radius or less where it would
// overlap (the disks cover less of the box than the grains: 52 % against 70 % in the baseline);
// `equal_area`, the grain's equal-area radius, the disks pushed apart from the centroids until
// they no longer overlap (relaxApart in disks.cpp: Jacobi sweeps), so that they cover what the
// grains cover; what the sweeps leave is taken off the radii as for `inscribed`.
enum class DiskSize { inscribed, equal_area };
inline constexpr Named<DiskSize> disk_size_names[] = {{"inscribed", DiskSize::inscribed},
                                                      {"equal_area", DiskSize::equal_area}};

// What the disks keep out of besides each other.
struct DiskBounds {
  double width = 0.0;  // the box's walls x = 0, x = width and y = 0; 0: no walls
  double height = 0.0; // the box's top, which equal_area disks are relaxed below
  DiskSize size = DiskSize::inscribed;
  int sweeps = 2000;        // equal_area: relaxation sweeps at most
  std::vector<char> meshed; // per grain, 1: meshed (an FE body, not a disk); empty: none
  Polygons bodies;          // other FE bodies' outlines, e.g. the placed projectile
};

// The disks of the grains not marked in `bounds.meshed`, in grain order.
Disks grainDisks(const Polygons &grains, double density, const DiskBounds &bounds = {});

// The disks of a target inside its box's walls, of the given size: of the grains not marked in
// `meshed` (every grain if empty), clear of the projectile when one is given.
Disks targetDisks(const Target &target, DiskSize size = DiskSize::inscribed,
                  const std::vector<char> &meshed = {},
                  const PlacedProjectile *projectile = nullptr);

} // namespace mesopen
