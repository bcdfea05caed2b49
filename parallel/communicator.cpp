#include "communicator.hpp"

namespace mesopen::parallel {

const Communicator &serial() {
  static const SerialCommunicator one;
  return one;
}

} // namespace mesopen::parallel
