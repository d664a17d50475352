#pragma once
// A thin RAII layer over the HDF5 C API for the project's files (body models,
// avatars, simulation results). Every read checks the dataset exists, has the
// expected rank/shape and (for floating data) is finite, and throws
// sflsh::Error naming the file and dataset otherwise. HDF5's own error stack
// printing is silenced; its failures become sflsh::Error too.
//
// Writing goes to "<path>.partial" and is renamed over <path> by commit(), so a
// failed or interrupted job never leaves a half-written file behind.
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh::io {

/// An HDF5 file image in memory, readable as Hdf5File(name, Mode::Read) (and so
/// by every reader that takes a path) while this object lives: fuzzing and
/// replaying inputs need no temporary files. `data` is not copied and must
/// outlive this object; `name` must not be registered twice at once.
class Hdf5MemoryImage {
 public:
  Hdf5MemoryImage(std::string name, const void* data, std::size_t size);
  ~Hdf5MemoryImage();
  Hdf5MemoryImage(const Hdf5MemoryImage&) = delete;
  Hdf5MemoryImage& operator=(const Hdf5MemoryImage&) = delete;
  const std::string& name() const { return name_; }

 private:
  std::string name_;
};

class Hdf5File {
 public:
  enum class Mode { Read, Write };
  /// Opens `path` for reading (a file, or a live Hdf5MemoryImage of that
  /// name), or creates `<path>.partial` for writing.
  ///
  /// Reading guards memory: a dataset may declare at most
  /// kMaxExpansion · (file size) + kMaxSmallDataset bytes of values (a
  /// deflated dataset expands ~1000x at most), so a 1 kB file cannot make a
  /// reader allocate gigabytes because a header says so.
  Hdf5File(const std::string& path, Mode mode);
  static constexpr std::uint64_t kMaxExpansion = 4096;
  static constexpr std::uint64_t kMaxSmallDataset = 16u << 20;  ///< bytes
  ~Hdf5File();  // Write mode without commit(): removes the partial file.
  Hdf5File(const Hdf5File&) = delete;
  Hdf5File& operator=(const Hdf5File&) = delete;

  /// Write mode: closes the file and renames it to its final path.
  void commit();

  const std::string& path() const { return path_; }
  bool has(const std::string& name) const;  // dataset or group, e.g. "/tet/nodes"
  /// Shape of a dataset (throws if missing).
  std::vector<std::int64_t> shape(const std::string& name) const;

  // --- writing (intermediate groups are created) ---
  /// Row-major 2-D array (rows x cols). `as_float32` stores single precision.
  void write(const std::string& name, const double* data, std::int64_t rows, std::int64_t cols,
             bool as_float32 = false);
  void write(const std::string& name, const int* data, std::int64_t rows, std::int64_t cols);
  /// N-D array of doubles with an explicit shape (row-major).
  void write_nd(const std::string& name, const double* data, const std::vector<std::int64_t>& shape,
                bool as_float32 = false);
  void write_nd(const std::string& name, const int* data, const std::vector<std::int64_t>& shape);
  /// 1-D dataset of fixed-length UTF-8 strings (as wide as the longest value,
  /// NUL-padded; a value must not contain NUL). Never variable-length: see read_strings.
  void write_strings(const std::string& name, const std::vector<std::string>& values);
  void write_string(const std::string& name, const std::string& value);  // a one-element string dataset
  void write_scalar(const std::string& name, double value);
  void write_scalar(const std::string& name, std::int64_t value);

  /// Creates an empty dataset whose first axis grows with append(); each row
  /// has shape `row_shape` (e.g. {V, 3} for per-frame positions).
  void create_appendable(const std::string& name, const std::vector<std::int64_t>& row_shape, bool as_float32 = false);
  /// Appends `rows` rows (row-major, rows × Π row_shape values) to a dataset
  /// made by create_appendable (streams long outputs without holding them).
  void append(const std::string& name, const double* data, std::int64_t rows = 1);

  template <class Derived>
  void write_matrix(const std::string& name, const Eigen::DenseBase<Derived>& m, bool as_float32 = false) {
    using S = typename Derived::Scalar;
    Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> r = m;
    if constexpr (std::is_integral_v<S>) {
      Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> ri = r.template cast<int>();
      write(name, ri.data(), ri.rows(), ri.cols());
    } else {
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rd = r.template cast<double>();
      write(name, rd.data(), rd.rows(), rd.cols(), as_float32);
    }
  }

  // --- reading ---
  /// Reads a 1-D or 2-D numeric dataset as doubles (rank-1 -> n x 1).
  /// `rows`/`cols` of -1 accept any extent; otherwise a mismatch throws
  /// "FILE: dataset NAME has shape (a, b), expected (rows, cols)". Non-finite
  /// values throw naming the dataset and the first bad index.
  MatXr read_matrix(const std::string& name, std::int64_t rows = -1, std::int64_t cols = -1) const;
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> read_int_matrix(
      const std::string& name, std::int64_t rows = -1, std::int64_t cols = -1) const;
  /// N-D doubles; `expected` entries of -1 are free. Fills `shape_out`.
  std::vector<double> read_nd(const std::string& name, const std::vector<std::int64_t>& expected,
                              std::vector<std::int64_t>* shape_out = nullptr) const;
  /// A dataset of fixed-length strings (NUL- or space-padding removed).
  /// Variable-length strings (sflsh before 2026-11-26, h5py's default `str`)
  /// are refused with an error naming the dataset: libhdf5 1.10 reads them from
  /// the global heap without bounds checks, so a damaged file could hang or
  /// crash the reader.
  std::vector<std::string> read_strings(const std::string& name) const;
  std::string read_string(const std::string& name) const;
  double read_scalar(const std::string& name) const;
  /// A scalar that must be a whole number in [lo, hi]; anything else (NaN, 4e9, 2.5) is an
  /// error naming the file and the dataset.
  int read_int_scalar(const std::string& name, int lo, int hi) const;

  template <class M>
  M read_as(const std::string& name, std::int64_t rows = -1, std::int64_t cols = -1) const {
    return read_matrix(name, rows, cols).template cast<typename M::Scalar>();
  }

 private:
  long open_dataset(const std::string& name) const;  // hid_t
  // Throws unless the file type `type` (hid_t) is IEEE float32/64 or a plain integer.
  void check_number_type(long type, const std::string& name) const;
  /// The stored bytes of a dataset must cover what its shape needs before libhdf5 copies them:
  /// a compact dataset's buffer, each unfiltered chunk (chunks of `element_bytes` × the chunk
  /// dims), and every contiguous block or chunk must lie inside the file (its size and its
  /// superblock's end of allocation). Fails naming the dataset otherwise.
  void check_storage(long dataset, const std::string& name, std::uint64_t bytes_needed, std::uint64_t element_bytes) const;
  // Throws unless `count` values of `bytes_each` bytes fit the guard above.
  void check_declared_size(const std::string& name, std::uint64_t count, std::uint64_t bytes_each) const;
  std::uint64_t file_bytes_ = 0;  // size of the file or image being read
  void ensure_parent_groups(const std::string& name);
  std::string path_;
  std::unique_ptr<AtomicOutput> out_;  // writing: <path>.partial, renamed over <path> by commit()
  Mode mode_;
  long file_ = -1;  // hid_t
  // Appendable datasets stay open until commit/destruction so that HDF5's
  // chunk cache keeps a partly filled chunk in memory: reopening per append
  // flushed (deflated) and re-read (inflated) it on every frame.
  std::map<std::string, long> appendable_;  // name -> hid_t
  void close_appendable();
};

}  // namespace sflsh::io
