#include "communicator.hpp"
#include "partitioner.hpp"

#include <bit>

namespace mesopen::parallel {

const Communicator &serial() {
  static const SerialCommunicator one;
  return one;
}

void moveValues(const Communicator &processes, std::size_t items,
                const std::function<int(std::size_t)> &from,
                const std::function<int(std::size_t)> &to,
                const std::function<std::size_t(std::size_t)> &count,
                const std::function<void(std::size_t, double *)> &pack,
                const std::function<void(std::size_t, const double *)> &unpack) {
  const int me = processes.rank();
  const auto ranks = static_cast<std::size_t>(processes.size());
  std::vector<std::vector<std::int64_t>> out(ranks);
  std::vector<std::int64_t> sizes(ranks, 0);
  std::vector<double> values;
  for (std::size_t k = 0; k < items; ++k) {
    const int sender = from(k), receiver = to(k);
    if (sender == receiver)
      continue;
    if (sender == me) {
      values.resize(count(k));
      pack(k, values.data());
      for (const double v : values)
        out[static_cast<std::size_t>(receiver)].push_back(std::bit_cast<std::int64_t>(v));
    }
    if (receiver == me)
      sizes[static_cast<std::size_t>(sender)] += static_cast<std::int64_t>(count(k));
  }
  const std::vector<std::vector<std::int64_t>> in = processes.exchange(std::move(out), sizes);
  std::vector<std::size_t> at(ranks, 0);
  for (std::size_t k = 0; k < items; ++k) {
    const int sender = from(k), receiver = to(k);
    if (sender == receiver || receiver != me)
      continue;
    const auto r = static_cast<std::size_t>(sender);
    values.resize(count(k));
    for (double &v : values)
      v = std::bit_cast<double>(in[r][at[r]++]);
    unpack(k, values.data());
  }
}

const Partitioner &serialPartitioner() {
  static const SerialPartitioner one;
  return one;
}

} // namespace mesopen::parallel
