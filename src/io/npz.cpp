// numpy .npz archives (zip files of .npy entries): reading every entry safely
// (bounded sizes, integrity checks), writing atomically, and the public .npy /
// .npz API. The .npy format itself lives in npy_header.cpp, npy_decode.cpp and
// npy_encode.cpp.
#include "sflsh/io/npz.hpp"

#include <zip.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <fstream>
#include <sstream>

#include "io/npz_internal.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh::io {

namespace {

using npy_internal::encode_npy;
using npy_internal::parse_npy;
using npy_internal::ParsedNpy;

std::string zip_error_text(int code) {
  zip_error_t err;
  zip_error_init_with_code(&err, code);
  std::string s = zip_error_strerror(&err);
  zip_error_fini(&err);
  return s;
}

// Reads entry `index` completely; grows the buffer as data arrives so a lying
// size field cannot trigger a huge allocation, and stops at `max_bytes` (a
// bound from the archive's size: deflate expands at most ~1032x) so that a
// small "zip bomb" cannot fill the memory either.
std::string read_zip_entry(zip_t* z, zip_uint64_t index, const std::string& where, std::uint64_t max_bytes) {
  zip_file_t* f = zip_fopen_index(z, index, 0);
  if (!f) fail(where, ": cannot open the entry: ", zip_strerror(z));
  std::string buf;
  std::vector<char> chunk(1 << 16);
  while (true) {
    const zip_int64_t got = zip_fread(f, chunk.data(), chunk.size());
    if (got < 0) {
      const std::string msg = zip_file_strerror(f);
      zip_fclose(f);
      fail(where, ": cannot read the entry (truncated or corrupt archive): ", msg);
    }
    if (got == 0) break;
    if (buf.size() + std::uint64_t(got) > max_bytes) {
      zip_fclose(f);
      fail(where, ": the entry expands beyond ", max_bytes, " bytes, more than its archive can hold (corrupt archive?)");
    }
    buf.append(chunk.data(), size_t(got));
  }
  // zip_fclose reports CRC mismatches of the data just read.
  const int rc = zip_fclose(f);
  if (rc != 0) fail(where, ": entry failed its integrity check (corrupt archive): ", zip_error_text(rc));
  return buf;
}

std::string key_of(const std::string& entry_name) {
  const std::string suffix = ".npy";
  if (entry_name.size() > suffix.size() && entry_name.compare(entry_name.size() - suffix.size(), suffix.size(), suffix) == 0)
    return entry_name.substr(0, entry_name.size() - suffix.size());
  return entry_name;
}

// Largest entry accepted from an archive of `archive_bytes` bytes.
std::uint64_t max_entry_bytes(std::uint64_t archive_bytes) { return (std::uint64_t(16) << 20) + 1100 * archive_bytes; }

// Calls fn(key, parsed) for every .npy entry of the open archive `z` (discarded here).
template <class Fn>
void for_each_entry(zip_t* z, const std::string& path, std::uint64_t archive_bytes, Fn fn) {
  struct Closer {
    zip_t* z;
    ~Closer() { zip_discard(z); }
  } closer{z};
  const zip_int64_t n = zip_get_num_entries(z, 0);
  for (zip_int64_t i = 0; i < n; ++i) {
    const char* name = zip_get_name(z, zip_uint64_t(i), 0);
    if (!name) fail(path, ": cannot read the name of archive entry ", i);
    const std::string key = key_of(name);
    const std::string where = path + ": key '" + key + "'";
    fn(key, parse_npy(read_zip_entry(z, zip_uint64_t(i), where, max_entry_bytes(archive_bytes)), where));
  }
}

template <class Fn>
void for_each_npz_entry(const std::string& path, Fn fn) {
  if (!std::filesystem::exists(path)) fail(path, ": file not found");
  std::error_code ec;
  const std::uint64_t bytes = std::filesystem::file_size(path, ec);
  if (ec) fail(path, ": not a regular file (", ec.message(), ")");
  int err = 0;
  zip_t* z = zip_open(path.c_str(), ZIP_RDONLY | ZIP_CHECKCONS, &err);
  if (!z) fail(path, ": not a readable .npz (zip) archive (truncated or corrupt?): ", zip_error_text(err));
  for_each_entry(z, path, bytes, fn);
}

template <class Fn>
void for_each_npz_entry_in_memory(const std::string& bytes, const std::string& name, Fn fn) {
  zip_error_t error;
  zip_error_init(&error);
  zip_source_t* src = zip_source_buffer_create(bytes.data(), bytes.size(), 0, &error);
  if (!src) {
    zip_error_fini(&error);
    fail(name, ": cannot read the archive from memory");
  }
  zip_t* z = zip_open_from_source(src, ZIP_RDONLY | ZIP_CHECKCONS, &error);
  if (!z) {
    const std::string msg = zip_error_strerror(&error);
    zip_source_free(src);
    zip_error_fini(&error);
    fail(name, ": not a readable .npz (zip) archive (truncated or corrupt?): ", msg);
  }
  zip_error_fini(&error);
  for_each_entry(z, name, bytes.size(), fn);
}

std::map<std::string, NpyArray> collect_arrays(
    const std::function<void(const std::function<void(const std::string&, ParsedNpy)>&)>& each,
    std::map<std::string, std::vector<std::string>>* strings) {
  std::map<std::string, NpyArray> arrays;
  each([&](const std::string& key, ParsedNpy p) {
    if (p.kind == ParsedNpy::Kind::Numeric)
      arrays[key] = std::move(p.array);
    else if (p.kind == ParsedNpy::Kind::Text && strings)
      (*strings)[key] = std::move(p.strings);
  });
  return arrays;
}

NpyArray numeric_array(ParsedNpy p, const std::string& where) {
  if (p.kind != ParsedNpy::Kind::Numeric)
    fail(where, ": dtype '", p.array.dtype, "' is not numeric (expected float, int or bool data)");
  return std::move(p.array);
}

}  // namespace

// ---------------------------------------------------------------------------

std::string format_shape(const std::vector<std::int64_t>& shape) {
  std::ostringstream os;
  os << "(";
  for (size_t i = 0; i < shape.size(); ++i) {
    if (i) os << ", ";
    if (shape[i] < 0)
      os << "any";
    else
      os << shape[i];
  }
  os << (shape.size() == 1 ? ",)" : ")");
  return os.str();
}

std::int64_t NpyArray::size() const {
  std::int64_t n = 1;
  for (auto s : shape) n *= s;
  return n;
}

void NpyArray::require_shape(const std::vector<std::int64_t>& expected, const std::string& where,
                             const std::string& key) const {
  bool ok = expected.size() == shape.size();
  for (size_t i = 0; ok && i < expected.size(); ++i) ok = expected[i] < 0 || expected[i] == shape[i];
  if (!ok) fail(where, ": key '", key, "' has shape ", format_shape(shape), ", expected ", format_shape(expected));
}

void NpyArray::require_finite(const std::string& where, const std::string& key) const {
  for (size_t i = 0; i < data.size(); ++i)
    if (!std::isfinite(data[i]))
      fail(where, ": key '", key, "' holds a non-finite value (", data[i], ") at flat index ", i);
}

std::map<std::string, NpyArray> read_npz(const std::string& path,
                                         std::map<std::string, std::vector<std::string>>* strings) {
  return collect_arrays([&](const auto& fn) { for_each_npz_entry(path, fn); }, strings);
}

std::map<std::string, NpyArray> read_npz_bytes(const std::string& bytes, const std::string& name,
                                               std::map<std::string, std::vector<std::string>>* strings) {
  return collect_arrays([&](const auto& fn) { for_each_npz_entry_in_memory(bytes, name, fn); }, strings);
}

std::vector<NpzEntryInfo> list_npz(const std::string& path) {
  std::vector<NpzEntryInfo> out;
  for_each_npz_entry(path, [&](const std::string& key, const ParsedNpy& p) {
    out.push_back({key, p.array.dtype, p.array.shape});
  });
  return out;
}

NpyArray read_npy(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, ": cannot open file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return numeric_array(parse_npy(ss.str(), path), path);
}

NpyArray read_npy_bytes(const std::string& bytes, const std::string& name) {
  return numeric_array(parse_npy(bytes, name), name);
}

void write_npz(const std::string& path, const std::map<std::string, NpyArray>& arrays, bool compressed) {
  AtomicOutput out(path);  // removes the partial archive unless committed
  const std::string& tmp = out.temp_path();
  std::error_code ec;
  std::filesystem::remove(tmp, ec);
  int err = 0;
  zip_t* z = zip_open(tmp.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &err);
  if (!z) fail(path, ": cannot create archive: ", zip_error_text(err));
  // libzip reads the buffers at zip_close(): keep them alive until then.
  std::vector<std::string> buffers;
  buffers.reserve(arrays.size());
  try {
    for (const auto& [key, a] : arrays) {
      const std::string where = path + ": key '" + key + "'";
      buffers.push_back(encode_npy(a, where));
      zip_source_t* src = zip_source_buffer(z, buffers.back().data(), buffers.back().size(), 0);
      if (!src) fail(where, ": cannot add entry: ", zip_strerror(z));
      const zip_int64_t idx = zip_file_add(z, (key + ".npy").c_str(), src, ZIP_FL_ENC_UTF_8);
      if (idx < 0) {
        zip_source_free(src);
        fail(where, ": cannot add entry: ", zip_strerror(z));
      }
      if (zip_set_file_compression(z, zip_uint64_t(idx), compressed ? ZIP_CM_DEFLATE : ZIP_CM_STORE, 0) != 0)
        fail(where, ": cannot set compression: ", zip_strerror(z));
    }
  } catch (...) {
    zip_discard(z);
    throw;
  }
  if (zip_close(z) != 0) {
    const std::string msg = zip_strerror(z);
    zip_discard(z);
    fail(path, ": cannot write archive: ", msg);
  }
  out.commit();
}

}  // namespace sflsh::io
