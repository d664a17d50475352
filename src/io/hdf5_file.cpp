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

// HDF5 prints its error stack to stderr by default; we report our own errors.
struct SilenceHdf5 {
  SilenceHdf5() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }
};
const SilenceHdf5 g_silence;

struct MemoryImage {
  const void* data;
  std::size_t size;
};
std::mutex g_images_mutex;
std::map<std::string, MemoryImage>& memory_images() {
  static std::map<std::string, MemoryImage> images;
  return images;
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
    out_ = std::make_unique<AtomicOutput>(path);
    file_ = H5Fcreate(out_->temp_path().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
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
  out_.reset();  // removes the partial file unless committed
}

void Hdf5File::commit() {
  require(mode_ == Mode::Write, path_, ": commit() on a file opened for reading");
  close_appendable();
  if (H5Fclose(file_) < 0) fail(path_, ": failed to flush/close");
  file_ = -1;
  out_->commit();
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

}  // namespace sflsh::io
