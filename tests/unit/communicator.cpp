// The communicators on one process: every operation gives back this process's values unchanged
// (the solver's one-process results depend on it) and counts no traffic, a gather MPI_Allgatherv
// cannot address is refused, and the traffic counter counts past 32 bits.
#include "communicator.hpp"
#include "mpi_communicator.hpp"

#include <gtest/gtest.h>

#include <climits>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

using namespace mesopen;

namespace {

void expectUnchanged(const parallel::Communicator &one) {
  EXPECT_EQ(one.rank(), 0);
  EXPECT_EQ(one.size(), 1);
  const std::vector<double> values{1.5, -0.0, 3e300};
  EXPECT_EQ(one.allGather(values), values);
  const std::vector<std::int64_t> indices{0, 7, std::int64_t{1} << 40};
  EXPECT_EQ(one.allGather(indices), indices);
  EXPECT_EQ(one.allGather(values, {3}), values);
  EXPECT_EQ(one.allGather(indices, {3}), indices);
  const std::vector<double> sums = one.sumInOrder(values);
  ASSERT_EQ(sums.size(), values.size());
  EXPECT_TRUE(std::signbit(sums[1])); // not 0.0 + -0.0
  EXPECT_EQ(one.min(2.5), 2.5);
  EXPECT_EQ(one.max(values), values);
  const std::vector<std::vector<std::int64_t>> lists{indices};
  EXPECT_EQ(one.exchange(lists), lists);
  EXPECT_EQ(one.exchange(lists, {3}), lists);
  // share and collect: one process holds every value already, neither callback is called
  bool called = false;
  one.share(
      3, [&](double *) { called = true; }, [&](const double *) { called = true; });
  one.collect(
      3, [&](double *) { called = true; }, [&](int, const double *) { called = true; });
  EXPECT_FALSE(called);
}

} // namespace

TEST(Communicator, SerialGivesBackItsInput) { expectUnchanged(parallel::serial()); }

TEST(Communicator, MpiOnOneProcessGivesBackItsInput) {
  parallel::ensureMpi();
  const parallel::Traffic before = parallel::traffic();
  expectUnchanged(parallel::MpiCommunicator(MPI_COMM_SELF));
  EXPECT_EQ(parallel::allReduce(2.5, MPI_MAX, MPI_COMM_SELF), 2.5);
  EXPECT_EQ(parallel::gatherItems(std::vector<int>{1, 2}, 0, MPI_COMM_SELF),
            (std::vector<int>{1, 2}));
  EXPECT_EQ(parallel::traffic().bytes, before.bytes);
  EXPECT_EQ(parallel::traffic().operations, before.operations);
}

// The counts are 64-bit: 9 GiB, past what 32 bits hold, counted exactly.
TEST(Communicator, TrafficCountsPast32Bits) {
  const parallel::Traffic before = parallel::traffic();
  for (int k = 0; k < 3; ++k)
    parallel::detail::countReceived(std::int64_t{3} << 30);
  EXPECT_EQ(parallel::traffic().bytes - before.bytes, std::int64_t{9} << 30);
  EXPECT_EQ(parallel::traffic().operations - before.operations, 3);
}

// An all-gather (every rank's parts on every rank, MPI_Allgatherv's int offsets) of more than
// INT_MAX bytes is refused; the gathers to one rank (gatherItems, collect) go in pieces.
TEST(Communicator, AllGatherPastIntMaxBytesIsRefused) {
  parallel::ensureMpi();
  EXPECT_NO_THROW(parallel::detail::gatherLayout(INT_MAX, MPI_COMM_SELF));
  EXPECT_THROW(parallel::detail::gatherLayout(std::int64_t{INT_MAX} + 1, MPI_COMM_SELF),
               std::length_error);
}
