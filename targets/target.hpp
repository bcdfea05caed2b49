// Data of a sand target: what the generator is asked for (TargetSpec) and what it makes
// (sites, convex grain polygons, triangle meshes). SI units throughout (m, kg).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mesopen {

enum class Placement { regular, clustered }; // thesis section 4.2.5
enum class Tessellation { voronoi, power };  // thesis Voronoi + Eq. 4.4, or Laguerre
enum class MeshKind { none, fan, quality };  // thesis section 4.2.3

// The names of the choices, as scenes and output files spell them.
template <class Enum> struct Named {
  const char *name;
  Enum value;
};
inline constexpr Named<Placement> placement_names[] = {{"regular", Placement::regular},
                                                       {"clustered", Placement::clustered}};
inline constexpr Named<Tessellation> tessellation_names[] = {{"power", Tessellation::power},
                                                             {"voronoi", Tessellation::voronoi}};
inline constexpr Named<MeshKind> mesh_names[] = {
    {"quality", MeshKind::quality}, {"fan", MeshKind::fan}, {"none", MeshKind::none}};

template <class Enum, std::size_t N> const char *nameOf(Enum value, const Named<Enum> (&names)[N]) {
  for (const auto &n : names)
    if (n.value == value)
      return n.name;
  return "?";
}
// The value named `name`, if one is.
template <class Enum, std::size_t N>
std::optional<Enum> valueOf(std::string_view name, const Named<Enum> (&names)[N]) {
  for (const auto &n : names)
    if (name == n.name)
      return n.value;
  return std::nullopt;
}

// What the generator is asked for. Defaults are the scene's defaults (run/scene.cpp lists them).
struct TargetSpec {
  double width = 7.076e-3;  // box W [m]
  double height = 3.538e-3; // box H [m]
  double diameter_min = 42e-6;
  double diameter_max = 78e-6; // equal to diameter_min for a uniform grain size
  double porosity = 0.30;      // requested (A_T - A_G) / A_T
  double void_ratio = 0.25;    // void-site diameter / mean grain diameter
  Placement placement = Placement::regular;
  std::uint64_t seed = 1;
  double step_scale = 1.0;        // placement step / mean diameter (docs/targets.md, study 1)
  double step_decay = 0.7;        // step factor when the overlap energy rises (1: thesis)
  int max_iterations = 0;         // placement iterations at most (0: by placement)
  double void_scale = 0.6;        // void-site count over the area rule (see initialSites)
  bool calibrate_porosity = true; // tune the void cells' size to the requested porosity
  Tessellation tessellation = Tessellation::power;
  MeshKind mesh = MeshKind::quality;
  double mesh_size = 10e-6; // target triangle edge and shortest polygon edge [m]
  double min_angle = 20.7;  // smallest triangle angle of the quality mesh [deg]
  double density = 2648.5;  // grain density for target.data [kg/m^3] (quartz, Table 3.3)

  double meanDiameter() const { return 0.5 * (diameter_min + diameter_max); }
  double area() const { return width * height; }
};

// Grain and void sites, grains first (indices [0, grains)), voids after.
struct Sites {
  std::vector<double> x, y, r;
  std::size_t grains = 0;
  std::size_t size() const { return x.size(); }
};

// Convex grain polygons, counter-clockwise, stored flat: grain g has the vertices
// [offset[g], offset[g+1]) of x, y.
struct Polygons {
  std::vector<std::uint64_t> offset{0};
  std::vector<double> x, y;
  std::size_t size() const { return offset.size() - 1; }
  std::size_t corners(std::size_t g) const { return offset[g + 1] - offset[g]; }
  void add(const std::vector<double> &px, const std::vector<double> &py);
};

// Triangle meshes of many bodies, each with its own nodes: body b has nodes
// [node_offset[b], node_offset[b+1]) and triangles [tri_offset[b], tri_offset[b+1]); the
// connectivity `tri` (3 per triangle, counter-clockwise) holds global node indices.
struct Meshes {
  std::vector<std::uint64_t> node_offset{0}, tri_offset{0};
  std::vector<double> x, y;
  std::vector<std::uint32_t> tri;
  std::size_t bodies() const { return node_offset.size() - 1; }
  std::size_t nodes() const { return x.size(); }
  std::size_t triangles() const { return tri.size() / 3; }
};

// A finished target with the figures of its validation (thesis section 4.2.4).
struct Target {
  TargetSpec spec;
  Sites sites;                           // after placement, before tessellation
  Polygons grains;                       // convex grains inside the box
  std::vector<std::uint32_t> grain_site; // site each grain grew from
  Meshes mesh;                           // per-grain meshes (empty when mesh = none)
};

} // namespace mesopen
