#pragma once
// Internals of the HDF5 file wrapper (include/sflsh/io/hdf5_file.hpp):
//   hdf5_file.cpp    — opening (on disk or a registered memory image), committing, paths,
//   hdf5_checks.cpp  — the size, storage and type checks that keep a corrupt file from
//                      crashing libhdf5 or exhausting memory,
//   hdf5_write.cpp   — datasets, appendable datasets and strings written,
//   hdf5_read.cpp    — datasets and strings read back.
#include <hdf5.h>

#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

namespace sflsh::io::hdf5_internal {

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
inline hid_t untimed(hid_t cls) {
  const hid_t p = H5Pcreate(cls);
  H5Pset_obj_track_times(p, false);
  return p;
}

inline std::string shape_str(const std::vector<std::int64_t>& s) {
  std::ostringstream os;
  os << "(";
  for (size_t i = 0; i < s.size(); ++i) os << (i ? ", " : "") << (s[i] < 0 ? std::string("*") : std::to_string(s[i]));
  if (s.size() == 1) os << ",";
  os << ")";
  return os.str();
}

// Product of `dims`, or UINT64_MAX when it overflows.
inline std::uint64_t element_count(const std::vector<std::int64_t>& dims) {
  std::uint64_t n = 1;
  for (auto d : dims) {
    if (d < 0) return UINT64_MAX;
    if (d != 0 && n > UINT64_MAX / std::uint64_t(d)) return UINT64_MAX;
    n *= std::uint64_t(d);
  }
  return n;
}

}  // namespace sflsh::io::hdf5_internal
