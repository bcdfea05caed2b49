// Helpers for tests that run the program: a fresh scratch directory and a command's exit code
// and output.
#pragma once

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace mesopen::test {

// A directory of its own under the system's temporary directory, removed at the end.
struct ScratchDir {
  std::filesystem::path path;
  explicit ScratchDir(const std::string &name) {
    path = std::filesystem::temp_directory_path() /
           ("mesopen-test-" + name + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~ScratchDir() { std::filesystem::remove_all(path); }
  std::string operator/(const std::string &file) const { return (path / file).string(); }
};

struct Result {
  int code;
  std::string output; // stdout and stderr together
};

// Run a shell command and return its exit code and output.
inline Result runCommand(const std::string &command) {
  const std::string cmd = command + " 2>&1";
  Result r{-1, {}};
  FILE *pipe = ::popen(cmd.c_str(), "r");
  if (!pipe)
    return r;
  char buffer[4096];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0)
    r.output.append(buffer, n);
  const int status = ::pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// Run `mesopen ARGS` and return its exit code and output.
inline Result runMesopen(const std::string &args) {
  return runCommand(std::string(MESOPEN_BINARY) + " " + args);
}

// A 0.6 x 0.3 mm target of 60 um grains and a 0.3 mm projectile, 20 ns; `run` ends the [run]
// table.
inline std::string tinyScene(const std::string &run = "frame_interval = 1e-8\n") {
  return "[target]\nwidth = 0.6e-3\nheight = 0.3e-3\ndiameter = 60e-6\nmesh_size = 15e-6\n"
         "[projectile]\nlength = 0.3e-3\n[run]\nend_time = 2e-8\n" +
         run;
}

inline std::string readFile(const std::string &path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void writeFile(const std::string &path, const std::string &text) {
  std::ofstream(path) << text;
}

// `mesopen run` on `scene`, written to DIR/scene.toml, with its output in DIR/out.
inline Result runScene(const ScratchDir &dir, const std::string &scene) {
  writeFile(dir / "scene.toml", scene);
  return runMesopen("run " + (dir / "scene.toml") + " -o " + (dir / "out") + " --quiet");
}

} // namespace mesopen::test
