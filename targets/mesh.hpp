// Triangle meshes of convex polygons (thesis section 4.2.3): the fan mesh (centroid to every
// vertex, the thesis's coarse option) and a quality Delaunay mesh at a requested edge length
// (CGAL Mesh_2, Ruppert-Shewchuk refinement with a smallest-angle bound).
// Equations: docs/models.md §10.5.
#pragma once

#include "target.hpp"

#include <cstdint>
#include <vector>

namespace mesopen {

struct TriangleMesh {
  std::vector<double> x, y;
  std::vector<std::uint32_t> tri; // 3 node indices per triangle, counter-clockwise
};

// Pieces no longer than `edge` that a boundary edge of length `length` is split into (at least
// one; zero for a zero length). Outlines made with it are not split again by qualityMesh.
int edgePieces(double length, double edge);

// Fan mesh: one node at the centroid, one triangle per polygon edge.
TriangleMesh fanMesh(const double *x, const double *y, std::size_t n);

// Quality mesh of a simple polygon (counter-clockwise): boundary edges are first split evenly
// into pieces no longer than `edge` (refinement may split them further where needed), then interior
// points are added until every triangle has edges about `edge` long or shorter and no angle below
// `min_angle_deg`. Refinement is proven to end for bounds up to 20.7 degrees (Shewchuk; CGAL Mesh_2
// handles small input angles by clusters); the scene allows no more, since a grain corner sharper
// than a larger bound makes it refine forever.
TriangleMesh qualityMesh(const double *x, const double *y, std::size_t n, double edge,
                         double min_angle_deg);

// Meshes of all grains, in parallel over grains, appended in grain order (so the result does
// not depend on the number of threads).
Meshes meshGrains(const Polygons &grains, MeshKind kind, double edge, double min_angle_deg);

// Append one mesh as the next body of `meshes`.
void appendBody(Meshes &meshes, const TriangleMesh &body);

} // namespace mesopen
