#include "h5_journal.hpp"

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <unistd.h>
#include <vector>

namespace mesopen {

namespace {

constexpr char magic[] = "mesopen-h5-journal 1\n";
enum Kind : std::uint8_t {
  end = 0,
  group_kind = 1,
  dataset_kind = 2,
  number_kind = 3,
  string_kind = 4
};

std::size_t typeBytes(H5File::Type type) {
  switch (type) {
  case H5File::Type::f64:
  case H5File::Type::i64:
  case H5File::Type::u64:
    return 8;
  case H5File::Type::i32:
  case H5File::Type::u32:
    return 4;
  case H5File::Type::u8:
    return 1;
  }
  return 0;
}

// Reads a journal: each value whole or the journal is damaged.
class Reader {
public:
  explicit Reader(const std::string &path) : path_(path), in_(std::fopen(path.c_str(), "rb")) {
    if (!in_)
      throw std::runtime_error("cannot open the journal '" + path + "': " + std::strerror(errno));
    std::error_code ec;
    size_ = std::filesystem::file_size(path, ec);
  }
  ~Reader() { std::fclose(in_); }
  void get(void *bytes, std::size_t n) {
    if (n > 0 && std::fread(bytes, 1, n, in_) != n)
      damaged("ends within a record");
  }
  template <class T> T get() {
    T v{};
    get(&v, sizeof v);
    return v;
  }
  // Checks that `n` bytes are left in the file: a damaged length is refused, not allocated.
  void left(std::uint64_t n) const {
    const long at = std::ftell(in_);
    if (at < 0 || static_cast<std::uint64_t>(at) > size_ ||
        n > size_ - static_cast<std::uint64_t>(at))
      damaged("holds a length past its end");
  }
  std::uint64_t length() {
    const auto n = get<std::uint64_t>();
    left(n);
    return n;
  }
  std::string getString() {
    std::string s(length(), '\0');
    get(s.data(), s.size());
    return s;
  }
  H5File::Type getType() {
    const auto t = get<std::uint8_t>();
    if (t > static_cast<std::uint8_t>(H5File::Type::u64))
      damaged("holds an unknown element type");
    return static_cast<H5File::Type>(t);
  }
  [[noreturn]] void damaged(const std::string &what) const {
    throw std::runtime_error("the journal '" + path_ + "' is damaged: it " + what);
  }

private:
  std::string path_;
  std::FILE *in_;
  std::uint64_t size_ = 0;
};

} // namespace

H5Journal::H5Journal(const std::string &path) : path_(path), out_(std::fopen(path.c_str(), "wb")) {
  if (!out_)
    throw std::runtime_error("cannot create the journal '" + path + "': " + std::strerror(errno));
  put(magic, sizeof magic - 1);
}

H5Journal::~H5Journal() {
  if (out_)
    std::fclose(out_);
}

void H5Journal::put(const void *bytes, std::size_t n) {
  if (out_ && n > 0 && std::fwrite(bytes, 1, n, out_) != n)
    failed_ = true;
}

void H5Journal::putString(const std::string &s) {
  const std::uint64_t n = s.size();
  put(&n, sizeof n);
  put(s.data(), s.size());
}

void H5Journal::group(const std::string &name) {
  const std::uint8_t kind = group_kind;
  put(&kind, 1);
  putString(name);
}

void H5Journal::dataset(const std::string &name, const void *data, H5File::Type type, int rank,
                        const std::uint64_t *dims) {
  const std::uint8_t header[3] = {dataset_kind, static_cast<std::uint8_t>(type),
                                  static_cast<std::uint8_t>(rank)};
  put(header, 1);
  putString(name);
  put(header + 1, 2);
  std::uint64_t count = 1;
  for (int i = 0; i < rank; ++i)
    count *= dims[i];
  put(dims, sizeof(std::uint64_t) * static_cast<std::size_t>(rank));
  put(data, count * typeBytes(type));
}

void H5Journal::attribute(const std::string &object, const std::string &name, const void *value,
                          H5File::Type type) {
  const std::uint8_t kind = number_kind, t = static_cast<std::uint8_t>(type);
  put(&kind, 1);
  putString(object);
  putString(name);
  put(&t, 1);
  put(value, typeBytes(type));
}

void H5Journal::attribute(const std::string &object, const std::string &name,
                          const std::string &value) {
  const std::uint8_t kind = string_kind;
  put(&kind, 1);
  putString(object);
  putString(name);
  putString(value);
}

void H5Journal::close() {
  if (!out_)
    return;
  const std::uint8_t kind = end;
  put(&kind, 1);
  const bool flushed = std::fflush(out_) == 0 && ::fsync(::fileno(out_)) == 0;
  const bool closed = std::fclose(out_) == 0;
  out_ = nullptr;
  if (failed_ || !flushed || !closed)
    throw std::runtime_error("cannot write the journal '" + path_ + "': " + std::strerror(errno));
}

void H5Journal::replay(const std::string &path, H5File &file) {
  Reader in(path);
  char head[sizeof magic - 1];
  in.get(head, sizeof head);
  if (std::memcmp(head, magic, sizeof head) != 0)
    in.damaged("does not begin as a journal");
  std::vector<unsigned char> data;
  for (;;) {
    const auto kind = in.get<std::uint8_t>();
    switch (kind) {
    case end:
      return;
    case group_kind:
      file.createGroup(in.getString());
      break;
    case dataset_kind: {
      const std::string name = in.getString();
      const H5File::Type type = in.getType();
      const auto rank = in.get<std::uint8_t>();
      if (rank < 1 || rank > 2)
        in.damaged("holds a dataset of rank " + std::to_string(rank));
      std::uint64_t dims[2] = {0, 0}, count = 1;
      in.get(dims, sizeof(std::uint64_t) * rank);
      for (int i = 0; i < rank; ++i) {
        if (dims[i] != 0 && count > (std::uint64_t(1) << 60) / dims[i])
          in.damaged("holds a dataset larger than any file");
        count *= dims[i];
      }
      in.left(count * typeBytes(type));
      data.resize(count * typeBytes(type));
      in.get(data.data(), data.size());
      file.writeRaw(name, data.data(), type, rank, dims);
      break;
    }
    case number_kind: {
      const std::string object = in.getString(), name = in.getString();
      const H5File::Type type = in.getType();
      unsigned char value[8] = {};
      in.get(value, typeBytes(type));
      file.attributeRaw(object, name, value, type);
      break;
    }
    case string_kind: {
      const std::string object = in.getString(), name = in.getString();
      file.attribute(object, name, in.getString());
      break;
    }
    default:
      in.damaged("holds an unknown record");
    }
  }
}

} // namespace mesopen
