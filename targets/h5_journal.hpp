// A journal of the calls that changed an HDF5 file (H5File::record): each group, dataset and
// attribute in order, with its data, in a file of its own. Made again on another file in the
// same state (the same calls before), they write the same bytes: H5File's files are
// reproducible. A run's checkpoints keep run.h5's frames this way (run/checkpoint.hpp).
// Format: "mesopen-h5-journal 1\n", then records, each a kind byte (1 group, 2 dataset,
// 3 numeric attribute, 4 string attribute) and its fields (strings as a u64 length and bytes,
// numbers little-endian: a dataset's type byte, rank byte, dims and values; an attribute's type
// byte and value), then a kind byte 0 when the journal was closed whole.
#pragma once

#include "h5file.hpp"

#include <cstdio>
#include <string>

namespace mesopen {

class H5Journal final : public H5Recorder {
public:
  // A new journal at `path` (an existing file is replaced). Throws std::runtime_error.
  explicit H5Journal(const std::string &path);
  H5Journal(const H5Journal &) = delete;
  H5Journal &operator=(const H5Journal &) = delete;
  ~H5Journal() override; // closes quietly, unmarked: replay refuses it

  void group(const std::string &name) override;
  void dataset(const std::string &name, const void *data, H5File::Type type, int rank,
               const std::uint64_t *dims) override;
  void attribute(const std::string &object, const std::string &name, const void *value,
                 H5File::Type type) override;
  void attribute(const std::string &object, const std::string &name,
                 const std::string &value) override;

  // Marks the journal whole, writes it to the disk (fsync) and closes it. Throws
  // std::runtime_error when a write failed (also an earlier one).
  void close();
  const std::string &path() const { return path_; }

  // Makes the calls of the journal at `path`, in order, on `file`. Throws std::runtime_error for
  // a journal that cannot be read, is damaged or was not closed whole.
  static void replay(const std::string &path, H5File &file);

private:
  void put(const void *bytes, std::size_t n);
  void putString(const std::string &s);
  std::string path_;
  std::FILE *out_ = nullptr;
  bool failed_ = false;
};

} // namespace mesopen
