#include "communicator.hpp"
#include "partitioner.hpp"

namespace mesopen::parallel {

const Communicator &serial() {
  static const SerialCommunicator one;
  return one;
}

const Partitioner &serialPartitioner() {
  static const SerialPartitioner one;
  return one;
}

} // namespace mesopen::parallel
