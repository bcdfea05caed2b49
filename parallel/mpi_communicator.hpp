// MPI for the whole program: its initialisation (LIGGGHTS needs it), the processes mpirun started
// (World), the communicator the solvers share their work through, and the gather of plain data
// the DEM adapter uses. The only place, with its .cpp, that calls MPI for mesopen's own work.
#pragma once

#include "communicator.hpp"

#include <mpi.h>

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
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
// A failure of this process alone, which the others would wait for in their next exchange: says
// `why` on stderr and ends every process (MPI_Abort, exit code 1).
[[noreturn]] void abortEveryProcess(const std::string &why);

// What this process has received from the others through the operations of this file (the
// solver's communicator, the coupling's gathers and reductions, the partitioner's reductions),
// since it started, in 64-bit counts. `bytes` is the payload an operation delivers to this
// process from the others, counted as a gather counts it whatever algorithm MPI uses: an
// all-gather counts the other processes' parts, a reduction of n bytes (P - 1) n, a gather to a
// root the others' parts at the root and nothing elsewhere, and the byte counts a gather of
// unequal parts exchanges first (8 bytes from each other process) as well; a barrier counts
// nothing; point-to-point messages count their payload. `operations` is the collective calls made
// with more than one process (messages are not among them), `messages` the point-to-point
// messages received (an empty one too). Not counted:
// MPI's own traffic (parts forwarded along a ring or tree, headers), and what Zoltan and LIGGGHTS
// send on their own (a partition's cuts, the disks' decomposition).
struct Traffic {
  std::int64_t bytes = 0, operations = 0, messages = 0;
};
Traffic traffic();

namespace detail {
// One collective operation that delivered `bytes` from other processes (added to traffic()).
void countReceived(std::int64_t bytes);
// `messages` point-to-point messages that delivered `bytes` (added to traffic(), no operation).
void countMessages(std::int64_t bytes, std::int64_t messages);
// The MPI type of T, for the reductions.
template <class T> MPI_Datatype mpiType() {
  if constexpr (std::is_same_v<T, double>)
    return MPI_DOUBLE;
  else if constexpr (std::is_same_v<T, int>)
    return MPI_INT;
  else if constexpr (std::is_same_v<T, unsigned long>)
    return MPI_UNSIGNED_LONG;
  else if constexpr (std::is_same_v<T, std::int64_t>)
    return MPI_INT64_T;
  else
    static_assert(sizeof(T) == 0, "no MPI type for this reduction");
}

// Every rank's byte count (exchanged as 64-bit integers, an all-gather counted by traffic()) and
// where each lands in the gathered whole. MPI_Allgatherv takes int counts and offsets: a whole of
// more than INT_MAX bytes is refused (std::length_error), not cut or wrapped.
struct GatherLayout {
  std::vector<int> counts, offsets;
  std::int64_t total = 0;
};
GatherLayout gatherLayout(std::int64_t mine, MPI_Comm comm);
// The same from byte counts every rank knows already (no message).
GatherLayout layoutOf(const std::vector<std::int64_t> &sizes);
// Every rank's 64-bit `count` at rank `root` (MPI_Gather; the others get none).
std::vector<std::int64_t> gatherCounts(std::int64_t count, int root, MPI_Comm comm);
// `bytes` bytes to or from one rank as messages in pieces of at most `piece` bytes (MPI counts
// are int), counted by traffic() at the receiver.
constexpr std::int64_t byte_piece = std::int64_t{1} << 30;
void sendBytes(const void *data, std::int64_t bytes, int to, MPI_Comm comm,
               std::int64_t piece = byte_piece);
void receiveBytes(void *data, std::int64_t bytes, int from, MPI_Comm comm,
                  std::int64_t piece = byte_piece);
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
  detail::countReceived(layout.total - layout.counts[rank]);
  return all;
}

// The same when every rank knows how many items each sends (`sizes[r]` from rank r): one call.
// A part of another size than `sizes` says is a bug of the caller: std::logic_error.
template <class T>
std::vector<T> allGatherItems(std::vector<T> mine, const std::vector<std::int64_t> &sizes,
                              MPI_Comm comm) {
  static_assert(std::is_trivially_copyable_v<T>);
  int ranks = 1, rank = 0;
  MPI_Comm_size(comm, &ranks);
  MPI_Comm_rank(comm, &rank);
  if (sizes.size() != static_cast<std::size_t>(ranks) ||
      sizes[static_cast<std::size_t>(rank)] != static_cast<std::int64_t>(mine.size()))
    throw std::logic_error("an all-gather of " + std::to_string(mine.size()) +
                           " items where its sizes say otherwise");
  if (ranks == 1)
    return mine;
  std::vector<std::int64_t> bytes(sizes);
  for (std::int64_t &b : bytes)
    b *= static_cast<std::int64_t>(sizeof(T));
  const detail::GatherLayout layout = detail::layoutOf(bytes);
  std::vector<T> all(static_cast<std::size_t>(layout.total) / sizeof(T));
  MPI_Allgatherv(mine.data(), layout.counts[rank], MPI_BYTE, all.data(), layout.counts.data(),
                 layout.offsets.data(), MPI_BYTE, comm);
  detail::countReceived(layout.total - layout.counts[rank]);
  return all;
}

// Every rank's items (plain data, sent as bytes) concatenated in rank order on rank `root`; the
// others get none. The byte counts go to `root` as 64-bit integers first (one call), then each
// rank's items as messages (in pieces: any size, 64-bit counts and offsets).
template <class T> std::vector<T> gatherItems(std::vector<T> mine, int root, MPI_Comm comm) {
  static_assert(std::is_trivially_copyable_v<T>);
  int ranks = 1, rank = 0;
  MPI_Comm_size(comm, &ranks);
  if (ranks == 1)
    return mine;
  MPI_Comm_rank(comm, &rank);
  const auto bytes = static_cast<std::int64_t>(mine.size() * sizeof(T));
  const std::vector<std::int64_t> counts = detail::gatherCounts(bytes, root, comm);
  if (rank != root) {
    detail::sendBytes(mine.data(), bytes, root, comm);
    return {};
  }
  std::int64_t total = 0;
  for (std::int64_t count : counts)
    total += count;
  std::vector<T> all(static_cast<std::size_t>(total) / sizeof(T));
  char *at = reinterpret_cast<char *>(all.data());
  for (int r = 0; r < ranks; ++r) {
    const std::int64_t count = counts[static_cast<std::size_t>(r)];
    if (r != rank)
      detail::receiveBytes(at, count, r, comm);
    else if (count > 0)
      std::memcpy(at, mine.data(), static_cast<std::size_t>(count));
    at += count;
  }
  return all;
}

// Every rank's `value` combined by `op` (MPI_MIN, MPI_MAX, MPI_SUM), on every rank.
template <class T> T allReduce(T value, MPI_Op op, MPI_Comm comm) {
  int ranks = 1;
  MPI_Comm_size(comm, &ranks);
  if (ranks == 1)
    return value;
  T result{};
  MPI_Allreduce(&value, &result, 1, detail::mpiType<T>(), op, comm);
  detail::countReceived(static_cast<std::int64_t>(sizeof(T)) * (ranks - 1));
  return result;
}

// The processes of an MPI communicator (MPI initialised), through a duplicate of it: its messages
// never meet those of a library that shares the processes (LIGGGHTS).
class MpiCommunicator final : public Communicator {
public:
  // `piece`: the most values of an exchange's message (MPI counts are int); smaller in tests.
  explicit MpiCommunicator(MPI_Comm comm = MPI_COMM_WORLD,
                           std::int64_t piece = std::int64_t{1} << 30);
  ~MpiCommunicator() override;
  MpiCommunicator(const MpiCommunicator &) = delete;
  MpiCommunicator &operator=(const MpiCommunicator &) = delete;
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  MPI_Comm handle() const { return comm_; } // the duplicate
  std::vector<double> allGather(std::vector<double> mine) const override;
  std::vector<std::int64_t> allGather(std::vector<std::int64_t> mine) const override;
  std::vector<double> allGather(std::vector<double> mine,
                                const std::vector<std::int64_t> &sizes) const override;
  std::vector<std::int64_t> allGather(std::vector<std::int64_t> mine,
                                      const std::vector<std::int64_t> &sizes) const override;
  std::vector<double> sumInOrder(std::vector<double> mine) const override;
  double min(double value) const override;
  std::vector<double> max(std::vector<double> values) const override;
  void share(std::size_t count, const std::function<void(double *)> &pack,
             const std::function<void(const double *)> &unpack) const override;
  // The counts to process 0 (MPI_Gather, 64-bit), then each process's values as messages to it
  // (in pieces of at most 2^30 bytes), received one process after the other.
  void collect(std::size_t count, const std::function<void(double *)> &pack,
               const std::function<void(int, const double *)> &unpack) const override;
  // Each list, an empty one too, as a message to its process, whose length the receiver takes
  // from it (MPI_Mprobe): no collective call. In pieces of `piece` values, all full but the last,
  // which may be empty.
  std::vector<std::vector<std::int64_t>>
  exchange(std::vector<std::vector<std::int64_t>> to) const override;
  std::vector<std::vector<std::int64_t>>
  exchangeWith(std::vector<std::vector<std::int64_t>> to,
               const std::vector<int> &partners) const override;
  // The messages alone. A message of another size than `sizes` says is a bug of the caller: a
  // shorter one throws std::logic_error, a longer one is an MPI error.
  std::vector<std::vector<std::int64_t>>
  exchange(std::vector<std::vector<std::int64_t>> to,
           const std::vector<std::int64_t> &sizes) const override;

private:
  MPI_Comm comm_;
  int rank_ = 0, size_ = 1;
  std::int64_t piece_;
};

} // namespace mesopen::parallel
