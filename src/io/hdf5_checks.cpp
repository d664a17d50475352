// Checks against corrupt HDF5 files: declared sizes against the file size, a
// dataset's storage against its shape, and number types.
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

}  // namespace sflsh::io
