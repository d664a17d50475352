#pragma once
// numpy .npy / .npz reading and writing (the format numpy documents in
// numpy.lib.format: magic "\x93NUMPY", version, a header dict with 'descr',
// 'fortran_order', 'shape'; .npz is a zip of such files, stored or deflated).
// Reads float16/32/64, (u)int8..64 and bool in either byte order, C or Fortran
// order (returned in C order); values are converted to double. Every failure
// (truncated archive, malformed header, data shorter than the shape, ...)
// throws sflsh::Error naming the file and key; sizes are bounds-checked.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace sflsh::io {

struct NpyArray {
  std::vector<std::int64_t> shape;  ///< numpy shape (C order after reading)
  std::string dtype;                ///< numpy descr as stored, e.g. "<f4"
  std::vector<double> data;         ///< values in C (row-major) order
  std::int64_t size() const;
  /// Throws "<where>: key '<key>' has shape (..), expected (..)" on mismatch;
  /// -1 entries of `expected` are free.
  void require_shape(const std::vector<std::int64_t>& expected, const std::string& where,
                     const std::string& key) const;
  /// Throws naming where/key and the flat index of the first NaN/Inf.
  void require_finite(const std::string& where, const std::string& key) const;
};

/// A shape as numpy prints it, "(20, 3)" or "(4,)"; -1 entries print as "any".
std::string format_shape(const std::vector<std::int64_t>& shape);

/// All arrays of an .npz file, by key (without the ".npy" suffix). Entries that
/// are not numeric (object arrays, strings) are skipped unless `strings`
/// is given, where unicode/bytes arrays are collected instead.
std::map<std::string, NpyArray> read_npz(const std::string& path,
                                         std::map<std::string, std::vector<std::string>>* strings = nullptr);
/// read_npz over an archive held in memory (`bytes`); `name` stands for the
/// file in messages.
std::map<std::string, NpyArray> read_npz_bytes(const std::string& bytes, const std::string& name,
                                               std::map<std::string, std::vector<std::string>>* strings = nullptr);
/// What an .npz entry holds (read from its .npy header), for diagnostics:
/// lists every entry, including object and string arrays that read_npz skips.
struct NpzEntryInfo {
  std::string key;                  ///< entry name without ".npy"
  std::string dtype;                ///< numpy descr, e.g. "<f4", "<U6", "|O"
  std::vector<std::int64_t> shape;  ///< numpy shape
};
std::vector<NpzEntryInfo> list_npz(const std::string& path);

/// One .npy file.
NpyArray read_npy(const std::string& path);
/// One .npy array held in memory; `name` stands for the file in messages.
NpyArray read_npy_bytes(const std::string& bytes, const std::string& name);

/// Writes an .npz (float64 arrays unless the array's dtype says "<f4", "<i4"
/// or "<i8"), deflated when `compressed`. Atomic (temp file + rename).
void write_npz(const std::string& path, const std::map<std::string, NpyArray>& arrays, bool compressed = false);

}  // namespace sflsh::io
