// A body of another process here in part (Contact::exchangeHalo), on every process of mpirun: a
// square of 2 x 2 elements pressed 0.2 of an element deep into a strip of 64 x 2 (132 boundary
// nodes: it goes in part, the part near the square), the square's corner node deep enough that
// the crossing count decides its side (Contact::insideOf, from the window's corner). After 200
// steps every node's position and velocity equal those of the same run on one process to the bit,
// and the square was pushed out. Prints what failed and exits 1.
#include "meshes.hpp"
#include "mpi_communicator.hpp"
#include "node_states.hpp"
#include "zoltan_partitioner.hpp"

#include "contact.hpp"
#include "solver.hpp"

#include <mpi.h>

#include <cstdio>
#include <vector>

using namespace mesopen;

namespace {

constexpr double h = 10e-6; // the element size

struct Run : test::NodeStates {
  double deepest = 0.0;
};

// The strip moving up at 5 m/s into the square, whose lower edge starts 0.2 h inside it.
Run pressed(const parallel::Communicator &processes, const parallel::Partitioner &partitioner) {
  test::TestMesh mesh;
  mesh.addRectangle(0.0, 0.0, 64 * h, 2 * h, 64, 2);
  mesh.addRectangle(31 * h, 1.8 * h, 2 * h, 2 * h, 2, 2);
  fem::Model model = mesh.model(test::oneMaterial("quartz"));
  fem::setBodyVelocity(model, 0, 0.0, 5.0);
  fem::setBodyVelocity(model, 1, 0.0, 0.0);
  model.wake(1);
  fem::Contact contact(model, {});
  fem::Solver solver(model, {}, processes, partitioner);
  solver.addForceProvider(&contact);
  for (int step = 0; step < 200; ++step)
    solver.step();
  solver.collectFrame(); // every node's position and velocity on the first process
  return {{model.nodes.x, model.nodes.y, model.nodes.vx, model.nodes.vy},
          contact.statistics().max_depth};
}

} // namespace

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  int failures = 0;
  {
    const parallel::MpiCommunicator world(MPI_COMM_WORLD);
    const parallel::ZoltanRcb rcb(MPI_COMM_WORLD);
    const Run shared = pressed(world, rcb);
    if (world.rank() == 0) {
      const Run one = pressed(parallel::serial(), parallel::serialPartitioner());
      failures += test::differingNodeStates(world.size(), shared, one);
      // the square's nodes were pushed up by the strip, from 0.2 h deep
      if (!(one.deepest > 0.15 && one.vy.back() > 1.0)) {
        std::printf("the square was not pressed and pushed out: deepest %.3g, vy %.3g m/s\n",
                    one.deepest, one.vy.back());
        ++failures;
      }
      std::printf("%d processes: %s (deepest %.3f of an element)\n", world.size(),
                  failures ? "FAILED" : "the same run as on one", one.deepest);
    }
    MPI_Bcast(&failures, 1, MPI_INT, 0, MPI_COMM_WORLD);
  }
  MPI_Finalize();
  return failures ? 1 : 0;
}
