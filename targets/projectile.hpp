// The projectile's geometry (thesis sections 3.2, 4.3): a tangent ogive of
// caliber-radius-head psi = rho / d on a cylindrical shank, its sharp tip cut by two flat
// facets at half-angle theta to the axis. Body frame: the sharp tip at the origin, the axis
// along +y (the body extends upward; in a target the nose points down).
// Equations: docs/models.md §10.7.
#pragma once

#include "mesh.hpp"
#include "target.hpp"

#include <vector>

namespace mesopen {

// An ogive penetrator (thesis) or a flat plate as wide as the box: a piston for planar compaction
// (shock) tests.
enum class ProjectileKind { ogive, plate };
inline constexpr Named<ProjectileKind> projectile_kind_names[] = {{"ogive", ProjectileKind::ogive},
                                                                  {"plate", ProjectileKind::plate}};

struct ProjectileSpec {
  bool enabled = true;
  ProjectileKind shape = ProjectileKind::ogive; // a plate is `length` thick and the box's width
  double length = 1.7e-3;                       // sharp-ogive length L, tip to base [m]
  double length_over_diameter = 3.85;
  double crh = 3.5;                // psi = ogive radius / diameter
  double tip_half_angle = 60.0;    // facet half-angle to the axis [deg]
  double tip_facet_length = 40e-6; // length of each facet [m] (0: no facets, sharp tip)
  double mesh_size = 0.0;          // triangle edge [m]; 0 takes the target's mesh_size
  double min_angle = 20.7;         // smallest triangle angle [deg]
};

// Derived dimensions. The half-width at distance s from the sharp tip is
// y(s) = sqrt(rho^2 - (s - L_n)^2) + d/2 - rho for s <= L_n, d/2 on the shank.
struct ProjectileShape {
  double diameter;     // d = L / (l/d)
  double ogive_radius; // rho = psi d
  double nose_length;  // L_n = d sqrt(psi - 1/4)
  double length;       // L (sharp)
  double tip_cut;      // s_t: where the facets meet the axis (the blunted tip), from the sharp tip
  double facet_end;    // s_f: where the facets meet the ogive
  double halfWidth(double s) const; // y(s) of the sharp ogive and shank
};

ProjectileShape projectileShape(const ProjectileSpec &spec);

// Closed polygon of the blunted projectile, counter-clockwise, edges no longer than `edge`.
void projectileOutline(const ProjectileShape &shape, double edge, std::vector<double> &x,
                       std::vector<double> &y);

// Exact area and centroid height (along the axis from the sharp tip) of the blunted profile.
double exactArea(const ProjectileShape &shape);
double exactCentroidY(const ProjectileShape &shape);

// The projectile's quality mesh in its body frame (sharp tip at the origin, axis along +y), at
// triangle edge `edge` and the spec's smallest angle, its triangles from the tip to the base; its
// outline in `outline_x`, `outline_y`.
TriangleMesh projectileMesh(const ProjectileShape &shape, const ProjectileSpec &spec, double edge,
                            std::vector<double> &outline_x, std::vector<double> &outline_y);

// The projectile placed in a target: its outline and mesh in target coordinates.
struct PlacedProjectile {
  ProjectileShape shape;
  std::vector<double> outline_x, outline_y;
  TriangleMesh mesh;
  double offset_x = 0.0, offset_y = 0.0; // body frame -> target frame translation
};

// How the projectile meets the target: its axis turned counter-clockwise by `angle` from straight
// down (about its tip; the angle of attack plus the obliquity), and its tip `offset` to the side of
// the box's middle [m].
struct ProjectileAttitude {
  double angle = 0.0, offset = 0.0;
};

// Tip down at x = W/2 (+ offset, the axis turned by the attitude's angle), lowered from above the
// box until it first touches a grain. A plate spans the box, 0 <= x <= W, its face down (its
// shape: diameter W, length its thickness, no nose); it takes no attitude.
PlacedProjectile placeProjectile(const ProjectileSpec &spec, double default_mesh_size,
                                 const TargetSpec &target, const Polygons &grains,
                                 const ProjectileAttitude &attitude = {});

} // namespace mesopen
