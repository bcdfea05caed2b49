// What the commands share about their output: the directory made before any work and cleared of
// an earlier run's files, JSON written whole, wall times.
#pragma once

#include "atomic_file.hpp"
#include "scene.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <system_error>

namespace mesopen {

using Clock = std::chrono::steady_clock;
inline double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

inline void writeJson(const std::string &path, const nlohmann::json &j) {
  writeText(path, j.dump(2) + "\n");
}

// Creates `dir` and removes the files an earlier run left there (`stale`, relative to `dir`), so
// that no old figures sit beside new data. Throws InputError when the directory cannot be made.
inline void prepareOutputDirectory(const std::string &dir,
                                   std::initializer_list<std::string> stale) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw InputError(dir + ": cannot create the output directory" +
                     (ec ? " (" + ec.message() + ")" : std::string(" (a file has that name)")));
  for (const auto &file : stale)
    fs::remove(fs::path(dir) / file, ec);
}

} // namespace mesopen
