// Decoding of one .npy buffer (numpy.lib.format, versions 1.0-3.0): the dtype,
// byte order, Fortran order and text arrays. Every size is bounds-checked so a
// corrupt or hostile buffer produces sflsh::Error, never a crash or a huge allocation.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "io/npz_internal.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh::io::npy_internal {

namespace {

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

}  // namespace

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
  const NpyHeader h = parse_npy_header(header_text, where);

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

}  // namespace sflsh::io::npy_internal
