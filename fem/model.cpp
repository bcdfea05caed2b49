#include "model.hpp"

#include <algorithm>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace mesopen::fem {

namespace {
// A body's boundary edges: those of one of its (remaining) elements only, in that element's
// counter-clockwise order, sorted by their lower node.
void findBoundary(const Elements &el, Body &body) {
  struct Edge {
    std::uint32_t lo, hi;
    int use; // +1: used from lo to hi, -1: from hi to lo
  };
  std::vector<Edge> edges;
  edges.reserve(3 * (body.element_end - body.element_begin));
  for (std::size_t e = body.element_begin; e < body.element_end; ++e)
    if (!el.eroded[e])
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = el.node[3 * e + k], c = el.node[3 * e + (k + 1) % 3];
        edges.push_back({std::min(a, c), std::max(a, c), a < c ? 1 : -1});
      }
  std::sort(edges.begin(), edges.end(), [](const Edge &p, const Edge &q) {
    return std::tie(p.lo, p.hi) < std::tie(q.lo, q.hi);
  });
  body.boundary.clear();
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    int use = 0;
    for (; j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi; ++j)
      use += edges[j].use;
    if (j - i == 1 && use > 0)
      body.boundary.insert(body.boundary.end(), {edges[i].lo, edges[i].hi});
    else if (j - i == 1)
      body.boundary.insert(body.boundary.end(), {edges[i].hi, edges[i].lo});
    i = j;
  }
}
} // namespace

Model buildModel(const MeshView &mesh, std::vector<std::unique_ptr<Material>> materials,
                 const std::vector<int> &body_material,
                 const std::vector<std::string> &body_names) {
  const std::size_t n_bodies = mesh.node_offset.size() - 1;
  if (body_material.size() != n_bodies || mesh.tri_offset.size() != n_bodies + 1)
    throw std::invalid_argument("buildModel: " + std::to_string(n_bodies) + " bodies but " +
                                std::to_string(body_material.size()) + " materials");
  for (int m : body_material)
    if (m < 0 || static_cast<std::size_t>(m) >= materials.size())
      throw std::invalid_argument("buildModel: material index " + std::to_string(m) + " unknown");
  Model model;
  model.materials = std::move(materials);
  const std::size_t n_nodes = mesh.x.size(), n_elements = mesh.tri.size() / 3;
  Nodes &nd = model.nodes;
  nd.x = mesh.x, nd.y = mesh.y, nd.x0 = mesh.x, nd.y0 = mesh.y;
  nd.external.assign(n_nodes, {});
  for (auto *v : {&nd.vx, &nd.vy, &nd.fx, &nd.fy, &nd.mass, &nd.area0})
    v->assign(n_nodes, 0.0);
  nd.body.assign(n_nodes, 0);
  nd.is_loaded.assign(n_nodes, 0);

  Elements &el = model.elements;
  el.node = mesh.tri;
  for (auto *v : {&el.area0, &el.area, &el.sxx, &el.syy, &el.sxy, &el.pressure, &el.energy,
                  &el.plastic_strain, &el.viscosity})
    v->assign(n_elements, 0.0);
  el.body.assign(n_elements, 0);
  el.eroded.assign(n_elements, 0);
  nd.detached.assign(n_nodes, 0);

  model.bodies.resize(n_bodies);
  model.at_rest.assign(n_bodies, 1);
  for (std::size_t b = 0; b < n_bodies; ++b) {
    Body &body = model.bodies[b];
    body.name = b < body_names.size() ? body_names[b] : "body-" + std::to_string(b);
    body.node_begin = mesh.node_offset[b], body.node_end = mesh.node_offset[b + 1];
    body.element_begin = mesh.tri_offset[b], body.element_end = mesh.tri_offset[b + 1];
    body.material = body_material[b];
    const double rho = model.materials[body.material]->density();
    std::fill(nd.body.begin() + body.node_begin, nd.body.begin() + body.node_end, b);
    // Lumped mass: a third of each element's mass at each of its nodes.
    for (std::size_t e = body.element_begin; e < body.element_end; ++e) {
      const std::uint32_t *n = &el.node[3 * e];
      for (int k = 0; k < 3; ++k)
        if (n[k] < body.node_begin || n[k] >= body.node_end)
          throw std::invalid_argument("buildModel: element " + std::to_string(e) + " of " +
                                      body.name + " uses node " + std::to_string(n[k]) +
                                      " of another body");
      const double area = 0.5 * ((nd.x[n[1]] - nd.x[n[0]]) * (nd.y[n[2]] - nd.y[n[0]]) -
                                 (nd.x[n[2]] - nd.x[n[0]]) * (nd.y[n[1]] - nd.y[n[0]]));
      if (!(area > 0.0))
        throw std::invalid_argument("buildModel: element " + std::to_string(e) + " of " +
                                    body.name + " is not counter-clockwise (area " +
                                    std::to_string(area) + " m^2)");
      el.area0[e] = el.area[e] = area;
      el.body[e] = static_cast<std::uint32_t>(b);
      for (int k = 0; k < 3; ++k) {
        nd.mass[n[k]] += rho * area / 3.0;
        nd.area0[n[k]] += area / 3.0;
      }
    }
    findBoundary(el, body);
  }

  return model;
}

double erodeElements(Model &model, const std::vector<std::uint32_t> &elements) {
  Nodes &nd = model.nodes;
  Elements &el = model.elements;
  double energy = 0.0;
  std::vector<std::uint32_t> bodies;
  for (std::uint32_t e : elements) {
    if (el.eroded[e])
      continue;
    el.eroded[e] = 1;
    energy += el.energy[e];
    for (int k = 0; k < 3; ++k)
      nd.area0[el.node[3 * e + k]] -= el.area0[e] / 3.0;
    ++model.bodies[el.body[e]].eroded;
    if (std::find(bodies.begin(), bodies.end(), el.body[e]) == bodies.end())
      bodies.push_back(el.body[e]);
  }
  for (std::uint32_t b : bodies) {
    Body &body = model.bodies[b];
    findBoundary(el, body);
    // The nodes no remaining element holds.
    std::vector<std::uint8_t> held(body.node_end - body.node_begin, 0);
    for (std::size_t e = body.element_begin; e < body.element_end; ++e)
      if (!el.eroded[e])
        for (int k = 0; k < 3; ++k)
          held[el.node[3 * e + k] - body.node_begin] = 1;
    for (std::size_t a = body.node_begin; a < body.node_end; ++a)
      nd.detached[a] = !held[a - body.node_begin];
  }
  return energy;
}

void setBodyVelocity(Model &model, std::size_t body, double vx, double vy, double spin) {
  const BodyMotion m = bodyMotion(model, body);
  Nodes &nd = model.nodes;
  for (std::size_t a = model.bodies[body].node_begin; a < model.bodies[body].node_end; ++a) {
    nd.vx[a] = vx - spin * (nd.y[a] - m.com_y);
    nd.vy[a] = vy + spin * (nd.x[a] - m.com_x);
  }
  model.wake(body);
}

// One pass of raw moments: H about the centre of mass (thesis Eq. 3.13, H = sum r x m v) is
// H = sum m (x vy - y vx) - (X Py - Y Px), X, Y the centre of mass, P the momentum.
BodyMotion bodyMotion(const Model &model, std::size_t body) {
  const Nodes &nd = model.nodes;
  const Body &b = model.bodies[body];
  BodyMotion m{0, 0, 0, 0, 0, 0};
  double moment = 0.0;
  for (std::size_t a = b.node_begin; a < b.node_end; ++a) {
    if (nd.detached[a])
      continue;
    const double mass = nd.mass[a];
    m.mass += mass;
    m.com_x += mass * nd.x[a];
    m.com_y += mass * nd.y[a];
    m.px += mass * nd.vx[a];
    m.py += mass * nd.vy[a];
    moment += mass * (nd.x[a] * nd.vy[a] - nd.y[a] * nd.vx[a]);
  }
  m.com_x /= m.mass, m.com_y /= m.mass;
  m.angular_momentum = moment - (m.com_x * m.py - m.com_y * m.px);
  return m;
}

} // namespace mesopen::fem
