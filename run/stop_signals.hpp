// SIGINT and SIGTERM as requests to stop: the first is noted (stopSignal) for the command to end
// cleanly at its next check, with its files whole and status "interrupted"; a second ends the
// process at once (the default action, restored by the first).
#pragma once

#include <stdexcept>
#include <string>

namespace mesopen {

namespace parallel {
struct World;
}

void catchStopSignals(bool on); // on: note the signals (and forget an earlier one); off: default
int stopSignal();               // the signal noted, 0 if none
void setStopSignal(int signal); // as if `signal` had been received (0: none)
std::string stopSignalName();   // "SIGINT" or "SIGTERM"

// A signal received during a run's set-up, found between its phases.
struct Interrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// Throws Interrupted ("SIGINT during the <phase>") when a signal has been received on any rank of
// `world`: every rank ends at the same phase (mpirun passes the signal to each, not at the same
// moment).
void stopIfAsked(const parallel::World &world, const std::string &phase);

} // namespace mesopen
