// A command's log, DIR/mesopen.log: what ran (program version, command line, host, threads, the
// start in UTC), then one line per event (progress, warnings, the end) with the wall seconds since
// the start. The file is rewritten whole under a temporary name at every line, so that it is
// always whole and holds every line written so far.
#pragma once

#include "output.hpp"

#include <string>

namespace mesopen {

class CommandLog {
public:
  CommandLog() = default; // writes nothing (the ranks but 0, the tests)
  // Starts DIR/mesopen.log with the program's version, `command_line`, the host, the threads and
  // the time now; `append`: after what the file holds (a run resumed).
  CommandLog(const std::string &dir, const std::string &command_line, bool append = false);
  bool on() const { return !path_.empty(); }
  // Appends "[    12.345 s] text" and writes the file. Throws std::runtime_error when it cannot.
  void line(const std::string &text);
  // The same at a command's end, where a log that cannot be written must not change how the
  // command ended (its message on stderr says what happened): a failure to write is ignored.
  void lastLine(const std::string &text) noexcept;

private:
  std::string path_, text_;
  Clock::time_point start_ = Clock::now();
};

// The words as a shell reads them back: quoted where they hold anything but letters, digits and
// -_./=,:+@%.
std::string shellWords(int argc, const char *const *argv);

} // namespace mesopen
