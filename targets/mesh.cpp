#include "mesh.hpp"

#include "polygon.hpp"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_mesh_face_base_2.h>
#include <CGAL/Delaunay_mesh_size_criteria_2.h>
#include <CGAL/Delaunay_mesh_vertex_base_2.h>
#include <CGAL/Delaunay_mesher_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>

namespace mesopen {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Delaunay_mesh_vertex_base_2<K>;
using Fb = CGAL::Delaunay_mesh_face_base_2<K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using CDT = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::Exact_predicates_tag>;
using Criteria = CGAL::Delaunay_mesh_size_criteria_2<CDT>;
using Mesher = CGAL::Delaunay_mesher_2<CDT, Criteria>;
} // namespace

int edgePieces(double length, double edge) {
  return length > 0.0 ? std::max(1, static_cast<int>(std::ceil(length / edge - 1e-9))) : 0;
}

TriangleMesh fanMesh(const double *x, const double *y, std::size_t n) {
  TriangleMesh m;
  const Point c = centroid(x, y, n);
  m.x.assign(x, x + n);
  m.y.assign(y, y + n);
  m.x.push_back(c.x);
  m.y.push_back(c.y);
  for (std::uint32_t i = 0; i < n; ++i)
    m.tri.insert(m.tri.end(),
                 {static_cast<std::uint32_t>(n), i, static_cast<std::uint32_t>((i + 1) % n)});
  return m;
}

TriangleMesh qualityMesh(const double *x, const double *y, std::size_t n, double edge,
                         double min_angle_deg) {
  // Corners closer than 1e-6 of the edge length (or of the polygon's extent, for an edge longer
  // than the polygon: all its corners were dropped, and CGAL crashed on what was left) to the one
  // before are dropped: a sliver edge would make the refinement chase it down to round-off.
  double extent = 0.0;
  for (std::size_t i = 1; i < n; ++i)
    extent = std::max(extent, std::hypot(x[i] - x[0], y[i] - y[0]));
  const double merge = 1e-6 * std::min(edge, extent);
  std::vector<std::size_t> keep;
  for (std::size_t i = 0; i < n; ++i)
    if (keep.empty() || std::hypot(x[i] - x[keep.back()], y[i] - y[keep.back()]) > merge)
      keep.push_back(i);
  while (keep.size() > 1 &&
         std::hypot(x[keep.back()] - x[keep[0]], y[keep.back()] - y[keep[0]]) <= merge)
    keep.pop_back();
  if (keep.size() < 3)
    throw std::invalid_argument("a polygon of " + std::to_string(n) +
                                " corners has fewer than three apart: nothing to mesh");
  CDT cdt;
  // Split each boundary edge evenly (neighbouring grains get nearly the same boundary points; the
  // refinement may split an edge further where a triangle would encroach on it).
  std::vector<CDT::Vertex_handle> boundary;
  const std::size_t corners = keep.size();
  for (std::size_t k = 0; k < corners; ++k) {
    const std::size_t i = keep[k], j = keep[(k + 1) % corners];
    const double len = std::hypot(x[j] - x[i], y[j] - y[i]);
    const int pieces = std::max(1, edgePieces(len, edge));
    for (int k = 0; k < pieces; ++k) {
      const double t = static_cast<double>(k) / pieces;
      boundary.push_back(
          cdt.insert(K::Point_2(x[i] + t * (x[j] - x[i]), y[i] + t * (y[j] - y[i]))));
    }
  }
  for (std::size_t i = 0; i < boundary.size(); ++i)
    cdt.insert_constraint(boundary[i], boundary[(i + 1) % boundary.size()]);
  // CGAL's shape bound B is the squared sine of the smallest angle; the size bound is the
  // longest edge.
  const double s = std::sin(min_angle_deg * M_PI / 180.0);
  // The size bound is on the longest edge; 1.45 of the requested length gives triangles whose
  // mean edge is about the request (a 10 um mesh of the baseline target: ~420,000 triangles).
  Mesher mesher(cdt, Criteria(s * s, 1.45 * edge));
  mesher.refine_mesh();

  TriangleMesh m;
  std::map<CDT::Vertex_handle, std::uint32_t> id;
  // Number the nodes in a fixed order: by coordinates, so the result does not depend on
  // CGAL's internal storage order.
  std::vector<CDT::Vertex_handle> nodes;
  for (auto v = cdt.finite_vertices_begin(); v != cdt.finite_vertices_end(); ++v)
    nodes.push_back(v);
  std::sort(nodes.begin(), nodes.end(), [](auto a, auto b) {
    return a->point().x() < b->point().x() ||
           (a->point().x() == b->point().x() && a->point().y() < b->point().y());
  });
  for (auto v : nodes) {
    id[v] = static_cast<std::uint32_t>(m.x.size());
    m.x.push_back(v->point().x());
    m.y.push_back(v->point().y());
  }
  std::vector<std::array<std::uint32_t, 3>> tris;
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f)
    if (f->is_in_domain()) {
      std::array<std::uint32_t, 3> t{id[f->vertex(0)], id[f->vertex(1)], id[f->vertex(2)]};
      std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
      tris.push_back(t);
    }
  std::sort(tris.begin(), tris.end());
  for (const auto &t : tris)
    m.tri.insert(m.tri.end(), t.begin(), t.end());
  return m;
}

void appendBody(Meshes &meshes, const TriangleMesh &body) {
  if (meshes.x.size() + body.x.size() > UINT32_MAX)
    throw std::length_error(
        "mesh: more than 2^32 nodes; use a coarser mesh_size or a smaller target");
  const auto base = static_cast<std::uint32_t>(meshes.x.size());
  meshes.x.insert(meshes.x.end(), body.x.begin(), body.x.end());
  meshes.y.insert(meshes.y.end(), body.y.begin(), body.y.end());
  for (std::uint32_t v : body.tri)
    meshes.tri.push_back(base + v);
  meshes.node_offset.push_back(meshes.x.size());
  meshes.tri_offset.push_back(meshes.tri.size() / 3);
}

Meshes meshGrains(const Polygons &grains, MeshKind kind, double edge, double min_angle_deg) {
  Meshes out;
  if (kind == MeshKind::none)
    return out;
  const std::size_t n = grains.size();
  std::vector<TriangleMesh> bodies(n);
#pragma omp parallel for schedule(dynamic, 64)
  for (std::size_t g = 0; g < n; ++g) {
    const double *x = grains.x.data() + grains.offset[g], *y = grains.y.data() + grains.offset[g];
    bodies[g] = kind == MeshKind::fan ? fanMesh(x, y, grains.corners(g))
                                      : qualityMesh(x, y, grains.corners(g), edge, min_angle_deg);
  }
  std::size_t nodes = 0, tris = 0;
  for (const auto &b : bodies)
    nodes += b.x.size(), tris += b.tri.size();
  out.x.reserve(nodes);
  out.y.reserve(nodes);
  out.tri.reserve(tris);
  for (const auto &b : bodies)
    appendBody(out, b);
  return out;
}

} // namespace mesopen
