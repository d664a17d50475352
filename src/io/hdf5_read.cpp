// Reading HDF5 datasets back: strings, n-d arrays, matrices and scalars, each checked.
#include "sflsh/io/hdf5_file.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <sstream>

#include "io/hdf5_internal.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh::io {

using namespace hdf5_internal;

std::vector<std::string> Hdf5File::read_strings(const std::string& name) const {
  Handle ds(open_dataset(name), H5Dclose);
  Handle ftype(H5Dget_type(ds.id), H5Tclose);
  if (H5Tget_class(ftype.id) != H5T_STRING) fail(path_, ": dataset ", name, " is not a string dataset");
  Handle sp(H5Dget_space(ds.id), H5Sclose);
  const hssize_t n = H5Sget_simple_extent_npoints(sp.id);
  if (n < 0) fail(path_, ": dataset ", name, " has an unreadable shape");
  // Variable-length strings live in HDF5's global heap, which libhdf5 1.10
  // reads without bounds checks: a damaged file hangs or overruns it
  // (H5HG_read, found by scripts/fuzz.sh). sflsh writes fixed-length strings
  // and refuses the others before touching the heap.
  if (H5Tis_variable_str(ftype.id) != 0)
    fail(path_, ": dataset ", name,
         " holds variable-length strings, which this sflsh does not read (written by an older sflsh or another "
         "tool): run again the sflsh command that made the file (e.g. `sflsh precompute` for an avatar), or store "
         "the strings as fixed-length (h5py: dtype 'S<n>')");
  const size_t sz = H5Tget_size(ftype.id);
  if (sz == 0) fail(path_, ": dataset ", name, " has strings of size 0");
  check_declared_size(name, std::uint64_t(n), sz + sizeof(std::string));
  check_storage(ds.id, name, std::uint64_t(n) * sz, sz);
  std::vector<char> buf(sz * n + 1, 0);
  if (n > 0 && H5Dread(ds.id, ftype.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) < 0)
    fail(path_, ": cannot read dataset ", name);
  const bool space_padded = H5Tget_strpad(ftype.id) == H5T_STR_SPACEPAD;
  std::vector<std::string> out;
  for (hssize_t i = 0; i < n; ++i) {
    std::string s(buf.data() + i * sz, sz);
    s.resize(std::strlen(s.c_str()));
    if (space_padded) s.erase(s.find_last_not_of(' ') + 1);
    out.push_back(std::move(s));
  }
  return out;
}

std::string Hdf5File::read_string(const std::string& name) const {
  auto v = read_strings(name);
  if (v.size() != 1) fail(path_, ": dataset ", name, " holds ", v.size(), " strings, expected 1");
  return v[0];
}

std::vector<double> Hdf5File::read_nd(const std::string& name, const std::vector<std::int64_t>& expected,
                                      std::vector<std::int64_t>* shape_out) const {
  Handle ds(open_dataset(name), H5Dclose);
  Handle ftype(H5Dget_type(ds.id), H5Tclose);
  check_number_type(ftype.id, name);
  auto s = shape(name);
  bool ok = expected.empty() || s.size() == expected.size();
  for (size_t i = 0; ok && i < expected.size(); ++i) ok = expected[i] < 0 || expected[i] == s[i];
  if (!ok) fail(path_, ": dataset ", name, " has shape ", shape_str(s), ", expected ", shape_str(expected));
  check_declared_size(name, element_count(s), sizeof(double));
  const std::int64_t n = std::int64_t(element_count(s));
  check_storage(ds.id, name, std::uint64_t(n) * H5Tget_size(ftype.id), H5Tget_size(ftype.id));
  std::vector<double> buf(n);
  if (n > 0 && H5Dread(ds.id, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) < 0)
    fail(path_, ": cannot read dataset ", name, " (truncated or corrupted file?)");
  for (std::int64_t i = 0; i < n; ++i)
    if (!std::isfinite(buf[i])) fail(path_, ": dataset ", name, " holds a non-finite value at flat index ", i);
  if (shape_out) *shape_out = s;
  return buf;
}

MatXr Hdf5File::read_matrix(const std::string& name, std::int64_t rows, std::int64_t cols) const {
  auto s = shape(name);
  if (s.size() == 1) s.push_back(1);
  if (s.size() != 2) fail(path_, ": dataset ", name, " has rank ", s.size(), ", expected a matrix ", shape_str({rows, cols}));
  if ((rows >= 0 && s[0] != rows) || (cols >= 0 && s[1] != cols))
    fail(path_, ": dataset ", name, " has shape ", shape_str(s), ", expected ", shape_str({rows, cols}));
  auto buf = read_nd(name, {});  // checks the declared size first
  MatXr m(s[0], s[1]);
  std::copy(buf.begin(), buf.end(), m.data());
  return m;
}

Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> Hdf5File::read_int_matrix(
    const std::string& name, std::int64_t rows, std::int64_t cols) const {
  MatXr m = read_matrix(name, rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i)
    if (m.data()[i] != std::floor(m.data()[i]) || std::abs(m.data()[i]) > 2e9)
      fail(path_, ": dataset ", name, " holds a non-integer value at flat index ", i);
  return m.cast<int>();
}

double Hdf5File::read_scalar(const std::string& name) const {
  auto v = read_nd(name, {});
  if (v.size() != 1) fail(path_, ": dataset ", name, " holds ", v.size(), " values, expected a scalar");
  return v[0];
}

int Hdf5File::read_int_scalar(const std::string& name, int lo, int hi) const {
  const double v = read_scalar(name);
  if (!(v >= lo && v <= hi) || v != std::floor(v))
    fail(path_, ": dataset ", name, " is ", v, ", expected a whole number in [", lo, ", ", hi, "]");
  return int(v);
}

}  // namespace sflsh::io
