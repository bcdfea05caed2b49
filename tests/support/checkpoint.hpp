// Helpers for the tests of checkpoints (run/checkpoint.hpp): a run stopped after a given step as
// by SIGTERM, continued with --resume, and the bytes of the files compared.
#pragma once

#include "run.hpp"

#include <cstdlib>
#include <string>

namespace mesopen::test {

// `mesopen run SCENE -o OUT` stopped after step `stop` as by SIGTERM (MESOPEN_STOP_AT_STEP), on
// `threads` threads.
inline Result runStoppedAt(const std::string &scene, const std::string &out, long stop,
                           int threads) {
  ::setenv("MESOPEN_STOP_AT_STEP", std::to_string(stop).c_str(), 1);
  const Result r =
      runMesopen("run " + scene + " -o " + out + " --quiet --threads " + std::to_string(threads));
  ::unsetenv("MESOPEN_STOP_AT_STEP");
  return r;
}

inline Result runScene(const std::string &scene, const std::string &out, int threads) {
  return runMesopen("run " + scene + " -o " + out + " --quiet --threads " +
                    std::to_string(threads));
}

inline Result resume(const std::string &out, int threads) {
  return runMesopen("run --resume " + out + " --quiet --threads " + std::to_string(threads));
}

// The two files hold the same bytes (and the first is not empty).
inline bool sameBytes(const std::string &a, const std::string &b) {
  const std::string x = readFile(a), y = readFile(b);
  return !x.empty() && x == y;
}

// Whether two run.h5 files hold the same run, every dataset and attribute bit for bit, but for the
// checkpoint keys in the composed scene (tests/support/same_run.py). Files of runs with different
// checkpoint keys cannot be the same bytes: the scene they record differs.
inline bool sameRun(const std::string &a, const std::string &b) {
  const Result r = runCommand("/usr/bin/python3 " + std::string(MESOPEN_SOURCE_DIR) +
                              "/tests/support/same_run.py " + a + " " + b);
  if (r.code != 0)
    std::fprintf(stderr, "%s", r.output.c_str());
  return r.code == 0;
}

} // namespace mesopen::test
