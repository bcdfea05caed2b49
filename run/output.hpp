// What the commands share about their output: the directory made before any work and cleared of
// an earlier run's files, a lock against a second writer, JSON written whole, wall times.
#pragma once

#include "atomic_file.hpp"
#include "scene.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <sys/file.h>
#include <system_error>
#include <unistd.h>

namespace mesopen {

using Clock = std::chrono::steady_clock;
inline double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

inline void writeJson(const std::string &path, const nlohmann::json &j) {
  writeText(path, j.dump(2) + "\n");
}

// Creates `dir` and removes the files an earlier run left there (`stale`, relative to `dir`; a
// name ending in `*` removes every file it begins), so that no old figures sit beside new data.
// A directory whose summary.json another command wrote is refused (`command`: the one writing
// now; empty: no check), so that one command's output never overwrites another's. Throws
// InputError when the directory cannot be made or is refused.
inline void prepareOutputDirectory(const std::string &dir, const std::string &command,
                                   std::initializer_list<std::string> stale) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path summary = fs::path(dir) / "summary.json";
  if (!command.empty() && fs::is_regular_file(summary, ec)) {
    std::ifstream in(summary);
    const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    if (!j.is_discarded() && j.is_object() && j.contains("command") && j["command"].is_string() &&
        j["command"] != command)
      throw InputError(dir + ": holds the output of `mesopen " + j["command"].get<std::string>() +
                       "` (its summary.json); allowed: a new directory, or one `mesopen " +
                       command + "` wrote");
  }
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw InputError(dir + ": cannot create the output directory" +
                     (ec ? " (" + ec.message() + ")" : std::string(" (a file has that name)")));
  for (const std::string &file : stale) {
    if (!file.ends_with('*')) {
      fs::remove(fs::path(dir) / file, ec);
      continue;
    }
    const std::string prefix = file.substr(0, file.size() - 1);
    for (const auto &entry : fs::directory_iterator(dir, ec))
      if (entry.path().filename().string().starts_with(prefix))
        fs::remove(entry.path(), ec);
  }
}

// Takes the lock file `path` (flock, exclusive, without waiting) for as long as the process lives,
// so that a second command cannot write into a directory in use; `inherited`: the programs it
// starts hold it too. False when another process holds it; true when the file cannot be opened
// (the directory's own errors are reported when it is written).
inline bool lockForProcess(const std::string &path, bool inherited) {
  const int fd = open(path.c_str(), O_RDWR | O_CREAT | (inherited ? 0 : O_CLOEXEC), 0644);
  if (fd < 0 || flock(fd, LOCK_EX | LOCK_NB) == 0)
    return true;
  close(fd);
  return false;
}

} // namespace mesopen
