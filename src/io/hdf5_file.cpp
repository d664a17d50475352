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

#include "sflsh/core/error.hpp"

namespace sflsh::io {
namespace {

// HDF5 prints its error stack to stderr by default; we report our own errors.
struct SilenceHdf5 {
  SilenceHdf5() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }
};
const SilenceHdf5 g_silence;

// Closes an hid_t with the matching H5*close on scope exit.
struct Handle {
  hid_t id;
  herr_t (*close)(hid_t);
  Handle(hid_t i, herr_t (*c)(hid_t)) : id(i), close(c) {}
  ~Handle() {
    if (id >= 0) close(id);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
};

// Creation property list of `cls` (H5P_DATASET_CREATE, H5P_GROUP_CREATE) that
// stores no modification times: the same data gives the same bytes, so a
// rerun's file is bit-identical to the first (batch resume relies on it).
hid_t untimed(hid_t cls) {
  const hid_t p = H5Pcreate(cls);
  H5Pset_obj_track_times(p, false);
  return p;
}

std::string shape_str(const std::vector<std::int64_t>& s) {
  std::ostringstream os;
  os << "(";
  for (size_t i = 0; i < s.size(); ++i) os << (i ? ", " : "") << (s[i] < 0 ? std::string("*") : std::to_string(s[i]));
  if (s.size() == 1) os << ",";
  os << ")";
  return os.str();
}

struct MemoryImage {
  const void* data;
  std::size_t size;
};
std::mutex g_images_mutex;
std::map<std::string, MemoryImage>& memory_images() {
  static std::map<std::string, MemoryImage> images;
  return images;
}

// Product of `dims`, or UINT64_MAX when it overflows.
std::uint64_t element_count(const std::vector<std::int64_t>& dims) {
  std::uint64_t n = 1;
  for (auto d : dims) {
    if (d < 0) return UINT64_MAX;
    if (d != 0 && n > UINT64_MAX / std::uint64_t(d)) return UINT64_MAX;
    n *= std::uint64_t(d);
  }
  return n;
}

}  // namespace

Hdf5MemoryImage::Hdf5MemoryImage(std::string name, const void* data, std::size_t size) : name_(std::move(name)) {
  std::lock_guard<std::mutex> lock(g_images_mutex);
  require(memory_images().emplace(name_, MemoryImage{data, size}).second, name_, ": memory image registered twice");
}

Hdf5MemoryImage::~Hdf5MemoryImage() {
  std::lock_guard<std::mutex> lock(g_images_mutex);
  memory_images().erase(name_);
}

Hdf5File::Hdf5File(const std::string& path, Mode mode) : path_(path), mode_(mode) {
  if (mode == Mode::Read) {
    MemoryImage image{nullptr, 0};
    bool in_memory = false;
    {
      std::lock_guard<std::mutex> lock(g_images_mutex);
      const auto it = memory_images().find(path);
      if (it != memory_images().end()) image = it->second, in_memory = true;
    }
    if (in_memory) {
      // The core driver reads a copy of the image; nothing touches the disk.
      file_bytes_ = image.size;
      if (image.size < 8) fail(path, ": not an HDF5 file (or truncated/corrupted)");
      Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
      if (H5Pset_fapl_core(fapl.id, 1 << 16, 0) < 0 || H5Pset_file_image(fapl.id, const_cast<void*>(image.data), image.size) < 0)
        fail(path, ": cannot set up the in-memory HDF5 image");
      file_ = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.id);
      if (file_ < 0) fail(path, ": cannot open HDF5 file (truncated or corrupted?)");
      return;
    }
    if (!std::filesystem::exists(path)) fail(path, ": file not found");
    std::error_code ec;
    file_bytes_ = std::filesystem::file_size(path, ec);
    if (ec) fail(path, ": not a regular file (", ec.message(), ")");
    if (H5Fis_hdf5(path.c_str()) <= 0) fail(path, ": not an HDF5 file (or truncated/corrupted)");
    file_ = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    if (file_ < 0) fail(path, ": cannot open HDF5 file (truncated or corrupted?)");
  } else {
    write_path_ = path + ".partial";
    auto parent = std::filesystem::path(path).parent_path();
    if (!parent.empty()) {  // like AtomicOutput: missing folders are made
      std::error_code ec;
      std::filesystem::create_directories(parent, ec);
      if (ec) fail(path, ": cannot create folder ", parent.string(), ": ", ec.message());
    }
    file_ = H5Fcreate(write_path_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (file_ < 0) fail(path, ": cannot create file");
  }
}

void Hdf5File::close_appendable() {
  for (auto& [name, id] : appendable_) H5Dclose(id);
  appendable_.clear();
}

Hdf5File::~Hdf5File() {
  close_appendable();
  if (file_ >= 0) H5Fclose(file_);
  if (mode_ == Mode::Write && !committed_) {
    std::error_code ec;
    std::filesystem::remove(write_path_, ec);
  }
}

void Hdf5File::commit() {
  require(mode_ == Mode::Write, path_, ": commit() on a file opened for reading");
  close_appendable();
  if (H5Fclose(file_) < 0) fail(path_, ": failed to flush/close");
  file_ = -1;
  std::error_code ec;
  std::filesystem::rename(write_path_, path_, ec);
  if (ec) fail(path_, ": cannot rename ", write_path_, " into place: ", ec.message());
  committed_ = true;
}

bool Hdf5File::has(const std::string& name) const {
  // Check each path component so a missing intermediate group is not an error.
  std::string partial;
  std::stringstream ss(name);
  std::string comp;
  while (std::getline(ss, comp, '/')) {
    if (comp.empty()) continue;
    partial += "/" + comp;
    if (H5Lexists(file_, partial.c_str(), H5P_DEFAULT) <= 0) return false;
  }
  return !partial.empty();
}

void Hdf5File::check_declared_size(const std::string& name, std::uint64_t count, std::uint64_t bytes_each) const {
  const std::uint64_t limit = kMaxSmallDataset + kMaxExpansion * file_bytes_;
  if (count > limit / std::max<std::uint64_t>(bytes_each, 1))
    fail(path_, ": dataset ", name, " declares ", count, " values, more than a ", file_bytes_,
         "-byte file can hold (corrupted file?)");
}

void Hdf5File::check_storage(long dataset, const std::string& name, std::uint64_t bytes_needed,
                             std::uint64_t element_bytes) const {
  // libhdf5 1.10 copies a dataset's values for as many bytes as the datatype and shape need,
  // without checking them against what the file says is stored: a compact dataset's buffer,
  // an unfiltered chunk shorter than the chunk, or data past the end of the file (heap
  // over-reads in H5VM_memcpyvv, found by scripts/fuzz.sh, and reads past a truncated file).
  if (mode_ != Mode::Read) return;  // a file being written has no final size yet
  Handle dcpl(H5Dget_create_plist(dataset), H5Pclose);
  if (dcpl.id < 0) return;
  // The end that counts is the smaller of the file's size and the end of allocated space its
  // superblock declares: libhdf5 sizes its read buffers by the latter.
  std::uint64_t end = file_bytes_;
  haddr_t eoa = 0;
  if (H5Fget_eoa(file_, &eoa) >= 0 && eoa != HADDR_UNDEF) end = std::min<std::uint64_t>(end, std::uint64_t(eoa));
  auto require_inside = [&](haddr_t offset, std::uint64_t span, const char* what) {
    if (std::uint64_t(offset) > end || span > end - std::uint64_t(offset))
      fail(path_, ": dataset ", name, what, " lies at bytes ", std::uint64_t(offset), "..", std::uint64_t(offset) + span,
           " of a file that ends at byte ", end, " (truncated or corrupted file?)");
  };
  const H5D_layout_t layout = H5Pget_layout(dcpl.id);
  const std::uint64_t stored = H5Dget_storage_size(dataset);
  if (layout == H5D_COMPACT) {  // the values sit in the object header: as many bytes as it holds
    if (stored < bytes_needed)
      fail(path_, ": dataset ", name, " holds ", stored, " bytes of data, its shape needs ", bytes_needed,
           " (corrupted file?)");
  } else if (layout == H5D_CONTIGUOUS) {
    const haddr_t offset = H5Dget_offset(dataset);
    if (offset != HADDR_UNDEF) require_inside(offset, std::max(stored, bytes_needed), "");  // UNDEF: fill value
  } else if (layout == H5D_CHUNKED) {
    hsize_t dims[H5S_MAX_RANK];
    const int rank = H5Pget_chunk(dcpl.id, H5S_MAX_RANK, dims);
    if (rank <= 0) fail(path_, ": dataset ", name, " has an unreadable chunk layout (corrupted file?)");
    std::uint64_t chunk_bytes = element_bytes;
    for (int d = 0; d < rank; ++d) {
      if (dims[d] == 0 || chunk_bytes > (std::uint64_t(1) << 40) / dims[d])
        fail(path_, ": dataset ", name, " declares chunks of an impossible size (corrupted file?)");
      chunk_bytes *= dims[d];
    }
    // HDF5 requires chunks no larger than a fixed dimension; libhdf5 1.10 does not check it on
    // read and then copies out of a decompressed chunk with the declared chunk's strides (a
    // SEGV found by scripts/fuzz.sh: chunks of 20 × 4099 × 207 on a 20 × 3 × 207 dataset).
    Handle space(H5Dget_space(dataset), H5Sclose);
    hsize_t cur[H5S_MAX_RANK], maxd[H5S_MAX_RANK];
    if (space.id < 0 || H5Sget_simple_extent_ndims(space.id) != rank ||
        H5Sget_simple_extent_dims(space.id, cur, maxd) != rank)
      fail(path_, ": dataset ", name, " has chunks of rank ", rank, " that do not match its shape (corrupted file?)");
    for (int d = 0; d < rank; ++d)
      if (maxd[d] != H5S_UNLIMITED && dims[d] > std::max<hsize_t>(maxd[d], 1))
        fail(path_, ": dataset ", name, " declares chunks of ", dims[d], " along dimension ", d, ", larger than its ",
             maxd[d], " (corrupted file?)");
    const int filters = H5Pget_nfilters(dcpl.id);
    hsize_t num_chunks = 0;
    if (H5Dget_num_chunks(dataset, space.id, &num_chunks) < 0)
      fail(path_, ": dataset ", name, " has an unreadable chunk index (corrupted file?)");
    check_declared_size(name, num_chunks, 64);
    hsize_t coords[H5S_MAX_RANK];
    for (hsize_t c = 0; c < num_chunks; ++c) {
      unsigned mask = 0;
      haddr_t addr = 0;
      hsize_t size = 0;
      if (H5Dget_chunk_info(dataset, space.id, c, coords, &mask, &addr, &size) < 0)
        fail(path_, ": dataset ", name, " has an unreadable chunk ", c, " (corrupted file?)");
      require_inside(addr, size, (" chunk " + std::to_string(c)).c_str());
      // A chunk that no filter decodes is copied as is: it must be a whole chunk.
      const unsigned all = filters > 0 && filters < 32 ? (1u << filters) - 1 : 0u;
      const bool unfiltered = filters <= 0 || (all != 0 && (mask & all) == all);  // bit f set: filter f skipped
      if (unfiltered && size < chunk_bytes)
        fail(path_, ": dataset ", name, " chunk ", c, " holds ", size, " bytes, a chunk needs ", chunk_bytes,
             " (corrupted file?)");
    }
  }
}

void Hdf5File::check_number_type(long type, const std::string& name) const {
  // Only the usual layouts: libhdf5 1.10 converts exotic ones (e.g. a
  // 32-byte float, found by scripts/fuzz.sh) past the end of its buffers.
  const auto cls = H5Tget_class(type);
  if (cls != H5T_FLOAT && cls != H5T_INTEGER) fail(path_, ": dataset ", name, " is not numeric");
  bool usual = false;
  if (cls == H5T_FLOAT) {
    for (hid_t t : {H5T_IEEE_F32LE, H5T_IEEE_F32BE, H5T_IEEE_F64LE, H5T_IEEE_F64BE}) usual = usual || H5Tequal(type, t) > 0;
  } else {
    const size_t size = H5Tget_size(type);
    usual = (size == 1 || size == 2 || size == 4 || size == 8) && H5Tget_precision(type) == 8 * size &&
            H5Tget_offset(type) == 0;
  }
  if (!usual)
    fail(path_, ": dataset ", name, " has an unsupported number type (", H5Tget_size(type),
         " bytes); expected IEEE float32/float64 or an 8/16/32/64-bit integer");
}

long Hdf5File::open_dataset(const std::string& name) const {
  if (!has(name)) fail(path_, ": dataset ", name, " is missing");
  hid_t ds = H5Dopen2(file_, name.c_str(), H5P_DEFAULT);
  if (ds < 0) fail(path_, ": ", name, " is not a readable dataset");
  return ds;
}

std::vector<std::int64_t> Hdf5File::shape(const std::string& name) const {
  Handle ds(open_dataset(name), H5Dclose);
  Handle sp(H5Dget_space(ds.id), H5Sclose);
  int rank = H5Sget_simple_extent_ndims(sp.id);
  if (rank < 0) fail(path_, ": dataset ", name, " has an unreadable shape");
  std::vector<hsize_t> dims(rank);
  H5Sget_simple_extent_dims(sp.id, dims.data(), nullptr);
  return std::vector<std::int64_t>(dims.begin(), dims.end());
}

void Hdf5File::ensure_parent_groups(const std::string& name) {
  size_t pos = 0;
  while ((pos = name.find('/', pos + 1)) != std::string::npos) {
    std::string g = name.substr(0, pos);
    if (H5Lexists(file_, g.c_str(), H5P_DEFAULT) <= 0) {
      Handle gcpl(untimed(H5P_GROUP_CREATE), H5Pclose);
      hid_t gid = H5Gcreate2(file_, g.c_str(), H5P_DEFAULT, gcpl.id, H5P_DEFAULT);
      if (gid < 0) fail(path_, ": cannot create group ", g);
      H5Gclose(gid);
    }
  }
}

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
