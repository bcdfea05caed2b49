#include "h5file.hpp"

#include <hdf5.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <type_traits>

namespace mesopen {

static_assert(std::is_same_v<hid_t, std::int64_t>, "H5File stores hid_t as std::int64_t");

namespace {

// HDF5 closes what is open when the process exits; a file whose close failed (a full disk) stays
// half-closed, and that clean-up then crashed the process after it had said why it failed. Every
// file is closed explicitly here, so the library's exit handler is not installed (H5dont_atexit
// must come before the library's first use: at static initialization).
const bool no_exit_handler = [] { return H5dont_atexit() >= 0; }();

// Owns one HDF5 identifier and releases it with the matching close function.
class Handle {
public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Handle(const Handle &) = delete;
  Handle &operator=(const Handle &) = delete;
  ~Handle() {
    if (id_ >= 0)
      close_(id_);
  }
  operator hid_t() const { return id_; }

private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

// HDF5 prints its error stack by default; errors are reported by exceptions instead. The
// setting is per thread in thread-safe builds, so it is repeated at every entry point.
void quiet() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

herr_t firstError(unsigned, const H5E_error2_t *error, void *out) {
  auto &text = *static_cast<std::string *>(out);
  if (text.empty() && error->desc)
    text = error->desc;
  return 0;
}

[[noreturn]] void fail(const std::string &file, const char *what, const std::string &object = {}) {
  std::string reason;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, firstError, &reason);
  H5Eclear2(H5E_DEFAULT);
  std::string message = "HDF5 file '" + file + "': cannot " + what;
  if (!object.empty())
    message += " '" + object + "'";
  if (!reason.empty())
    message += " (" + reason + ")";
  throw std::runtime_error(message);
}

// Returns r, or throws when it is negative (a failed HDF5 call).
template <class R>
R check(R r, const std::string &file, const char *what, const std::string &object = {}) {
  if (r < 0)
    fail(file, what, object);
  return r;
}

hid_t fileType(H5File::Type type) {
  switch (type) {
  case H5File::Type::f64:
    return H5T_IEEE_F64LE;
  case H5File::Type::i32:
    return H5T_STD_I32LE;
  case H5File::Type::i64:
    return H5T_STD_I64LE;
  case H5File::Type::u8:
    return H5T_STD_U8LE;
  case H5File::Type::u32:
    return H5T_STD_U32LE;
  case H5File::Type::u64:
    return H5T_STD_U64LE;
  }
  return -1;
}

hid_t memoryType(H5File::Type type) {
  switch (type) {
  case H5File::Type::f64:
    return H5T_NATIVE_DOUBLE;
  case H5File::Type::i32:
    return H5T_NATIVE_INT32;
  case H5File::Type::i64:
    return H5T_NATIVE_INT64;
  case H5File::Type::u8:
    return H5T_NATIVE_UINT8;
  case H5File::Type::u32:
    return H5T_NATIVE_UINT32;
  case H5File::Type::u64:
    return H5T_NATIVE_UINT64;
  }
  return -1;
}

// File access: a fixed format version (1.8 objects, readable by HDF5 1.8 and later) so that a
// newer library writes the same bytes, and a close that releases every object of the file.
hid_t accessList(const std::string &path) {
  const hid_t fapl = check(H5Pcreate(H5P_FILE_ACCESS), path, "create file access list");
  if (H5Pset_libver_bounds(fapl, H5F_LIBVER_V18, H5F_LIBVER_V18) < 0 ||
      H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG) < 0) {
    H5Pclose(fapl);
    fail(path, "set file access properties");
  }
  return fapl;
}

// Scalar attribute `name` of `object`, replacing an existing one.
void putAttribute(hid_t file, const std::string &path, const std::string &object,
                  const std::string &name, hid_t file_type, hid_t memory_type, const void *value) {
  const std::string where = object + "@" + name;
  Handle owner(check(H5Oopen(file, object.c_str(), H5P_DEFAULT), path, "open object", object),
               H5Oclose);
  if (check(H5Aexists(owner, name.c_str()), path, "look up attribute", where) > 0)
    check(H5Adelete(owner, name.c_str()), path, "replace attribute", where);
  Handle space(check(H5Screate(H5S_SCALAR), path, "create dataspace for", where), H5Sclose);
  Handle attr(check(H5Acreate2(owner, name.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT),
                    path, "create attribute", where),
              H5Aclose);
  check(H5Awrite(attr, memory_type, value), path, "write attribute", where);
}

} // namespace

H5File H5File::create(const std::string &path) {
  quiet();
  Handle fapl(accessList(path), H5Pclose);
  // The file creation list also creates the root group: no time stamps there either.
  Handle fcpl(check(H5Pcreate(H5P_FILE_CREATE), path, "create file creation list"), H5Pclose);
  check(H5Pset_obj_track_times(fcpl, 0), path, "disable time tracking");
  const hid_t id = check(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl, fapl), path, "create file");
  return H5File(path, id);
}

H5File H5File::open(const std::string &path, bool writable) {
  quiet();
  Handle fapl(accessList(path), H5Pclose);
  const hid_t id = check(H5Fopen(path.c_str(), writable ? H5F_ACC_RDWR : H5F_ACC_RDONLY, fapl),
                         path, "open file");
  return H5File(path, id);
}

H5File::H5File(H5File &&other) noexcept
    : path_(std::move(other.path_)), id_(other.id_), recorder_(other.recorder_) {
  other.id_ = -1;
  other.recorder_ = nullptr;
}

H5File &H5File::operator=(H5File &&other) noexcept {
  if (this != &other) {
    if (id_ >= 0)
      H5Fclose(id_);
    path_ = std::move(other.path_);
    id_ = other.id_;
    recorder_ = other.recorder_;
    other.id_ = -1;
    other.recorder_ = nullptr;
  }
  return *this;
}

H5File::~H5File() {
  if (id_ >= 0) {
    quiet();
    H5Fclose(id_);
  }
}

void H5File::close() {
  if (id_ < 0)
    return;
  quiet();
  const hid_t id = id_;
  id_ = -1;
  check(H5Fclose(id), path_, "close file");
}

bool H5File::exists(const std::string &name) const {
  quiet();
  if (name == "/")
    return true;
  // Every parent must exist before the link itself can be asked for.
  for (std::size_t slash = name.find('/', 1); slash != std::string::npos;
       slash = name.find('/', slash + 1))
    if (check(H5Lexists(id_, name.substr(0, slash).c_str(), H5P_DEFAULT), path_, "look up", name) ==
        0)
      return false;
  return check(H5Lexists(id_, name.c_str(), H5P_DEFAULT), path_, "look up", name) > 0;
}

void H5File::createGroup(const std::string &name) {
  quiet();
  Handle gcpl(check(H5Pcreate(H5P_GROUP_CREATE), path_, "create group list", name), H5Pclose);
  check(H5Pset_obj_track_times(gcpl, 0), path_, "disable time tracking", name);
  Handle group(check(H5Gcreate2(id_, name.c_str(), H5P_DEFAULT, gcpl, H5P_DEFAULT), path_,
                     "create group", name),
               H5Gclose);
  if (recorder_)
    recorder_->group(name);
}

void H5File::checkSize(const std::string &name, std::size_t have, std::size_t want) const {
  if (have != want)
    throw std::runtime_error("HDF5 file '" + path_ + "': dataset '" + name + "' given " +
                             std::to_string(have) + " values for " + std::to_string(want));
}

void H5File::writeRaw(const std::string &name, const void *data, Type type, int rank,
                      const std::uint64_t *dims) {
  quiet();
  hsize_t extent[2] = {0, 0};
  hsize_t count = 1;
  for (int i = 0; i < rank; ++i) {
    extent[i] = dims[i];
    count *= dims[i];
  }
  Handle space(check(H5Screate_simple(rank, extent, nullptr), path_, "create dataspace for", name),
               H5Sclose);
  Handle dcpl(check(H5Pcreate(H5P_DATASET_CREATE), path_, "create dataset list", name), H5Pclose);
  check(H5Pset_obj_track_times(dcpl, 0), path_, "disable time tracking", name);
  check(H5Pset_layout(dcpl, H5D_CONTIGUOUS), path_, "set contiguous layout", name);
  Handle dataset(
      check(H5Dcreate2(id_, name.c_str(), fileType(type), space, H5P_DEFAULT, dcpl, H5P_DEFAULT),
            path_, "create dataset", name),
      H5Dclose);
  if (count > 0)
    check(H5Dwrite(dataset, memoryType(type), H5S_ALL, H5S_ALL, H5P_DEFAULT, data), path_,
          "write dataset", name);
  if (recorder_)
    recorder_->dataset(name, data, type, rank, dims);
}

void H5File::attributeRaw(const std::string &object, const std::string &name, const void *value,
                          Type type) {
  quiet();
  putAttribute(id_, path_, object, name, fileType(type), memoryType(type), value);
  if (recorder_)
    recorder_->attribute(object, name, value, type);
}

void H5File::attribute(const std::string &object, const std::string &name,
                       const std::string &value) {
  quiet();
  const std::string where = object + "@" + name;
  // Variable-length UTF-8: h5py reads it as str (a fixed-length string comes back as bytes).
  Handle type(check(H5Tcopy(H5T_C_S1), path_, "create string type for", where), H5Tclose);
  check(H5Tset_size(type, H5T_VARIABLE), path_, "size string of", where);
  check(H5Tset_cset(type, H5T_CSET_UTF8), path_, "set character set of", where);
  const char *text = value.c_str();
  putAttribute(id_, path_, object, name, type, type, &text);
  if (recorder_)
    recorder_->attribute(object, name, value);
}

std::vector<std::uint64_t> H5File::shape(const std::string &name) const {
  quiet();
  Handle dataset(check(H5Dopen2(id_, name.c_str(), H5P_DEFAULT), path_, "open dataset", name),
                 H5Dclose);
  Handle space(check(H5Dget_space(dataset), path_, "get dataspace of", name), H5Sclose);
  const int rank = check(H5Sget_simple_extent_ndims(space), path_, "get rank of", name);
  std::vector<hsize_t> dims(rank);
  check(H5Sget_simple_extent_dims(space, dims.data(), nullptr), path_, "get shape of", name);
  return {dims.begin(), dims.end()};
}

std::uint64_t H5File::elements(const std::string &name, std::size_t element_bytes) const {
  std::uint64_t n = 1;
  bool overflow = false;
  for (std::uint64_t d : shape(name)) {
    if (d != 0 && n > std::numeric_limits<std::uint64_t>::max() / d)
      overflow = true;
    n *= d;
  }
  std::error_code ec;
  const std::uintmax_t file_bytes = std::filesystem::file_size(path_, ec);
  const double declared = static_cast<double>(n) * static_cast<double>(element_bytes);
  if (overflow || (!ec && declared > 64.0 * static_cast<double>(file_bytes) + 1e6))
    throw std::runtime_error("HDF5 file '" + path_ + "': dataset '" + name + "' declares " +
                             (overflow ? std::string("more than 2^64") : std::to_string(n)) +
                             " elements, more than a file of " + std::to_string(file_bytes) +
                             " bytes can hold");
  return n;
}

void H5File::readRaw(const std::string &name, void *data, Type type, std::uint64_t count) const {
  quiet();
  Handle dataset(check(H5Dopen2(id_, name.c_str(), H5P_DEFAULT), path_, "open dataset", name),
                 H5Dclose);
  Handle space(check(H5Dget_space(dataset), path_, "get dataspace of", name), H5Sclose);
  const auto have = check(H5Sget_simple_extent_npoints(space), path_, "count elements of", name);
  checkSize(name, static_cast<std::size_t>(have), count);
  if (count > 0)
    check(H5Dread(dataset, memoryType(type), H5S_ALL, H5S_ALL, H5P_DEFAULT, data), path_,
          "read dataset", name);
}

bool H5File::hasAttribute(const std::string &object, const std::string &name) const {
  quiet();
  return check(H5Aexists_by_name(id_, object.c_str(), name.c_str(), H5P_DEFAULT), path_,
               "look up attribute", object + "@" + name) > 0;
}

void H5File::readAttributeRaw(const std::string &object, const std::string &name, void *value,
                              Type type) const {
  quiet();
  const std::string where = object + "@" + name;
  Handle attr(check(H5Aopen_by_name(id_, object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT),
                    path_, "open attribute", where),
              H5Aclose);
  check(H5Aread(attr, memoryType(type), value), path_, "read attribute", where);
}

std::string H5File::readStringAttribute(const std::string &object, const std::string &name) const {
  quiet();
  const std::string where = object + "@" + name;
  Handle attr(check(H5Aopen_by_name(id_, object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT),
                    path_, "open attribute", where),
              H5Aclose);
  Handle type(check(H5Aget_type(attr), path_, "get type of", where), H5Tclose);
  Handle space(check(H5Aget_space(attr), path_, "get dataspace of", where), H5Sclose);
  if (H5Tget_class(type) != H5T_STRING ||
      check(H5Sget_simple_extent_npoints(space), path_, "count elements of", where) != 1)
    throw std::runtime_error("HDF5 file '" + path_ + "': attribute '" + where +
                             "' is not one string");
  if (H5Tis_variable_str(type) > 0) {
    Handle memory(check(H5Tcopy(H5T_C_S1), path_, "create string type for", where), H5Tclose);
    check(H5Tset_size(memory, H5T_VARIABLE), path_, "size string of", where);
    check(H5Tset_cset(memory, H5Tget_cset(type)), path_, "set character set of", where);
    char *text = nullptr;
    check(H5Aread(attr, memory, &text), path_, "read attribute", where);
    std::string value = text ? text : "";
    H5free_memory(text);
    return value;
  }
  // fixed length (files of earlier versions), padded with nulls
  std::string value(H5Tget_size(type), '\0');
  check(H5Aread(attr, type, value.data()), path_, "read attribute", where);
  value.erase(value.find_last_not_of('\0') + 1);
  return value;
}

} // namespace mesopen
