// The finite-element model: nodes and 3-node triangles in struct-of-arrays form, grouped in
// bodies (the projectile, every meshed grain). 2D plane strain, 1 m thick: areas are volumes per
// metre, masses kg/m, forces N/m, energies J/m (plane strain).
// Equations: docs/models.md §1.
#pragma once

#include "material.hpp"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace mesopen::fem {

struct Nodes {
  std::vector<double> x, y;   // current position [m]
  std::vector<double> x0, y0; // initial position [m]
  std::vector<double> vx, vy; // velocity [m/s]
  std::vector<double> fx, fy; // total force of this step: internal + external [N/m]
  std::vector<double> mass;   // lumped mass [kg/m]
  std::vector<double> area0;  // a third of the initial area of each element at the node [m^2]
  std::vector<std::uint32_t> body;
  // 1: every element of the node has eroded; it goes on as a free mass, out of contact (see
  // erodeElements).
  std::vector<std::uint8_t> detached;
  // External forces of this step (contact, coupling) [N/m] and their frictional part, nonzero only
  // at the nodes listed in `loaded` (each once): few nodes carry them, and the node loops of the
  // time step then stream four arrays fewer. The four side by side: they are added to together, at
  // scattered nodes (one cache line a node).
  struct External {
    double fx, fy, friction_x, friction_y;
  };
  std::vector<External> external;
  std::vector<std::uint32_t> loaded;
  std::vector<std::uint8_t> is_loaded;
  std::size_t size() const { return x.size(); }

  void addExternal(std::uint32_t a, double fx, double fy, double friction_x, double friction_y) {
    addExternal(a, fx, fy, friction_x, friction_y, loaded);
  }
  // The same, a newly loaded node listed in `newly` (a thread's own list, appended to `loaded`
  // after: contact adds its forces in parallel, each thread on its own nodes).
  void addExternal(std::uint32_t a, double fx, double fy, double friction_x, double friction_y,
                   std::vector<std::uint32_t> &newly) {
    if (!is_loaded[a])
      is_loaded[a] = 1, newly.push_back(a);
    External &e = external[a];
    e.fx += fx, e.fy += fy, e.friction_x += friction_x, e.friction_y += friction_y;
  }
  // No external force on any node (the solver calls this before the providers add theirs).
  void clearExternal() {
    for (std::uint32_t a : loaded)
      external[a] = {}, is_loaded[a] = 0;
    loaded.clear();
    is_loaded.resize(x.size(), 0);
  }
};

// Element state: deviatoric stress S (S_zz = -S_xx - S_yy), pressure p (compression positive),
// internal energy E = m e per element [J/m], equivalent plastic strain.
struct Elements {
  std::vector<std::uint32_t> node; // 3 per element, counter-clockwise
  std::vector<double> area0;       // initial area [m^2] (the mass is rho0 A0)
  std::vector<double> area;        // current area [m^2]
  std::vector<double> sxx, syy, sxy, pressure, energy, plastic_strain;
  std::vector<double> viscosity; // artificial viscous pressure q of the last step [Pa]
  std::vector<std::uint32_t> body;
  std::vector<std::uint8_t> eroded; // 1: removed from the model (see erodeElements)
  std::size_t size() const { return area0.size(); }
};

struct Body {
  std::string name;
  std::size_t node_begin = 0, node_end = 0, element_begin = 0, element_end = 0;
  int material = 0;                    // index into Model::materials
  std::size_t eroded = 0;              // its elements removed by erosion
  std::vector<std::uint32_t> boundary; // boundary edges (node pairs, counter-clockwise)
};

// A velocity imposed on a node set: fixed nodes are the case v = 0.
struct VelocityConstraint {
  std::string name;
  std::vector<std::uint32_t> nodes;
  bool constrain_x = true, constrain_y = true;
  double vx = 0.0, vy = 0.0;
};

struct Model {
  Nodes nodes;
  Elements elements;
  std::vector<Body> bodies;
  std::vector<std::unique_ptr<Material>> materials;
  std::vector<VelocityConstraint> constraints;
  // Per body: 1 while it is at rest and unloaded, not updated (side by side: the time loop and the
  // contact look at every body's every step). Every body starts at rest; none goes back to rest.
  std::vector<std::uint8_t> at_rest;
  // Multiple time stepping (SolverSettings::max_level): per body, whether it steps in the step
  // being taken (1 for a body at rest: its nodes stand still, so they are current), and the time
  // its last or current step spans (its window). The force providers load due bodies alone, a
  // pair of bodies only when both are due, and give a body's nodes the impulse of the pair's
  // window as a force over the body's window. Empty: every body steps every step.
  std::vector<std::uint8_t> due;
  std::vector<double> window;
  // Per due body: its level (a pair of bodies is computed at the steps of the coarser one's).
  std::vector<std::uint8_t> level;
  // Per due body: its own stable step (safety times the shortest of its elements' steps at its
  // last update, at most 2^max_level base steps), which sets the stiffness of the contacts it
  // begins: a pair's penalty takes half the finer body's, at least the pair's window (tied to the
  // window alone the penalty of a pair across levels kicks the finer body too hard; Contact::hit).
  std::vector<double> own_step;

  // A body that was at rest takes part in the time loop again (contact calls this).
  void wake(std::size_t body) { at_rest[body] = 0; }
};

// A model from triangle meshes of many bodies (node and triangle offsets per body, as
// mesopen::Meshes stores them) and one material per body. Lumped masses, element areas and each
// body's boundary edges are computed here; every body starts at
// rest. Throws std::invalid_argument for a triangle that is not counter-clockwise.
struct MeshView {
  const std::vector<std::uint64_t> &node_offset, &tri_offset;
  const std::vector<double> &x, &y;
  const std::vector<std::uint32_t> &tri;
};
Model buildModel(const MeshView &mesh, std::vector<std::unique_ptr<Material>> materials,
                 const std::vector<int> &body_material, const std::vector<std::string> &body_names);

// Erosion: the elements removed from the model, as when a material fails (EPIC's eroding
// elements, Johnson & Stryk 1987). Their nodes keep their mass and momentum; a node left without
// elements goes on as a free mass (Nodes::detached) that nothing else touches. The bodies'
// boundaries are found anew (the edges of one remaining element), and the nodal reference areas
// lose the elements' thirds. Returns the internal energy the elements held [J/m], which leaves with
// them.
double erodeElements(Model &model, const std::vector<std::uint32_t> &elements);

// Initial velocity of a body: translation (vx, vy) plus rotation `spin` [rad/s] about its centre
// of mass. Marks the body as moving.
void setBodyVelocity(Model &model, std::size_t body, double vx, double vy, double spin = 0.0);

// Centre of mass, linear momentum and angular momentum about the centre of mass of a body (its
// nodes still held by an element: detached nodes have left it).
struct BodyMotion {
  double mass, com_x, com_y, px, py, angular_momentum;
};
BodyMotion bodyMotion(const Model &model, std::size_t body);

} // namespace mesopen::fem
