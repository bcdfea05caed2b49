// A small RAII layer over the HDF5 C API for the project's output files (target.h5, run.h5).
// Files are reproducible: the same calls with the same data give byte-identical files (no
// object time stamps, fixed file-format version, contiguous datasets). Every failure throws
// std::runtime_error naming the file and the object; HDF5's own error printing is silenced.
#pragma once

#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace mesopen {

class H5Recorder;

// Element types stored: float64, int32, int64, uint8, uint32, uint64 (little-endian in the file).
template <class T>
concept H5Number = std::same_as<T, double> || std::same_as<T, int> ||
    std::same_as<T, std::int64_t> || std::same_as<T, std::uint8_t> ||
    std::same_as<T, std::uint32_t> || std::same_as<T, std::uint64_t>;

class H5File {
public:
  enum class Type { f64, i32, i64, u8, u32, u64 };

  // New file (an existing one is replaced), open for writing.
  static H5File create(const std::string &path);
  // Existing file, read-only unless `writable`.
  static H5File open(const std::string &path, bool writable = false);

  H5File(H5File &&other) noexcept;
  H5File &operator=(H5File &&other) noexcept;
  H5File(const H5File &) = delete;
  H5File &operator=(const H5File &) = delete;
  ~H5File(); // closes quietly; call close() to see errors

  // Flushes and closes the file; throws on failure. Idempotent.
  void close();
  const std::string &path() const { return path_; }

  // Group or dataset by absolute name, e.g. "/mesh/x".
  bool exists(const std::string &name) const;
  // One new group; its parent must exist.
  void createGroup(const std::string &name);

  // 1-D dataset of data.size() elements.
  template <H5Number T> void write(const std::string &name, std::span<const T> data) {
    const std::uint64_t dims[1] = {data.size()};
    writeRaw(name, data.data(), typeOf<T>(), 1, dims);
  }
  template <H5Number T> void write(const std::string &name, const std::vector<T> &data) {
    write(name, std::span<const T>(data));
  }
  // 2-D dataset rows x cols from row-major data (size rows * cols).
  template <H5Number T>
  void write(const std::string &name, std::span<const T> data, std::size_t rows, std::size_t cols) {
    checkSize(name, data.size(), rows * cols);
    const std::uint64_t dims[2] = {rows, cols};
    writeRaw(name, data.data(), typeOf<T>(), 2, dims);
  }
  template <H5Number T>
  void write(const std::string &name, const std::vector<T> &data, std::size_t rows,
             std::size_t cols) {
    write(name, std::span<const T>(data), rows, cols);
  }

  // Scalar attribute of a group or dataset ("/" is the root group); replaces an existing one.
  template <H5Number T>
  void attribute(const std::string &object, const std::string &name, T value) {
    attributeRaw(object, name, &value, typeOf<T>());
  }
  void attribute(const std::string &object, const std::string &name, const std::string &value);

  // Dimensions of a dataset.
  std::vector<std::uint64_t> shape(const std::string &name) const;
  // The number of elements of a dataset, checked to be one the file can hold: at most 64 times its
  // size in bytes of `element_bytes` each (room for compression), so that a damaged or hostile
  // file declaring 2^40 elements is refused instead of allocated. Throws std::runtime_error.
  std::uint64_t elements(const std::string &name, std::size_t element_bytes) const;
  // All elements of a dataset (any rank, row-major), converted to T.
  template <H5Number T> std::vector<T> read(const std::string &name) const {
    const std::uint64_t n = elements(name, sizeof(T));
    std::vector<T> out(n);
    readRaw(name, out.data(), typeOf<T>(), n);
    return out;
  }

  bool hasAttribute(const std::string &object, const std::string &name) const;
  template <H5Number T> T readAttribute(const std::string &object, const std::string &name) const {
    T value{};
    readAttributeRaw(object, name, &value, typeOf<T>());
    return value;
  }
  std::string readStringAttribute(const std::string &object, const std::string &name) const;

  // Every later call that changes the file (a group, a dataset, an attribute) is also told to
  // `recorder`, after it succeeded, until another (or null) is set: a journal of them made again
  // on another file writes what they wrote (h5_journal.hpp).
  void record(H5Recorder *recorder) { recorder_ = recorder; }

private:
  friend class H5Journal; // makes recorded calls again
  H5File(std::string path, std::int64_t id) : path_(std::move(path)), id_(id) {}

  template <H5Number T> static constexpr Type typeOf() {
    if constexpr (std::same_as<T, double>)
      return Type::f64;
    else if constexpr (std::same_as<T, int>)
      return Type::i32;
    else if constexpr (std::same_as<T, std::int64_t>)
      return Type::i64;
    else if constexpr (std::same_as<T, std::uint8_t>)
      return Type::u8;
    else if constexpr (std::same_as<T, std::uint32_t>)
      return Type::u32;
    else
      return Type::u64;
  }

  void checkSize(const std::string &name, std::size_t have, std::size_t want) const;
  void writeRaw(const std::string &name, const void *data, Type type, int rank,
                const std::uint64_t *dims);
  void attributeRaw(const std::string &object, const std::string &name, const void *value,
                    Type type);
  void readRaw(const std::string &name, void *data, Type type, std::uint64_t count) const;
  void readAttributeRaw(const std::string &object, const std::string &name, void *value,
                        Type type) const;

  std::string path_;
  std::int64_t id_ = -1; // hid_t
  H5Recorder *recorder_ = nullptr;
};

// Told of the calls that change a file, as H5File makes them (H5File::record).
class H5Recorder {
public:
  virtual ~H5Recorder() = default;
  virtual void group(const std::string &name) = 0;
  // `data` holds the product of the `rank` dims values of `type`.
  virtual void dataset(const std::string &name, const void *data, H5File::Type type, int rank,
                       const std::uint64_t *dims) = 0;
  virtual void attribute(const std::string &object, const std::string &name, const void *value,
                         H5File::Type type) = 0;
  virtual void attribute(const std::string &object, const std::string &name,
                         const std::string &value) = 0;
};

} // namespace mesopen
