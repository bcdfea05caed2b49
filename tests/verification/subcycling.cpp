// Subcycling (SolverSettings::subcycle_levels): a body whose elements' stable step is shorter than
// the time loop's takes substeps of its own, its contact forces held over the step. Checked
// against the same impact without substeps.
#include "contact.hpp"
#include "meshes.hpp"
#include "solver.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace mesopen;
using test::TestMesh;

namespace {

struct Impact {
  double px_coarse, px_fine; // the bodies' momenta at the end [kg m/s per m]
  double worst_momentum;     // the largest |total momentum| over the run
  double balance_error, contact_energy, kinetic0;
  std::size_t steps, most_subcycled;
};

// A coarsely meshed quartz block (8 x 4 elements) at v against a finely meshed one at rest
// (32 x 16: a stable step 4 times shorter), 0.3 us: they meet, and part.
Impact impact(int levels, double v, double safety = 0.9) {
  TestMesh mesh;
  mesh.addRectangle(-0.21e-3, -0.05e-3, 0.2e-3, 0.1e-3, 8, 4, 0.2, 7);
  mesh.addRectangle(0.0, -0.05e-3, 0.2e-3, 0.1e-3, 32, 16, 0.2, 8);
  fem::Model model = mesh.model(test::oneMaterial("quartz-elastic"));
  fem::setBodyVelocity(model, 0, v, 0.0);
  fem::Contact contact(model, {});
  fem::Solver solver(model, {.safety = safety, .anti_locking = false, .subcycle_levels = levels});
  solver.addForceProvider(&contact);
  Impact r{};
  r.kinetic0 = solver.energy().kinetic;
  const fem::Nodes &nd = model.nodes;
  while (solver.time() < 0.3e-6) {
    solver.step();
    r.most_subcycled = std::max(r.most_subcycled, solver.subcycledBodies());
    double px = 0.0, py = 0.0;
    for (std::size_t a = 0; a < nd.size(); ++a)
      px += nd.mass[a] * nd.vx[a], py += nd.mass[a] * nd.vy[a];
    const double mv = fem::bodyMotion(model, 0).mass * v;
    r.worst_momentum = std::max({r.worst_momentum, std::abs(px - mv) / mv, std::abs(py) / mv});
  }
  r.px_coarse = fem::bodyMotion(model, 0).px, r.px_fine = fem::bodyMotion(model, 1).px;
  r.balance_error = solver.energy().balance_error, r.contact_energy = solver.energy().contact;
  r.steps = solver.steps();
  return r;
}

} // namespace

// With substeps the fine block takes 4 of them a step, and the run about 4 times fewer steps.
// Momentum is conserved to round-off: the contact's impulses over a step are the same on both
// sides, held over substeps or not. The energy balance closes within 2e-3 (1.3e-4 without
// substeps; with them 9.6e-4: the fine block's kinetic energy is the leapfrog's at the loop's
// steps, not at its own), and the contact puts no more energy in than without substeps (its
// energy, what the contact forces took out, -0.36 J/m without and -0.013 with, of 2.4 J/m):
// holding the contact force as two half-impulses at the step's ends instead (the impulse method
// of multiple time steps) put energy in where the fine body's vibration met the step, r-RESPA's
// resonance (run 6 ended with the contact's energy at -53 J/m against +5). The momentum the fine
// block leaves with is that of the run without substeps at a quarter of their step (the reference
// closest to converged) within 3 % of m v: the reference itself moves by 4 % of m v between
// safety 0.9 and 0.11 (the blocks part as their ringing decides), the run with substeps by 1.2 %
// (0.9 to 0.45) and less and less after.
TEST(Subcycling, ImpactOnAFinerBodyAsWithoutSubsteps) {
  const double v = 300.0;
  const Impact fine = impact(0, v), sub = impact(2, v), reference = impact(0, v, 0.225);
  std::printf("without substeps: %zu steps, momenta %.5g %.5g, balance %.2e, contact %.3g J/m\n",
              fine.steps, fine.px_coarse, fine.px_fine, fine.balance_error, fine.contact_energy);
  std::printf("with substeps:    %zu steps, momenta %.5g %.5g, balance %.2e, contact %.3g J/m, "
              "momentum error %.2e\n",
              sub.steps, sub.px_coarse, sub.px_fine, sub.balance_error, sub.contact_energy,
              sub.worst_momentum);
  std::printf("reference (a quarter of the step, no substeps): momenta %.5g %.5g\n",
              reference.px_coarse, reference.px_fine);
  EXPECT_EQ(fine.most_subcycled, 0u);
  EXPECT_EQ(sub.most_subcycled, 1u);
  EXPECT_LT(3 * sub.steps, fine.steps);
  const double mv = fine.px_coarse + fine.px_fine;
  EXPECT_GT(reference.px_fine, 0.5 * mv) << "they met";
  EXPECT_LT(sub.worst_momentum, 1e-12);
  EXPECT_LT(std::abs(sub.px_fine - reference.px_fine), 0.03 * mv);
  EXPECT_LT(std::abs(sub.balance_error), 2e-3);
  EXPECT_GT(sub.contact_energy, fine.contact_energy - 1e-3 * sub.kinetic0);
}
