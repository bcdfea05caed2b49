// Zoltan's RCB partition (parallel/zoltan_partitioner.hpp) at the edges, on every process of
// mpirun: no item, one item (which Zoltan refuses on the processes left without one: each item
// then stays where it is), two, and many, all on rank 0, with weights or none; every item gets a
// rank, the same call gives the same parts, and many items weighted alike are shared within 10 %.
// Prints what failed and exits 1; a failure on one process alone would hang the others, so every
// call must come back on every process.
#include "zoltan_partitioner.hpp"

#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <vector>

using namespace mesopen::parallel;

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1, failures = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  {
    const ZoltanRcb rcb(MPI_COMM_WORLD);
    for (int n : {0, 1, 2, 3, 64})
      for (bool weighted : {true, false}) {
        PartitionItems items;
        if (rank == 0)
          for (int k = 0; k < n; ++k) {
            items.id.push_back(static_cast<std::uint32_t>(k));
            items.x.push_back(k % 8), items.y.push_back(k / 8);
            items.weight.push_back(weighted ? 1.0 : 0.0);
          }
        try {
          const std::vector<int> to = rcb.partition(items), again = rcb.partition(items);
          bool ok = to.size() == items.size() && to == again;
          for (int r : to)
            ok = ok && r >= 0 && r < size;
          if (n < 2)
            ok = ok && std::all_of(to.begin(), to.end(), [&](int r) { return r == rank; });
          if (n == 64 && weighted && rank == 0) {
            std::vector<int> count(size, 0);
            for (int r : to)
              ++count[r];
            ok = ok && *std::max_element(count.begin(), count.end()) <= 1.1 * 64 / size;
          }
          if (!ok) {
            std::printf("rank %d: %d items%s: wrong parts\n", rank, n,
                        weighted ? "" : " unweighted");
            ++failures;
          }
        } catch (const std::exception &e) {
          std::printf("rank %d: %d items%s: %s\n", rank, n, weighted ? "" : " unweighted",
                      e.what());
          ++failures;
        }
      }
  }
  int any = 0;
  MPI_Allreduce(&failures, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  if (rank == 0)
    std::printf("partition_edges on %d processes: %s\n", size, any ? "FAILED" : "passed");
  MPI_Finalize();
  return any ? 1 : 0;
}
