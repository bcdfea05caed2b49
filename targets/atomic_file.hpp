// Whole-or-absent output files: write beside the destination under `path + ".tmp"`, then
// rename onto the destination (atomic within one file system).
#pragma once

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>

namespace mesopen {

// Calls write(temp_path) and renames the temporary file onto `path`. When `write` or the rename
// throws, the temporary file is removed and the exception passed on; `path` is left untouched.
template <class Write> void writeAtomically(const std::string &path, Write &&write) {
  const std::string temp = path + ".tmp";
  try {
    std::forward<Write>(write)(temp);
    std::filesystem::rename(temp, path);
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
    throw;
  }
}

// The whole of `text` as the file `path`, written atomically.
inline void writeText(const std::string &path, const std::string &text) {
  writeAtomically(path, [&](const std::string &temp) {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out)
      throw std::runtime_error("cannot create '" + temp + "': " + std::strerror(errno));
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.close();
    if (!out)
      throw std::runtime_error("cannot write '" + temp + "'");
  });
}

} // namespace mesopen
