// SIGINT and SIGTERM as requests to stop: the first is noted (stopSignal) for the command to end
// cleanly at its next check, with its files whole and status "interrupted"; a second ends the
// process at once (the default action, restored by the first).
#pragma once

#include <string>

namespace mesopen {

void catchStopSignals(bool on); // on: note the signals (and forget an earlier one); off: default
int stopSignal();               // the signal noted, 0 if none
void setStopSignal(int signal); // as if `signal` had been received (0: none)
std::string stopSignalName();   // "SIGINT" or "SIGTERM"

} // namespace mesopen
