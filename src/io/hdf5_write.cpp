// Writing HDF5 datasets: n-d arrays, matrices, appendable datasets, scalars and strings.
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

namespace {
void write_raw(hid_t file, const std::string& path, const std::string& name, const void* data,
               const std::vector<std::int64_t>& shape, hid_t mem_type, hid_t file_type) {
  std::vector<hsize_t> dims(shape.begin(), shape.end());
  Handle sp(H5Screate_simple(int(dims.size()), dims.data(), nullptr), H5Sclose);
  // Compress large datasets (chunked, deflate level 4): avatars carry big matrices.
  Handle dcpl(untimed(H5P_DATASET_CREATE), H5Pclose);
  hsize_t total = 1;
  for (auto d : dims) total *= d;
  if (total >= 4096 && !dims.empty()) {
    std::vector<hsize_t> chunk(dims);
    // Chunk along the first axis, about 64k elements per chunk.
    hsize_t row = total / (dims[0] ? dims[0] : 1);
    chunk[0] = std::max<hsize_t>(1, std::min<hsize_t>(dims[0], 65536 / std::max<hsize_t>(row, 1)));
    H5Pset_chunk(dcpl.id, int(chunk.size()), chunk.data());
    H5Pset_deflate(dcpl.id, 4);
  }
  Handle ds(H5Dcreate2(file, name.c_str(), file_type, sp.id, H5P_DEFAULT, dcpl.id, H5P_DEFAULT), H5Dclose);
  if (ds.id < 0) fail(path, ": cannot create dataset ", name, " (exists already?)");
  if (total > 0 && H5Dwrite(ds.id, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
    fail(path, ": cannot write dataset ", name);
}
}  // namespace

void Hdf5File::write_nd(const std::string& name, const double* data, const std::vector<std::int64_t>& shape,
                        bool as_float32) {
  require(mode_ == Mode::Write, path_, ": write on a file opened for reading");
  ensure_parent_groups(name);
  write_raw(file_, path_, name, data, shape, H5T_NATIVE_DOUBLE, as_float32 ? H5T_IEEE_F32LE : H5T_IEEE_F64LE);
}

void Hdf5File::write_nd(const std::string& name, const int* data, const std::vector<std::int64_t>& shape) {
  require(mode_ == Mode::Write, path_, ": write on a file opened for reading");
  ensure_parent_groups(name);
  write_raw(file_, path_, name, data, shape, H5T_NATIVE_INT, H5T_STD_I32LE);
}

void Hdf5File::write(const std::string& name, const double* data, std::int64_t rows, std::int64_t cols,
                     bool as_float32) {
  write_nd(name, data, {rows, cols}, as_float32);
}

void Hdf5File::write(const std::string& name, const int* data, std::int64_t rows, std::int64_t cols) {
  write_nd(name, data, {rows, cols});
}

void Hdf5File::create_appendable(const std::string& name, const std::vector<std::int64_t>& row_shape,
                                 bool as_float32) {
  require(mode_ == Mode::Write, path_, ": write on a file opened for reading");
  ensure_parent_groups(name);
  std::vector<hsize_t> dims{0}, maxdims{H5S_UNLIMITED}, chunk{1};
  hsize_t row = 1;
  for (auto d : row_shape) {
    dims.push_back(hsize_t(d));
    maxdims.push_back(hsize_t(d));
    chunk.push_back(hsize_t(std::max<std::int64_t>(d, 1)));
    row *= hsize_t(std::max<std::int64_t>(d, 1));
  }
  // Several rows per chunk when rows are small (scalars per frame).
  chunk[0] = std::max<hsize_t>(1, 16384 / row);
  Handle sp(H5Screate_simple(int(dims.size()), dims.data(), maxdims.data()), H5Sclose);
  Handle dcpl(untimed(H5P_DATASET_CREATE), H5Pclose);
  H5Pset_chunk(dcpl.id, int(chunk.size()), chunk.data());
  // Streamed while simulating: byte shuffle + fast deflate (level 1) compresses
  // float frames about as well as level 4 at a fraction of the time.
  H5Pset_shuffle(dcpl.id);
  H5Pset_deflate(dcpl.id, 1);
  const hid_t ds = H5Dcreate2(file_, name.c_str(), as_float32 ? H5T_IEEE_F32LE : H5T_IEEE_F64LE, sp.id, H5P_DEFAULT,
                              dcpl.id, H5P_DEFAULT);
  if (ds < 0) fail(path_, ": cannot create dataset ", name);
  appendable_[name] = ds;
}

void Hdf5File::append(const std::string& name, const double* data, std::int64_t rows) {
  require(mode_ == Mode::Write, path_, ": append on a file opened for reading");
  const auto open = appendable_.find(name);
  if (open == appendable_.end()) fail(path_, ": append to ", name, ", which create_appendable() did not create");
  const Handle ds(open->second, [](hid_t) -> herr_t { return 0; });  // stays open (see appendable_)
  Handle sp(H5Dget_space(ds.id), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(sp.id);
  std::vector<hsize_t> dims(rank);
  H5Sget_simple_extent_dims(sp.id, dims.data(), nullptr);
  std::vector<hsize_t> start(rank, 0), count(dims);
  start[0] = dims[0];
  count[0] = hsize_t(rows);
  dims[0] += hsize_t(rows);
  if (H5Dset_extent(ds.id, dims.data()) < 0) fail(path_, ": cannot extend dataset ", name);
  Handle fsp(H5Dget_space(ds.id), H5Sclose);
  H5Sselect_hyperslab(fsp.id, H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr);
  Handle msp(H5Screate_simple(rank, count.data(), nullptr), H5Sclose);
  if (H5Dwrite(ds.id, H5T_NATIVE_DOUBLE, msp.id, fsp.id, H5P_DEFAULT, data) < 0)
    fail(path_, ": cannot append to dataset ", name);
}

void Hdf5File::write_scalar(const std::string& name, double value) { write_nd(name, &value, {1}); }

void Hdf5File::write_scalar(const std::string& name, std::int64_t value) {
  require(mode_ == Mode::Write, path_, ": write on a file opened for reading");
  ensure_parent_groups(name);
  write_raw(file_, path_, name, &value, {1}, H5T_NATIVE_INT64, H5T_STD_I64LE);
}

void Hdf5File::write_strings(const std::string& name, const std::vector<std::string>& values) {
  require(mode_ == Mode::Write, path_, ": write on a file opened for reading");
  ensure_parent_groups(name);
  // Fixed-length strings (no global heap; see read_strings), as wide as the
  // longest value, padded with NULs.
  size_t width = 1;
  for (const auto& v : values) {
    require(v.find('\0') == std::string::npos, path_, ": dataset ", name, ": a string holds a NUL byte");
    width = std::max(width, v.size());
  }
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.id, width);
  H5Tset_strpad(type.id, H5T_STR_NULLPAD);
  H5Tset_cset(type.id, H5T_CSET_UTF8);
  std::vector<char> buf(width * values.size(), '\0');
  for (size_t i = 0; i < values.size(); ++i) std::copy(values[i].begin(), values[i].end(), buf.begin() + i * width);
  hsize_t n = values.size();
  Handle sp(H5Screate_simple(1, &n, nullptr), H5Sclose);
  Handle dcpl(untimed(H5P_DATASET_CREATE), H5Pclose);
  Handle ds(H5Dcreate2(file_, name.c_str(), type.id, sp.id, H5P_DEFAULT, dcpl.id, H5P_DEFAULT), H5Dclose);
  if (ds.id < 0) fail(path_, ": cannot create dataset ", name);
  if (n > 0 && H5Dwrite(ds.id, type.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) < 0)
    fail(path_, ": cannot write dataset ", name);
}

void Hdf5File::write_string(const std::string& name, const std::string& value) {
  write_strings(name, {value});
}

}  // namespace sflsh::io
