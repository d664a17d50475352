// numpy .npy / .npz reading and writing (numpy.lib.format, format versions
// 1.0-3.0). The .npy header is a Python dict literal; we parse it with a small
// tokenizer instead of guessing, and bounds-check every size so that a corrupt
// or hostile file produces sflsh::Error, never a crash or a huge allocation.
#include "sflsh/io/npz.hpp"

#include <zip.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <fstream>
#include <limits>
#include <sstream>

#include "sflsh/core/error.hpp"

namespace sflsh::io {

namespace {

// ---------------------------------------------------------------------------
// Header dict parsing. The header is e.g.
//   {'descr': '<f8', 'fortran_order': False, 'shape': (3, 4), }
// Values we accept: quoted strings, True/False, tuples of non-negative ints.
// A list value (structured dtype) is reported as unsupported.
struct NpyHeader {
  std::string descr;
  bool fortran_order = false;
  std::vector<std::int64_t> shape;
};

class HeaderParser {
 public:
  HeaderParser(const std::string& text, const std::string& where) : s_(text), where_(where) {}

  NpyHeader parse() {
    NpyHeader h;
    bool have_descr = false, have_order = false, have_shape = false;
    expect('{');
    while (true) {
      skip_ws();
      if (peek() == '}') {
        ++i_;
        break;
      }
      const std::string key = parse_string();
      expect(':');
      skip_ws();
      if (key == "descr") {
        if (peek() == '[') bad("structured dtypes (a list 'descr') are not supported");
        h.descr = parse_string();
        have_descr = true;
      } else if (key == "fortran_order") {
        h.fortran_order = parse_bool();
        have_order = true;
      } else if (key == "shape") {
        h.shape = parse_shape();
        have_shape = true;
      } else {
        bad("unexpected key '" + key + "'");
      }
      skip_ws();
      if (peek() == ',') {
        ++i_;
        continue;
      }
      skip_ws();
      expect('}');
      break;
    }
    if (!have_descr || !have_order || !have_shape)
      bad("the header must define 'descr', 'fortran_order' and 'shape'");
    return h;
  }

 private:
  [[noreturn]] void bad(const std::string& why) const {
    fail(where_, ": malformed .npy header (", why, ") at character ", i_);
  }
  char peek() const { return i_ < s_.size() ? s_[i_] : '\0'; }
  void skip_ws() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\t' || s_[i_] == '\n' || s_[i_] == '\r')) ++i_;
  }
  void expect(char c) {
    skip_ws();
    if (peek() != c) bad(std::string("expected '") + c + "'");
    ++i_;
  }
  std::string parse_string() {
    skip_ws();
    const char q = peek();
    if (q != '\'' && q != '"') bad("expected a quoted string");
    ++i_;
    const size_t start = i_;
    while (i_ < s_.size() && s_[i_] != q) {
      if (s_[i_] == '\\') bad("escapes in strings are not supported");
      ++i_;
    }
    if (i_ >= s_.size()) bad("unterminated string");
    return s_.substr(start, i_++ - start);
  }
  bool parse_bool() {
    if (s_.compare(i_, 4, "True") == 0) {
      i_ += 4;
      return true;
    }
    if (s_.compare(i_, 5, "False") == 0) {
      i_ += 5;
      return false;
    }
    bad("expected True or False");
  }
  std::vector<std::int64_t> parse_shape() {
    std::vector<std::int64_t> shape;
    expect('(');
    while (true) {
      skip_ws();
      if (peek() == ')') {
        ++i_;
        return shape;
      }
      if (!std::isdigit(static_cast<unsigned char>(peek()))) bad("expected a non-negative integer in 'shape'");
      std::int64_t v = 0;
      while (std::isdigit(static_cast<unsigned char>(peek()))) {
        const int d = peek() - '0';
        if (v > (std::numeric_limits<std::int64_t>::max() - d) / 10) bad("shape entry too large");
        v = v * 10 + d;
        ++i_;
      }
      if (peek() == 'L') ++i_;  // Python 2 long literal
      shape.push_back(v);
      if (shape.size() > 32) bad("more than 32 dimensions");
      skip_ws();
      if (peek() == ',') {
        ++i_;
      } else if (peek() != ')') {
        bad("expected ',' or ')' in 'shape'");
      }
    }
  }

  const std::string& s_;
  const std::string& where_;
  size_t i_ = 0;
};

// ---------------------------------------------------------------------------
// dtype description: byte order, kind and item size.
struct Dtype {
  char order = '<';  // '<' little, '>' big, '|' not applicable
  char kind = 'f';   // f i u b U S O ...
  int itemsize = 0;  // bytes per element
};

Dtype parse_descr(const std::string& descr, const std::string& where) {
  if (descr.size() < 2) fail(where, ": unsupported dtype '", descr, "'");
  Dtype d;
  size_t k = 0;
  if (descr[0] == '<' || descr[0] == '>' || descr[0] == '|' || descr[0] == '=') {
    d.order = descr[0] == '=' ? '<' : descr[0];  // '=' is native; sflsh runs on little-endian machines
    k = 1;
  }
  if (k >= descr.size()) fail(where, ": unsupported dtype '", descr, "'");
  d.kind = descr[k++];
  if (d.kind == 'O') return d;  // object array: item size is a pointer, content is a pickle
  const std::string digits = descr.substr(k);
  if (digits.empty() || digits.size() > 9 || !std::all_of(digits.begin(), digits.end(), [](unsigned char c) { return std::isdigit(c) != 0; }))
    fail(where, ": unsupported dtype '", descr, "'");
  d.itemsize = std::stoi(digits);
  if (d.kind == 'U') {
    if (d.itemsize > 1 << 20) fail(where, ": unsupported dtype '", descr, "' (string too long)");
    d.itemsize *= 4;  // UCS-4 code units
  }
  return d;
}

bool is_numeric(const Dtype& d) {
  switch (d.kind) {
    case 'f':
      return d.itemsize == 2 || d.itemsize == 4 || d.itemsize == 8;
    case 'i':
    case 'u':
      return d.itemsize == 1 || d.itemsize == 2 || d.itemsize == 4 || d.itemsize == 8;
    case 'b':
      return d.itemsize == 1;
    default:
      return false;
  }
}

bool is_text(const Dtype& d) { return (d.kind == 'U' || d.kind == 'S') && d.itemsize > 0; }

double half_to_double(std::uint16_t h) {
  const int sign = (h >> 15) & 1, exp = (h >> 10) & 0x1f, mant = h & 0x3ff;
  double v;
  if (exp == 0)
    v = std::ldexp(double(mant), -24);  // subnormal
  else if (exp == 31)
    v = mant ? std::numeric_limits<double>::quiet_NaN() : std::numeric_limits<double>::infinity();
  else
    v = std::ldexp(double(mant | 0x400), exp - 25);
  return sign ? -v : v;
}

// Reads one element of a numeric dtype at p, honouring its byte order.
double load_element(const unsigned char* p, const Dtype& d) {
  unsigned char b[8];
  const bool swap = d.order == '>' && d.itemsize > 1;
  for (int i = 0; i < d.itemsize; ++i) b[i] = swap ? p[d.itemsize - 1 - i] : p[i];
  auto as = [&](auto t) {
    std::memcpy(&t, b, sizeof(t));
    return t;
  };
  switch (d.kind) {
    case 'f':
      if (d.itemsize == 2) return half_to_double(as(std::uint16_t{}));
      if (d.itemsize == 4) return double(as(float{}));
      return as(double{});
    case 'i':
      if (d.itemsize == 1) return double(as(std::int8_t{}));
      if (d.itemsize == 2) return double(as(std::int16_t{}));
      if (d.itemsize == 4) return double(as(std::int32_t{}));
      return double(as(std::int64_t{}));
    case 'u':
      if (d.itemsize == 1) return double(as(std::uint8_t{}));
      if (d.itemsize == 2) return double(as(std::uint16_t{}));
      if (d.itemsize == 4) return double(as(std::uint32_t{}));
      return double(as(std::uint64_t{}));
    default:  // 'b'
      return b[0] ? 1.0 : 0.0;
  }
}

void append_utf8(std::string& out, std::uint32_t cp) {
  if (cp < 0x80) {
    out += char(cp);
  } else if (cp < 0x800) {
    out += char(0xC0 | (cp >> 6));
    out += char(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += char(0xE0 | (cp >> 12));
    out += char(0x80 | ((cp >> 6) & 0x3F));
    out += char(0x80 | (cp & 0x3F));
  } else if (cp < 0x110000) {
    out += char(0xF0 | (cp >> 18));
    out += char(0x80 | ((cp >> 12) & 0x3F));
    out += char(0x80 | ((cp >> 6) & 0x3F));
    out += char(0x80 | (cp & 0x3F));
  } else {
    out += '?';
  }
}

// Maps a C-order flat index to the Fortran-order storage offset: a Fortran
// array stores element (i0, .., in) at i0 + d0 * (i1 + d1 * (..)).
std::vector<std::int64_t> fortran_offsets(const std::vector<std::int64_t>& shape, std::int64_t count) {
  std::vector<std::int64_t> offsets(count);
  const size_t nd = shape.size();
  std::vector<std::int64_t> fstride(nd, 1), idx(nd, 0);
  for (size_t k = 1; k < nd; ++k) fstride[k] = fstride[k - 1] * shape[k - 1];
  for (std::int64_t c = 0; c < count; ++c) {
    std::int64_t off = 0;
    for (size_t k = 0; k < nd; ++k) off += idx[k] * fstride[k];
    offsets[c] = off;
    for (size_t k = nd; k-- > 0;) {  // odometer over C order (last index fastest)
      if (++idx[k] < shape[k]) break;
      idx[k] = 0;
    }
  }
  return offsets;
}

// One parsed .npy entry: either numbers (NpyArray) or strings.
struct ParsedNpy {
  NpyArray array;
  std::vector<std::string> strings;
  enum class Kind { Numeric, Text, Skipped } kind = Kind::Numeric;
  std::string skip_reason;
};

// Parses a whole .npy byte buffer. `where` is "FILE" or "FILE: key 'K'".
ParsedNpy parse_npy(const std::string& bytes, const std::string& where) {
  static const char kMagic[] = "\x93NUMPY";
  if (bytes.size() < 10 || bytes.compare(0, 6, kMagic, 6) != 0)
    fail(where, ": not a .npy array (bad magic; truncated or not numpy data)");
  const auto* u = reinterpret_cast<const unsigned char*>(bytes.data());
  const int major = u[6];
  std::uint64_t header_len, prefix;
  if (major == 1) {
    header_len = u[8] | (std::uint64_t(u[9]) << 8);
    prefix = 10;
  } else if (major == 2 || major == 3) {
    if (bytes.size() < 12) fail(where, ": truncated .npy header");
    header_len = u[8] | (std::uint64_t(u[9]) << 8) | (std::uint64_t(u[10]) << 16) | (std::uint64_t(u[11]) << 24);
    prefix = 12;
  } else {
    fail(where, ": unsupported .npy format version ", major, ".", int(u[7]));
  }
  if (header_len > bytes.size() - prefix)
    fail(where, ": .npy header length ", header_len, " exceeds the ", bytes.size(), "-byte entry (truncated?)");
  const std::string header_text = bytes.substr(prefix, header_len);
  const NpyHeader h = HeaderParser(header_text, where).parse();

  ParsedNpy out;
  out.array.shape = h.shape;
  out.array.dtype = h.descr;
  const Dtype d = parse_descr(h.descr, where);
  if (d.kind == 'O') {
    out.kind = ParsedNpy::Kind::Skipped;
    out.skip_reason = "object array (pickled Python objects)";
    return out;
  }
  if (!is_numeric(d) && !is_text(d)) fail(where, ": unsupported dtype '", h.descr, "'");

  // Element count and byte size, overflow-safe: compare against the bytes present.
  const std::uint64_t available = bytes.size() - prefix - header_len;
  const std::uint64_t max_count = available / std::uint64_t(d.itemsize);
  std::uint64_t count = 1;
  bool zero = false;
  for (auto s : h.shape) zero = zero || s == 0;
  if (zero) {
    count = 0;
  } else {
    for (auto s : h.shape) {
      if (std::uint64_t(s) > max_count / count)
        fail(where, ": shape ", format_shape(h.shape), " of dtype '", h.descr, "' needs more data than the ", available,
             " bytes present (truncated or corrupt)");
      count *= std::uint64_t(s);
    }
  }
  const std::uint64_t need = count * std::uint64_t(d.itemsize);
  if (need > available)
    fail(where, ": shape ", format_shape(h.shape), " of dtype '", h.descr, "' needs ", need, " bytes, only ", available,
         " present (truncated?)");
  const unsigned char* data = u + prefix + header_len;
  const std::int64_t n = std::int64_t(count);
  std::vector<std::int64_t> order;
  if (h.fortran_order && h.shape.size() > 1 && n > 0) order = fortran_offsets(h.shape, n);
  auto src = [&](std::int64_t c) { return order.empty() ? c : order[c]; };

  if (is_text(d)) {
    out.kind = ParsedNpy::Kind::Text;
    out.strings.reserve(n);
    for (std::int64_t c = 0; c < n; ++c) {
      const unsigned char* p = data + src(c) * d.itemsize;
      std::string s;
      if (d.kind == 'S') {
        s.assign(reinterpret_cast<const char*>(p), d.itemsize);
        s.erase(std::find(s.begin(), s.end(), '\0'), s.end());
      } else {
        for (int k = 0; k < d.itemsize / 4; ++k) {
          const unsigned char* q = p + 4 * k;
          const std::uint32_t cp = d.order == '>' ? (std::uint32_t(q[0]) << 24 | q[1] << 16 | q[2] << 8 | q[3])
                                                  : (std::uint32_t(q[3]) << 24 | q[2] << 16 | q[1] << 8 | q[0]);
          if (cp == 0) break;  // numpy pads with NULs
          append_utf8(s, cp);
        }
      }
      out.strings.push_back(std::move(s));
    }
    return out;
  }
  out.array.data.resize(n);
  for (std::int64_t c = 0; c < n; ++c) out.array.data[c] = load_element(data + src(c) * d.itemsize, d);
  return out;
}

// ---------------------------------------------------------------------------
// .npy writing (format 1.0; header padded so the data starts 64-byte aligned,
// as numpy does).
std::string encode_npy(const NpyArray& a, const std::string& where) {
  std::string descr = "<f8";
  if (a.dtype == "<f4" || a.dtype == "<i4" || a.dtype == "<i8") descr = a.dtype;
  std::int64_t count = 1;
  for (auto s : a.shape) {
    require(s >= 0, where, ": negative extent in shape ", format_shape(a.shape));
    count *= s;
  }
  require(count == std::int64_t(a.data.size()), where, ": shape ", format_shape(a.shape), " holds ", count,
          " values but the array has ", a.data.size());
  std::ostringstream hs;
  hs << "{'descr': '" << descr << "', 'fortran_order': False, 'shape': (";
  for (size_t i = 0; i < a.shape.size(); ++i) hs << a.shape[i] << (a.shape.size() == 1 || i + 1 < a.shape.size() ? ", " : "");
  hs << "), }";
  std::string header = hs.str();
  const size_t total = 10 + header.size() + 1;
  header.append((64 - total % 64) % 64, ' ');
  header += '\n';
  require(header.size() < 65536, where, ": .npy header too long");
  std::string out = "\x93NUMPY";
  out += char(1);
  out += char(0);
  out += char(header.size() & 0xff);
  out += char(header.size() >> 8);
  out += header;
  const size_t item = descr == "<f4" || descr == "<i4" ? 4 : 8;
  const size_t off = out.size();
  out.resize(off + item * a.data.size());
  char* p = out.data() + off;
  for (double v : a.data) {
    if (descr == "<f4") {
      const float f = float(v);
      std::memcpy(p, &f, 4);
    } else if (descr == "<i4") {
      require(v == std::floor(v) && std::abs(v) <= 2147483647.0, where, ": value ", v, " does not fit dtype <i4");
      const std::int32_t i = std::int32_t(v);
      std::memcpy(p, &i, 4);
    } else if (descr == "<i8") {
      require(v == std::floor(v) && std::abs(v) <= 9.2e18, where, ": value ", v, " does not fit dtype <i8");
      const std::int64_t i = std::int64_t(v);
      std::memcpy(p, &i, 8);
    } else {
      std::memcpy(p, &v, 8);
    }
    p += item;
  }
  return out;
}

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
  const std::string tmp = path + ".partial";
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
    std::filesystem::remove(tmp, ec);
    throw;
  }
  if (zip_close(z) != 0) {
    const std::string msg = zip_strerror(z);
    zip_discard(z);
    std::filesystem::remove(tmp, ec);
    fail(path, ": cannot write archive: ", msg);
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    const std::string msg = ec.message();
    std::filesystem::remove(tmp, ec);
    fail(path, ": cannot move ", tmp, " into place: ", msg);
  }
}

}  // namespace sflsh::io
