#include "stop_signals.hpp"

#include "liggghts_dem.hpp"

#include <csignal>

namespace mesopen {

namespace {

volatile std::sig_atomic_t stop_signal = 0;

extern "C" void requestStop(int signal) {
  stop_signal = signal;
  std::signal(signal, SIG_DFL);
}

} // namespace

void catchStopSignals(bool on) {
  if (on)
    stop_signal = 0;
  if (on || stop_signal == 0)
    for (int s : {SIGINT, SIGTERM})
      std::signal(s, on ? requestStop : SIG_DFL);
}

int stopSignal() { return stop_signal; }

void setStopSignal(int signal) { stop_signal = signal; }

std::string stopSignalName() { return stop_signal == SIGINT ? "SIGINT" : "SIGTERM"; }

void stopIfAsked(const parallel::World &world, const std::string &phase) {
  const double s = world.size > 1 ? world.max(stopSignal()) : stopSignal();
  if (s != 0) {
    setStopSignal(static_cast<int>(s));
    throw Interrupted(stopSignalName() + " during the " + phase);
  }
}

} // namespace mesopen
