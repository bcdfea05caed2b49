#include "mpi_communicator.hpp"

#include <algorithm>
#include <atomic>
#include <climits>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace mesopen::parallel {

namespace {
std::atomic<std::int64_t> received_bytes{0}, received_operations{0};
} // namespace

Traffic traffic() {
  return {received_bytes.load(std::memory_order_relaxed),
          received_operations.load(std::memory_order_relaxed)};
}

namespace detail {
void countReceived(std::int64_t bytes) {
  received_bytes.fetch_add(bytes, std::memory_order_relaxed);
  received_operations.fetch_add(1, std::memory_order_relaxed);
}
} // namespace detail

void ensureMpi() {
  int initialised = 0, finalised = 0;
  MPI_Initialized(&initialised);
  MPI_Finalized(&finalised);
  if (initialised || finalised)
    return;
  // A process not started by mpirun is a singleton: Open MPI 4.1 then starts a daemon and probes
  // UCX, 0.27 s here; isolated, with the ob1 layer (intra-node, all one process needs), 0.02 s.
  // Settings the user made in the environment are kept.
  if (!std::getenv("OMPI_COMM_WORLD_SIZE")) {
    setenv("OMPI_MCA_ess_singleton_isolated", "1", 0);
    setenv("OMPI_MCA_pml", "ob1", 0);
  }
  MPI_Init(nullptr, nullptr);
  std::atexit([] {
    int done = 0;
    MPI_Finalized(&done);
    if (!done)
      MPI_Finalize();
  });
}

World world(bool needed) {
  if (!needed && !std::getenv("OMPI_COMM_WORLD_SIZE"))
    return {};
  ensureMpi();
  World w;
  MPI_Comm_rank(MPI_COMM_WORLD, &w.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &w.size);
  return w;
}

void World::barrier() const {
  if (size > 1) {
    MPI_Barrier(MPI_COMM_WORLD);
    detail::countReceived(0);
  }
}

double World::sum(double value) const {
  return size > 1 ? allReduce(value, MPI_SUM, MPI_COMM_WORLD) : value;
}

double World::max(double value) const {
  return size > 1 ? allReduce(value, MPI_MAX, MPI_COMM_WORLD) : value;
}

namespace detail {

GatherLayout gatherLayout(std::int64_t mine, MPI_Comm comm) {
  int ranks = 1;
  MPI_Comm_size(comm, &ranks);
  std::vector<std::int64_t> sizes(static_cast<std::size_t>(ranks));
  MPI_Allgather(&mine, 1, MPI_INT64_T, sizes.data(), 1, MPI_INT64_T, comm);
  if (ranks > 1)
    countReceived(static_cast<std::int64_t>(sizeof(std::int64_t)) * (ranks - 1));
  GatherLayout layout;
  for (std::int64_t size : sizes) {
    if (layout.total + size > INT_MAX) // every rank sees the same sizes: all throw
      throw std::length_error("an MPI gather of " + std::to_string(layout.total + size) +
                              " bytes or more: MPI_Allgatherv takes at most " +
                              std::to_string(INT_MAX));
    layout.counts.push_back(static_cast<int>(size));
    layout.offsets.push_back(static_cast<int>(layout.total));
    layout.total += size;
  }
  return layout;
}

} // namespace detail

MpiCommunicator::MpiCommunicator(MPI_Comm comm) : comm_(comm) {
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &size_);
}

std::vector<double> MpiCommunicator::allGather(std::vector<double> mine) const {
  return allGatherItems(std::move(mine), comm_);
}

std::vector<std::int64_t> MpiCommunicator::allGather(std::vector<std::int64_t> mine) const {
  return allGatherItems(std::move(mine), comm_);
}

std::vector<double> MpiCommunicator::sumInOrder(std::vector<double> mine) const {
  if (size_ == 1 || mine.empty())
    return mine;
  const std::vector<double> all = allGather(mine);
  std::vector<double> sum(mine.size(), 0.0);
  for (std::size_t k = 0; k < all.size(); ++k)
    sum[k % mine.size()] += all[k];
  return sum;
}

double MpiCommunicator::min(double value) const { // exact in any order: one reduction
  return allReduce(value, MPI_MIN, comm_);
}

void MpiCommunicator::share(std::size_t count, const std::function<void(double *)> &pack,
                            const std::function<void(const double *)> &unpack) const {
  std::vector<double> mine(count);
  pack(mine.data());
  unpack(allGather(std::move(mine)).data());
}

} // namespace mesopen::parallel
