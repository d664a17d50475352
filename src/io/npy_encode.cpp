// Encoding of one array as a .npy buffer.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>

#include "io/npz_internal.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh::io::npy_internal {

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

}  // namespace sflsh::io::npy_internal
