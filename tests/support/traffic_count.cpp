// The byte counter of the communication layer (parallel::traffic) on every process of mpirun:
// each operation, on parts of known sizes (equal or not, empty on some ranks), must add exactly the
// bytes the other processes' parts hold (and the 8-byte size each sends first where the parts may
// differ), and one operation per MPI call; the data must arrive too, so that the counts are those
// of real parts. A gather to rank 0 counts its parts there alone. Prints what failed and exits 1.
#include "mpi_communicator.hpp"

#include <mpi.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

using namespace mesopen::parallel;

namespace {

int failures = 0, rank = 0, size = 1;

// The counter's change across `operation` against the bytes and MPI calls expected.
// (and `messages` point-to-point messages received, unless -1)
template <class F>
void expectTraffic(const std::string &what, std::int64_t bytes, std::int64_t operations,
                   F &&operation, std::int64_t messages = -1) {
  const Traffic before = traffic();
  const bool data_ok = operation();
  const Traffic after = traffic();
  const std::int64_t got = after.bytes - before.bytes, calls = after.operations - before.operations;
  const std::int64_t received = after.messages - before.messages;
  if (got != bytes || calls != operations || !data_ok || (messages >= 0 && received != messages)) {
    std::printf("rank %d of %d: %s: %lld bytes in %lld operations and %lld messages, expected %lld "
                "in %lld and %lld%s\n",
                rank, size, what.c_str(), static_cast<long long>(got),
                static_cast<long long>(calls), static_cast<long long>(received),
                static_cast<long long>(bytes), static_cast<long long>(operations),
                static_cast<long long>(messages), data_ok ? "" : "; the data gathered are wrong");
    ++failures;
  }
}

struct Item { // 24 bytes of plain data
  std::int64_t id;
  double x, y;
};

} // namespace

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const std::int64_t others = size - 1, sizes = 8 * others; // the parts' byte counts, 8 bytes each
  {
    const MpiCommunicator comm(MPI_COMM_WORLD);
    // k doubles from every rank: 8 k from each other rank.
    for (const std::int64_t k : {0, 1, 1000, 12345}) {
      expectTraffic(
          "all-gather of " + std::to_string(k) + " doubles", 8 * k * others + sizes, 2, [&] {
            const std::vector<double> all = comm.allGather(std::vector<double>(k, rank + 0.5));
            bool ok = static_cast<std::int64_t>(all.size()) == k * size;
            for (std::size_t i = 0; ok && i < all.size(); ++i)
              ok = all[i] == static_cast<double>(i / k) + 0.5;
            return ok;
          });
    }
    // rank r sends 3 r + 1 64-bit integers: all but its own.
    std::int64_t total = 0;
    for (int r = 0; r < size; ++r)
      total += 3 * r + 1;
    expectTraffic("all-gather of unequal 64-bit parts", 8 * (total - (3 * rank + 1)) + sizes, 2,
                  [&] {
                    const std::vector<std::int64_t> all =
                        comm.allGather(std::vector<std::int64_t>(3 * rank + 1, rank));
                    return static_cast<std::int64_t>(all.size()) == total && all.back() == size - 1;
                  });
    // the same with the sizes known: one call, no sizes
    std::vector<std::int64_t> known(static_cast<std::size_t>(size));
    for (int r = 0; r < size; ++r)
      known[static_cast<std::size_t>(r)] = 3 * r + 1;
    expectTraffic("all-gather of unequal 64-bit parts, the sizes known",
                  8 * (total - (3 * rank + 1)), 1, [&] {
                    const std::vector<std::int64_t> all =
                        comm.allGather(std::vector<std::int64_t>(3 * rank + 1, rank), known);
                    return static_cast<std::int64_t>(all.size()) == total && all.back() == size - 1;
                  });
    expectTraffic("all-gather of 2 doubles from every rank, the sizes known", 16 * others, 1, [&] {
      const std::vector<double> all =
          comm.allGather(std::vector<double>{1.0 * rank, 2.0}, std::vector<std::int64_t>(size, 2));
      return static_cast<int>(all.size()) == 2 * size && all[2 * (size - 1)] == size - 1.0;
    });
    // sums in order: an all-gather of the values (as many from every rank: one call); the least
    // value: one reduction.
    expectTraffic("sums of 7 doubles in rank order", 8 * 7 * others, 1, [&] {
      const std::vector<double> sums = comm.sumInOrder(std::vector<double>(7, 1.0));
      return sums.size() == 7 && sums[6] == size;
    });
    expectTraffic("least of one double", 8 * others, 1,
                  [&] { return comm.min(10.0 - rank) == 10.0 - (size - 1); });
    expectTraffic("largest of 5 doubles, element by element", 8 * 5 * others, 1, [&] {
      const std::vector<double> most = comm.max({-1.0 * rank, 1.0 * rank, 0.0, 2.0, -3.0});
      return most == std::vector<double>{0.0, size - 1.0, 0.0, 2.0, -3.0};
    });
    // share: rank r holds 2 r values (rank 0 none).
    std::int64_t shared = 0;
    for (int r = 0; r < size; ++r)
      shared += 2 * r;
    expectTraffic("share of 2 r values from rank r", 8 * (shared - 2 * rank) + sizes, 2, [&] {
      bool ok = true;
      comm.share(
          static_cast<std::size_t>(2 * rank),
          [&](double *mine) {
            for (int i = 0; i < 2 * rank; ++i)
              mine[i] = rank;
          },
          [&](const double *all) { ok = shared == 0 || all[shared - 1] == size - 1; });
      return ok;
    });
    // collect: the same values to rank 0 alone, rank by rank (the counts gathered to rank 0, one
    // collective call; the values as messages).
    expectTraffic("collect of 2 r values from rank r to rank 0",
                  rank == 0 ? 8 * shared + 8 * (size - 1) : 0, 1, [&] {
                    bool ok = true;
                    int unpacked = 0;
                    comm.collect(
                        static_cast<std::size_t>(2 * rank),
                        [&](double *mine) {
                          for (int i = 0; i < 2 * rank; ++i)
                            mine[i] = rank;
                        },
                        [&](int r, const double *values) {
                          ok = ok && r == ++unpacked && values[0] == r && values[2 * r - 1] == r;
                        });
                    return ok && unpacked == (rank == 0 ? size - 1 : 0);
                  });
    // exchange: rank s sends rank q (q + 1) (s + 1) integers, none to the next rank up; a
    // message from every other rank, its length with it (no collective call, no size counted);
    // with the sizes known, the messages to the lists that are not empty.
    auto sent = [&](int s, int q) {
      return q == (s + 1) % size && size > 2 ? 0 : (q + 1) * (s + 1);
    };
    std::int64_t from_others = 0;
    std::vector<std::int64_t> sizes(static_cast<std::size_t>(size));
    for (int s = 0; s < size; ++s) {
      sizes[static_cast<std::size_t>(s)] = sent(s, rank);
      if (s != rank)
        from_others += sent(s, rank);
    }
    for (const bool known : {false, true})
      expectTraffic(std::string("exchange of (q + 1) (s + 1) integers from s to q") +
                        (known ? ", the sizes known" : ""),
                    8 * from_others, 0, [&] {
                      std::vector<std::vector<std::int64_t>> to(static_cast<std::size_t>(size));
                      for (int q = 0; q < size; ++q)
                        to[static_cast<std::size_t>(q)].assign(sent(rank, q), 1000 * rank + q);
                      const auto from = known ? comm.exchange(std::move(to), sizes)
                                              : comm.exchange(std::move(to));
                      bool ok = static_cast<int>(from.size()) == size;
                      for (int s = 0; ok && s < size; ++s) {
                        const auto &list = from[static_cast<std::size_t>(s)];
                        ok = static_cast<int>(list.size()) == sent(s, rank) &&
                             (list.empty() ||
                              (list.front() == 1000 * s + rank && list.back() == 1000 * s + rank));
                      }
                      return ok;
                    });
    // the same in messages of at most 3 values: lists of 0 to 7 values, exact multiples of 3
    // among them (a last, empty message ends those), with the sizes known and not
    const MpiCommunicator small(MPI_COMM_WORLD, 3);
    auto length = [](int s, int q) { return (7 * s + 3 * q) % 8; };
    std::int64_t in_pieces = 0, pieces_unknown = 0, pieces_known = 0;
    std::vector<std::int64_t> lengths(static_cast<std::size_t>(size));
    for (int s = 0; s < size; ++s) {
      lengths[static_cast<std::size_t>(s)] = length(s, rank);
      if (s != rank) {
        in_pieces += length(s, rank);
        pieces_unknown += length(s, rank) / 3 + 1; // (the last shorter than 3, maybe empty)
        pieces_known += (length(s, rank) + 2) / 3;
      }
    }
    for (const bool known : {false, true})
      expectTraffic(
          std::string("exchange of 0 to 7 integers in messages of 3") +
              (known ? ", the sizes known" : ""),
          8 * in_pieces, 0,
          [&] {
            std::vector<std::vector<std::int64_t>> to(static_cast<std::size_t>(size));
            for (int q = 0; q < size; ++q)
              for (int k = 0; k < length(rank, q); ++k)
                to[static_cast<std::size_t>(q)].push_back(1000 * rank + 10 * q + k);
            const auto from =
                known ? small.exchange(std::move(to), lengths) : small.exchange(std::move(to));
            bool ok = static_cast<int>(from.size()) == size;
            for (int s = 0; ok && s < size; ++s) {
              const auto &list = from[static_cast<std::size_t>(s)];
              ok = static_cast<int>(list.size()) == length(s, rank);
              for (std::size_t k = 0; ok && k < list.size(); ++k)
                ok = list[k] == 1000 * s + 10 * rank + static_cast<std::int64_t>(k);
            }
            return ok;
          },
          known ? pieces_known : pieces_unknown);
  }
  // The coupling's and the partitioner's operations.
  expectTraffic("all-gather of 5 items of 24 bytes", 24 * 5 * others + sizes, 2, [&] {
    const std::vector<Item> all =
        allGatherItems(std::vector<Item>(5, Item{rank, 1.0, 2.0}), MPI_COMM_WORLD);
    return static_cast<int>(all.size()) == 5 * size && all.back().id == size - 1;
  });
  // a gather to rank 0: the counts to it (one call), then the items as messages
  expectTraffic("gather of rank + 2 items of 24 bytes to rank 0",
                rank == 0 ? 24 * (others * (others + 1) / 2 + 2 * others) + 8 * others : 0, 1, [&] {
                  const std::vector<Item> all = gatherItems(
                      std::vector<Item>(rank + 2, Item{rank, 0.0, 0.0}), 0, MPI_COMM_WORLD);
                  return rank == 0 ? static_cast<std::int64_t>(all.size()) ==
                                         (size * (size - 1)) / 2 + 2 * size
                                   : all.empty();
                });
  // bytes sent in pieces (here of 7 bytes; 2^30 in the gathers) arrive whole and in order
  expectTraffic("100 bytes from every rank to rank 0 in pieces of 7", rank == 0 ? 100 * others : 0,
                0, [&] {
                  std::vector<unsigned char> bytes(100);
                  if (rank != 0) {
                    for (std::size_t i = 0; i < bytes.size(); ++i)
                      bytes[i] = static_cast<unsigned char>(rank + i);
                    detail::sendBytes(bytes.data(), 100, 0, MPI_COMM_WORLD, 7);
                    return true;
                  }
                  bool ok = true;
                  for (int r = 1; r < size; ++r) {
                    detail::receiveBytes(bytes.data(), 100, r, MPI_COMM_WORLD, 7);
                    for (std::size_t i = 0; i < bytes.size(); ++i)
                      ok = ok && bytes[i] == static_cast<unsigned char>(r + i);
                  }
                  return ok;
                });
  expectTraffic("reduction of a double", 8 * others, 1,
                [&] { return allReduce(double(rank), MPI_MAX, MPI_COMM_WORLD) == size - 1; });
  expectTraffic("reduction of an int", 4 * others, 1,
                [&] { return allReduce(rank, MPI_MIN, MPI_COMM_WORLD) == 0; });
  expectTraffic("reduction of an unsigned long", 8 * others, 1, [&] {
    return allReduce<unsigned long>(1, MPI_SUM, MPI_COMM_WORLD) == static_cast<unsigned long>(size);
  });
  const World w = world(true);
  expectTraffic("the world's sum", 8 * others, 1, [&] { return w.sum(1.0) == size; });
  expectTraffic("the world's barrier", 0, 1, [&] {
    w.barrier();
    return true;
  });
  // Within one process nothing is received and no operation counted.
  expectTraffic("all-gather within one process", 0, 0, [&] {
    return MpiCommunicator(MPI_COMM_SELF).allGather(std::vector<double>(100, 1.0)).size() == 100;
  });
  int any = 0;
  MPI_Allreduce(&failures, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  if (rank == 0)
    std::printf("traffic_count on %d processes: %s\n", size, any ? "FAILED" : "every count exact");
  MPI_Finalize();
  return any ? 1 : 0;
}
