#include "command_log.hpp"

#include "atomic_file.hpp"
#include "version.hpp"

#include <omp.h>

#include <cstdio>
#include <ctime>
#include <fstream>
#include <sstream>
#include <unistd.h>

namespace mesopen {

CommandLog::CommandLog(const std::string &dir, const std::string &command_line, bool append)
    : path_(dir + "/mesopen.log") {
  if (append) {
    std::ifstream before(path_, std::ios::binary);
    std::ostringstream text;
    text << before.rdbuf();
    text_ = text.str();
    if (!text_.empty() && text_.back() != '\n')
      text_ += '\n';
  }
  char host[256] = "unknown";
  gethostname(host, sizeof host - 1);
  const std::time_t now = std::time(nullptr);
  char when[32];
  std::strftime(when, sizeof when, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  text_ += std::string("mesopen ") + programVersion() + "\ncommand: " + command_line +
           "\nhost: " + host + ", " + std::to_string(omp_get_max_threads()) +
           " threads\nstarted: " + when + "\n";
  writeText(path_, text_);
}

void CommandLog::line(const std::string &text) {
  if (!on())
    return;
  char stamp[32];
  std::snprintf(stamp, sizeof stamp, "[%10.3f s] ", secondsSince(start_));
  text_ += stamp + text + "\n";
  writeText(path_, text_);
}

void CommandLog::lastLine(const std::string &text) noexcept {
  try {
    line(text);
  } catch (const std::exception &) {
  }
}

std::string shellWords(int argc, const char *const *argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) {
    const std::string word = argv[i];
    const bool plain = !word.empty() &&
                       word.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                              "0123456789-_./=,:+@%") == std::string::npos;
    std::string quoted = "'";
    for (char c : word)
      quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    line += (i ? " " : "") + (plain ? word : quoted + "'");
  }
  return line;
}

} // namespace mesopen
