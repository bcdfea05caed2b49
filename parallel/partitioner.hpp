// Which process owns which work item (an FE body): a partition of weighted points into one part
// per process, each part compact in space and of about the same weight. The solver asks for one
// and never asks how it is made: with one process nothing is partitioned (SerialPartitioner);
// with several, Zoltan's recursive coordinate bisection (ZoltanRcb, zoltan_partitioner.hpp).
#pragma once

#include <cstdint>
#include <vector>

namespace mesopen::parallel {

// The items one process owns now: a global id each (below 2^32), a point, and a weight (the work
// the item brings; zero for an item that brings none now).
struct PartitionItems {
  std::vector<std::uint32_t> id;
  std::vector<double> x, y, weight;
  std::size_t size() const { return id.size(); }
};

class Partitioner {
public:
  virtual ~Partitioner() = default;
  // Collective: every process passes the items it owns (together, every item once) and gets back
  // the rank each of its items is to go to, in their order.
  virtual std::vector<int> partition(const PartitionItems &mine) const = 0;
};

// One process: every item stays on rank 0.
class SerialPartitioner final : public Partitioner {
public:
  std::vector<int> partition(const PartitionItems &mine) const override {
    return std::vector<int>(mine.size(), 0);
  }
};

// The one serial partitioner (a solver's default).
const Partitioner &serialPartitioner();

} // namespace mesopen::parallel
