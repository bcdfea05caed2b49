// Zoltan's recursive coordinate bisection (RCB) over the processes of an MPI communicator: the
// box of all items' points is cut in two at the weighted median across its longer side, and each
// half again, until there is one part per process. The same items, on the same processes, give
// the same parts. The only place that calls Zoltan.
#pragma once

#include "partitioner.hpp"

#include <mpi.h>

struct Zoltan_Struct;

namespace mesopen::parallel {

class ZoltanRcb final : public Partitioner {
public:
  explicit ZoltanRcb(MPI_Comm comm); // MPI initialised
  ~ZoltanRcb() override;
  ZoltanRcb(const ZoltanRcb &) = delete;
  ZoltanRcb &operator=(const ZoltanRcb &) = delete;
  // Fewer than two items in all (which Zoltan's RCB refuses on the processes left without one):
  // each stays where it is. Throws std::runtime_error on every process if Zoltan reports an error
  // on any (its errors are not always on every process).
  std::vector<int> partition(const PartitionItems &mine) const override;

private:
  MPI_Comm comm_;
  Zoltan_Struct *zoltan_ = nullptr;
};

} // namespace mesopen::parallel
