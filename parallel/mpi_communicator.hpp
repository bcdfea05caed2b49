// MPI for the whole program: its initialisation (LIGGGHTS needs it), the processes mpirun started
// (World), the communicator the solvers share their work through, and the gather of plain data
// the DEM adapter uses. The only place, with its .cpp, that calls MPI for mesopen's own work.
#pragma once

#include "communicator.hpp"

#include <mpi.h>

#include <cstdint>
#include <type_traits>
#include <vector>

namespace mesopen::parallel {

// MPI initialised (once), and finalised when the program exits.
void ensureMpi();
// This process's rank among the processes mpirun started, and their number: MPI is initialised if
// mpirun (Open MPI) started the program or `needed`; else rank 0 of 1.
struct World {
  int rank = 0, size = 1;
  void barrier() const;
  double sum(double value) const; // over the ranks
  double max(double value) const;
};
World world(bool needed);

namespace detail {
// Every rank's byte count (exchanged as 64-bit integers) and where each lands in the gathered
// whole. MPI_Allgatherv takes int counts and offsets: a whole of more than INT_MAX bytes is refused
// (std::length_error), not cut or wrapped.
struct GatherLayout {
  std::vector<int> counts, offsets;
  std::int64_t total = 0;
};
GatherLayout gatherLayout(std::int64_t mine, MPI_Comm comm);
} // namespace detail

// Every rank's items (plain data, sent as bytes), concatenated in rank order on every rank.
template <class T> std::vector<T> allGatherItems(std::vector<T> mine, MPI_Comm comm) {
  static_assert(std::is_trivially_copyable_v<T>);
  int ranks = 1, rank = 0;
  MPI_Comm_size(comm, &ranks);
  if (ranks == 1)
    return mine;
  MPI_Comm_rank(comm, &rank);
  const detail::GatherLayout layout =
      detail::gatherLayout(static_cast<std::int64_t>(mine.size() * sizeof(T)), comm);
  std::vector<T> all(static_cast<std::size_t>(layout.total) / sizeof(T));
  MPI_Allgatherv(mine.data(), layout.counts[rank], MPI_BYTE, all.data(), layout.counts.data(),
                 layout.offsets.data(), MPI_BYTE, comm);
  return all;
}

// The processes of an MPI communicator (MPI initialised).
class MpiCommunicator final : public Communicator {
public:
  explicit MpiCommunicator(MPI_Comm comm = MPI_COMM_WORLD);
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  std::vector<double> allGather(std::vector<double> mine) const override;
  std::vector<std::int64_t> allGather(std::vector<std::int64_t> mine) const override;
  std::vector<double> sumInOrder(std::vector<double> mine) const override;
  double min(double value) const override;
  void share(std::size_t count, const std::function<void(double *)> &pack,
             const std::function<void(const double *)> &unpack) const override;

private:
  MPI_Comm comm_;
  int rank_ = 0, size_ = 1;
};

} // namespace mesopen::parallel
