// The communicators on one process: every operation gives back this process's values unchanged
// (the solver's one-process results depend on it), and a gather MPI_Allgatherv cannot address is
// refused.
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
  const std::vector<double> sums = one.sumInOrder(values);
  ASSERT_EQ(sums.size(), values.size());
  EXPECT_TRUE(std::signbit(sums[1])); // not 0.0 + -0.0
  EXPECT_EQ(one.min(2.5), 2.5);
}

} // namespace

TEST(Communicator, SerialGivesBackItsInput) { expectUnchanged(parallel::serial()); }

TEST(Communicator, MpiOnOneProcessGivesBackItsInput) {
  parallel::ensureMpi();
  expectUnchanged(parallel::MpiCommunicator(MPI_COMM_SELF));
}

TEST(Communicator, GatherPastIntMaxBytesIsRefused) {
  parallel::ensureMpi();
  EXPECT_NO_THROW(parallel::detail::gatherLayout(INT_MAX, MPI_COMM_SELF));
  EXPECT_THROW(parallel::detail::gatherLayout(std::int64_t{INT_MAX} + 1, MPI_COMM_SELF),
               std::length_error);
}
