// Structured triangle meshes for solver tests: rectangles of nx x ny cells, each cell cut by one
// diagonal (all the same way, the arrangement in which constant-strain triangles lock), with the
// option to move interior nodes at random so that no two elements are alike.
#pragma once

#include "model.hpp"

#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace mesopen::test {

struct TestMesh {
  std::vector<std::uint64_t> node_offset{0}, tri_offset{0};
  std::vector<double> x, y;
  std::vector<std::uint32_t> tri;

  // A new body: [x0, x0 + w] x [y0, y0 + h], nodes moved by up to `jitter` cell sizes inside.
  void addRectangle(double x0, double y0, double w, double h, int nx, int ny, double jitter = 0.0,
                    std::uint64_t seed = 1) {
    const std::uint32_t first = static_cast<std::uint32_t>(x.size());
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-jitter, jitter);
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        const bool inside = i > 0 && i < nx && j > 0 && j < ny;
        x.push_back(x0 + w * (i + (inside ? u(rng) : 0.0)) / nx);
        y.push_back(y0 + h * (j + (inside ? u(rng) : 0.0)) / ny);
      }
    auto id = [&](int i, int j) { return first + static_cast<std::uint32_t>(j * (nx + 1) + i); };
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        tri.insert(tri.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1),
                               id(i, j + 1)});
    node_offset.push_back(x.size());
    tri_offset.push_back(tri.size() / 3);
  }

  fem::Model model(std::vector<std::unique_ptr<fem::Material>> materials,
                   std::vector<int> body_material = {}) const {
    if (body_material.empty())
      body_material.assign(node_offset.size() - 1, 0);
    return fem::buildModel({node_offset, tri_offset, x, y, tri}, std::move(materials),
                           body_material, {});
  }
};

inline std::vector<std::unique_ptr<fem::Material>> oneMaterial(const std::string &name,
                                                               const fem::Parameters &p = {}) {
  std::vector<std::unique_ptr<fem::Material>> m;
  m.push_back(fem::makeMaterial(name, p));
  return m;
}

// Nodes of a model for which `where(x, y)` holds (initial positions).
inline std::vector<std::uint32_t> nodesWhere(const fem::Model &model,
                                             const std::function<bool(double, double)> &where) {
  std::vector<std::uint32_t> out;
  for (std::size_t a = 0; a < model.nodes.size(); ++a)
    if (where(model.nodes.x0[a], model.nodes.y0[a]))
      out.push_back(static_cast<std::uint32_t>(a));
  return out;
}

} // namespace mesopen::test
