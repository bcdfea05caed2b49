// Levels (multiple time stepping) on every process of mpirun while every moving body changes owner
// every 10 steps (a partitioner that hands each body to the next rank at each call): a strip of
// 2,048 elements (stepped in 4 parts, each a slab two cells deep) struck from above by three
// squares of elements a third as large, which set the base step, so that the strip's parts far from
// them step at a coarser level than those beneath them. A body that changes owner brings what
// only its owner keeps of its levels (its elements' last steps, its energies; its parts' levels,
// forces and window starts; the contact's pushed depths per level of pair). After 300 steps every
// node's position and velocity equal those of the same run on one process to the bit, and the run
// on one process saved element updates. Prints what failed and exits 1.
#include "meshes.hpp"
#include "mpi_communicator.hpp"
#include "node_states.hpp"

#include "contact.hpp"
#include "solver.hpp"

#include <mpi.h>

#include <cstdio>
#include <vector>

using namespace mesopen;

namespace {

constexpr double h = 10e-6; // the strip's element size

// Every body to the rank after the one the last call gave it: (id + calls) mod size.
class RotatingPartitioner final : public parallel::Partitioner {
public:
  explicit RotatingPartitioner(int size) : size_(size) {}
  std::vector<int> partition(const parallel::PartitionItems &mine) const override {
    ++calls_;
    std::vector<int> to;
    for (std::uint32_t id : mine.id)
      to.push_back(static_cast<int>((id + calls_) % static_cast<unsigned>(size_)));
    return to;
  }

private:
  int size_;
  mutable unsigned calls_ = 0;
};

struct Run : test::NodeStates {
  double share = 1.0; // element updates computed over those at a single rate
  std::size_t parts = 0;
};

Run struck(const parallel::Communicator &processes, const parallel::Partitioner &partitioner) {
  test::TestMesh mesh;
  mesh.addRectangle(0.0, 0.0, 128 * h, 8 * h, 128, 8);
  for (double x0 : {10 * h, 60 * h, 110 * h})
    mesh.addRectangle(x0, 8.1 * h, 2 * h, 2 * h, 6, 6);
  fem::Model model = mesh.model(test::oneMaterial("quartz"));
  for (std::size_t b = 1; b < 4; ++b)
    fem::setBodyVelocity(model, b, 0.0, -20.0 - 5.0 * static_cast<double>(b));
  fem::Contact contact(model, {});
  fem::Solver solver(model, {.rebalance_every = 10, .max_level = 2}, processes, partitioner);
  solver.addForceProvider(&contact);
  for (int step = 0; step < 300; ++step)
    solver.step();
  solver.collectFrame(); // every node's position and velocity on the first process
  return {{model.nodes.x, model.nodes.y, model.nodes.vx, model.nodes.vy},
          solver.elementSteps() / solver.singleRateElementSteps(),
          solver.parts()};
}

} // namespace

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  int failures = 0;
  {
    const parallel::MpiCommunicator world(MPI_COMM_WORLD);
    const RotatingPartitioner rotating(world.size());
    const Run shared = struck(world, rotating);
    if (world.rank() == 0) {
      const Run one = struck(parallel::serial(), parallel::serialPartitioner());
      failures += test::differingNodeStates(world.size(), shared, one);
      if (!(one.parts == 4 && one.share < 0.9)) {
        std::printf("not a run at levels in parts: %zu parts, %.3f of the element updates\n",
                    one.parts, one.share);
        ++failures;
      }
      std::printf("%d processes: %s (%.3f of the element updates, %zu parts)\n", world.size(),
                  failures ? "FAILED" : "the same run as on one", one.share, one.parts);
    }
    MPI_Bcast(&failures, 1, MPI_INT, 0, MPI_COMM_WORLD);
  }
  MPI_Finalize();
  return failures ? 1 : 0;
}
