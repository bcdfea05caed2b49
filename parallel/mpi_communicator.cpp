#include "mpi_communicator.hpp"

#include <algorithm>
#include <atomic>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace mesopen::parallel {

namespace {
std::atomic<std::int64_t> received_bytes{0}, received_operations{0}, received_messages{0};
} // namespace

Traffic traffic() {
  return {received_bytes.load(std::memory_order_relaxed),
          received_operations.load(std::memory_order_relaxed),
          received_messages.load(std::memory_order_relaxed)};
}

namespace detail {
void countReceived(std::int64_t bytes) {
  received_bytes.fetch_add(bytes, std::memory_order_relaxed);
  received_operations.fetch_add(1, std::memory_order_relaxed);
}
void countMessages(std::int64_t bytes, std::int64_t messages) {
  received_bytes.fetch_add(bytes, std::memory_order_relaxed);
  received_messages.fetch_add(messages, std::memory_order_relaxed);
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

void abortEveryProcess(const std::string &why) {
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  std::fprintf(stderr, "mesopen: process %d of %d: %s; every process ends\n", rank, size,
               why.c_str());
  std::fflush(stderr);
  MPI_Abort(MPI_COMM_WORLD, 1);
  std::abort(); // (MPI_Abort does not return)
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
  return layoutOf(sizes);
}

GatherLayout layoutOf(const std::vector<std::int64_t> &sizes) {
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

std::vector<std::int64_t> gatherCounts(std::int64_t count, int root, MPI_Comm comm) {
  int ranks = 1, rank = 0;
  MPI_Comm_size(comm, &ranks);
  MPI_Comm_rank(comm, &rank);
  std::vector<std::int64_t> counts(rank == root ? static_cast<std::size_t>(ranks) : 0);
  MPI_Gather(&count, 1, MPI_INT64_T, counts.data(), 1, MPI_INT64_T, root, comm);
  countReceived(rank == root ? static_cast<std::int64_t>(sizeof(count)) * (ranks - 1) : 0);
  return counts;
}

namespace {
constexpr int bytes_tag = 2;
} // namespace

void sendBytes(const void *data, std::int64_t bytes, int to, MPI_Comm comm, std::int64_t piece) {
  const char *from = static_cast<const char *>(data);
  for (std::int64_t at = 0; at < bytes; at += piece)
    MPI_Send(from + at, static_cast<int>(std::min(piece, bytes - at)), MPI_BYTE, to, bytes_tag,
             comm);
}

void receiveBytes(void *data, std::int64_t bytes, int from, MPI_Comm comm, std::int64_t piece) {
  char *to = static_cast<char *>(data);
  std::int64_t messages = 0;
  for (std::int64_t at = 0; at < bytes; at += piece, ++messages)
    MPI_Recv(to + at, static_cast<int>(std::min(piece, bytes - at)), MPI_BYTE, from, bytes_tag,
             comm, MPI_STATUS_IGNORE);
  countMessages(bytes, messages);
}

} // namespace detail

MpiCommunicator::MpiCommunicator(MPI_Comm comm, std::int64_t piece) : piece_(piece) {
  if (piece < 1 || piece > INT_MAX)
    throw std::invalid_argument("MpiCommunicator: a message of " + std::to_string(piece) +
                                " values; allowed 1 to " + std::to_string(INT_MAX));
  MPI_Comm_dup(comm, &comm_);
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &size_);
}

MpiCommunicator::~MpiCommunicator() {
  int finalised = 0;
  MPI_Finalized(&finalised);
  if (!finalised)
    MPI_Comm_free(&comm_);
}

std::vector<double> MpiCommunicator::allGather(std::vector<double> mine) const {
  return allGatherItems(std::move(mine), comm_);
}

std::vector<std::int64_t> MpiCommunicator::allGather(std::vector<std::int64_t> mine) const {
  return allGatherItems(std::move(mine), comm_);
}

std::vector<double> MpiCommunicator::allGather(std::vector<double> mine,
                                               const std::vector<std::int64_t> &sizes) const {
  return allGatherItems(std::move(mine), sizes, comm_);
}

std::vector<std::int64_t> MpiCommunicator::allGather(std::vector<std::int64_t> mine,
                                                     const std::vector<std::int64_t> &sizes) const {
  return allGatherItems(std::move(mine), sizes, comm_);
}

std::vector<double> MpiCommunicator::sumInOrder(std::vector<double> mine) const {
  if (size_ == 1 || mine.empty())
    return mine;
  // (every process gives as many values: one call)
  const std::vector<double> all =
      allGather(mine, std::vector<std::int64_t>(static_cast<std::size_t>(size_),
                                                static_cast<std::int64_t>(mine.size())));
  std::vector<double> sum(mine.size(), 0.0);
  for (std::size_t k = 0; k < all.size(); ++k)
    sum[k % mine.size()] += all[k];
  return sum;
}

double MpiCommunicator::min(double value) const { // exact in any order: one reduction
  return allReduce(value, MPI_MIN, comm_);
}

std::vector<double> MpiCommunicator::max(std::vector<double> values) const { // one reduction
  if (size_ == 1 || values.empty())
    return values;
  MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE, MPI_MAX,
                comm_);
  detail::countReceived(static_cast<std::int64_t>(sizeof(double) * values.size()) * (size_ - 1));
  return values;
}

void MpiCommunicator::share(std::size_t count, const std::function<void(double *)> &pack,
                            const std::function<void(const double *)> &unpack) const {
  if (size_ == 1) // (this process holds every value)
    return;
  std::vector<double> mine(count);
  pack(mine.data());
  unpack(allGather(std::move(mine)).data());
}

void MpiCommunicator::collect(std::size_t count, const std::function<void(double *)> &pack,
                              const std::function<void(int, const double *)> &unpack) const {
  if (size_ == 1)
    return;
  std::vector<double> values(rank_ == 0 ? 0 : count);
  if (rank_ != 0)
    pack(values.data());
  const auto bytes = static_cast<std::int64_t>(sizeof(double) * count);
  const std::vector<std::int64_t> counts = detail::gatherCounts(bytes, 0, comm_);
  if (rank_ != 0) {
    detail::sendBytes(values.data(), bytes, 0, comm_);
    return;
  }
  for (int r = 1; r < size_; ++r) {
    const std::int64_t received = counts[static_cast<std::size_t>(r)];
    values.resize(static_cast<std::size_t>(received) / sizeof(double));
    detail::receiveBytes(values.data(), received, r, comm_);
    unpack(r, values.data());
  }
}

// Every other process (exchange) or every partner (exchangeWith) gets a message from this one, an
// empty list too, and its length comes with it (MPI_Mprobe): no collective call. A list of n
// values goes as n / piece + 1 messages, all full but the last (empty when n is a multiple), so
// the receiver knows where it ends.
std::vector<std::vector<std::int64_t>>
MpiCommunicator::exchange(std::vector<std::vector<std::int64_t>> to) const {
  std::vector<int> others;
  for (int r = 0; r < size_; ++r)
    if (r != rank_)
      others.push_back(r);
  return exchangeWith(std::move(to), others);
}

std::vector<std::vector<std::int64_t>>
MpiCommunicator::exchangeWith(std::vector<std::vector<std::int64_t>> to,
                              const std::vector<int> &partners) const {
  if (to.size() != static_cast<std::size_t>(size_))
    throw std::invalid_argument("exchange: " + std::to_string(to.size()) + " lists for " +
                                std::to_string(size_) + " processes");
  const auto ranks = static_cast<std::size_t>(size_), me = static_cast<std::size_t>(rank_);
  for (std::size_t r = 0, k = 0; r < ranks; ++r) {
    const bool partner = k < partners.size() && partners[k] == static_cast<int>(r);
    k += partner;
    if (r != me && !partner && !to[r].empty())
      throw std::logic_error("exchange: " + std::to_string(to[r].size()) + " values for process " +
                             std::to_string(r) + ", not a partner");
  }
  std::vector<std::vector<std::int64_t>> from(ranks);
  from[me] = std::move(to[me]);
  if (size_ == 1)
    return from;
  const std::int64_t piece = piece_;
  constexpr int tag = 3; // (its own: a message of another kind is never taken for one of these)
  std::vector<MPI_Request> requests;
  for (const int r : partners) {
    const auto n = static_cast<std::int64_t>(to[static_cast<std::size_t>(r)].size());
    for (std::int64_t at = 0;; at += piece) {
      const std::int64_t part = std::min(piece, n - at);
      requests.emplace_back();
      MPI_Isend(to[static_cast<std::size_t>(r)].data() + at, static_cast<int>(part), MPI_INT64_T, r,
                tag, comm_, &requests.back());
      if (part < piece)
        break;
    }
  }
  std::int64_t received = 0, messages = 0;
  for (const int r : partners) {
    std::vector<std::int64_t> &list = from[static_cast<std::size_t>(r)];
    for (int count = static_cast<int>(piece); count == piece; ++messages) {
      MPI_Message message;
      MPI_Status status;
      MPI_Mprobe(r, tag, comm_, &message, &status);
      MPI_Get_count(&status, MPI_INT64_T, &count);
      const std::size_t at = list.size();
      list.resize(at + static_cast<std::size_t>(count));
      MPI_Mrecv(list.data() + at, count, MPI_INT64_T, &message, MPI_STATUS_IGNORE);
      received += count;
    }
  }
  MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
  detail::countMessages(static_cast<std::int64_t>(sizeof(std::int64_t)) * received, messages);
  return from;
}

std::vector<std::vector<std::int64_t>>
MpiCommunicator::exchange(std::vector<std::vector<std::int64_t>> to,
                          const std::vector<std::int64_t> &sizes) const {
  const auto ranks = static_cast<std::size_t>(size_);
  if (to.size() != ranks || sizes.size() != ranks)
    throw std::invalid_argument("exchange: " + std::to_string(to.size()) + " lists and " +
                                std::to_string(sizes.size()) + " sizes for " +
                                std::to_string(size_) + " processes");
  const auto me = static_cast<std::size_t>(rank_);
  std::vector<std::vector<std::int64_t>> from(ranks);
  from[me] = std::move(to[me]);
  if (size_ == 1)
    return from;
  const std::int64_t piece = piece_;
  constexpr int tag = 1;
  std::vector<MPI_Request> requests;
  std::int64_t received = 0;
  for (std::size_t r = 0; r < ranks; ++r) {
    if (r == me || sizes[r] == 0)
      continue;
    from[r].resize(static_cast<std::size_t>(sizes[r]));
    for (std::int64_t at = 0; at < sizes[r]; at += piece) {
      requests.emplace_back();
      MPI_Irecv(from[r].data() + at, static_cast<int>(std::min(piece, sizes[r] - at)), MPI_INT64_T,
                static_cast<int>(r), tag, comm_, &requests.back());
    }
    received += sizes[r];
  }
  const auto messages = static_cast<std::int64_t>(requests.size());
  for (std::size_t r = 0; r < ranks; ++r) {
    const auto n = static_cast<std::int64_t>(to[r].size());
    if (r == me || n == 0)
      continue;
    for (std::int64_t at = 0; at < n; at += piece) {
      requests.emplace_back();
      MPI_Isend(to[r].data() + at, static_cast<int>(std::min(piece, n - at)), MPI_INT64_T,
                static_cast<int>(r), tag, comm_, &requests.back());
    }
  }
  std::vector<MPI_Status> statuses(requests.size());
  MPI_Waitall(static_cast<int>(requests.size()), requests.data(), statuses.data());
  detail::countMessages(static_cast<std::int64_t>(sizeof(std::int64_t)) * received, messages);
  // (a message longer than its receive is an MPI error already; a shorter one is caught here)
  std::size_t k = 0;
  for (std::size_t r = 0; r < ranks; ++r) {
    if (r == me || sizes[r] == 0)
      continue;
    std::int64_t got = 0;
    for (std::int64_t at = 0; at < sizes[r]; at += piece, ++k) {
      int count = 0;
      MPI_Get_count(&statuses[k], MPI_INT64_T, &count);
      got += count;
    }
    if (got != sizes[r])
      throw std::logic_error("exchange: " + std::to_string(got) + " values from process " +
                             std::to_string(r) + ", " + std::to_string(sizes[r]) + " expected");
  }
  return from;
}

} // namespace mesopen::parallel
