#pragma once
// Internals of the numpy .npy / .npz reader and writer (include/sflsh/io/npz.hpp):
//   npy_header.cpp  — the .npy header dict (a Python literal) and its tokenizer,
//   npy_decode.cpp  — dtypes and the decoding of one .npy buffer into numbers or strings,
//   npy_encode.cpp  — the encoding of one array as a .npy buffer,
//   npz.cpp         — the zip archive: reading entries safely, writing, the public API.
#include <cstdint>
#include <string>
#include <vector>

#include "sflsh/io/npz.hpp"

namespace sflsh::io::npy_internal {

// The .npy header dict, e.g.
//   {'descr': '<f8', 'fortran_order': False, 'shape': (3, 4), }
// Values we accept: quoted strings, True/False, tuples of non-negative ints.
// A list value (structured dtype) is reported as unsupported.
struct NpyHeader {
  std::string descr;
  bool fortran_order = false;
  std::vector<std::int64_t> shape;
};

// Parses the header text of a .npy entry; `where` names it in errors.
NpyHeader parse_npy_header(const std::string& text, const std::string& where);

// One parsed .npy entry: either numbers (NpyArray) or strings.
struct ParsedNpy {
  NpyArray array;
  std::vector<std::string> strings;
  enum class Kind { Numeric, Text, Skipped } kind = Kind::Numeric;
  std::string skip_reason;
};

// Parses a whole .npy byte buffer. `where` is "FILE" or "FILE: key 'K'".
ParsedNpy parse_npy(const std::string& bytes, const std::string& where);

// .npy writing (format 1.0; header padded so the data starts 64-byte aligned,
// as numpy does).
std::string encode_npy(const NpyArray& a, const std::string& where);

}  // namespace sflsh::io::npy_internal
