// Reading and writing SMPL-format body models (layout in body_model_io.hpp).
// Both readers go through one assembly routine over an "array source", so the
// HDF5 and .npz paths check exactly the same things: every array's shape
// against the vertex count V taken from v_template, finiteness, integer and
// in-range faces, the kinematic tree, and finally BodyModel::validate().
#include "sflsh/body/body_model_io.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "sflsh/body/procedural_body.hpp"
#include <cstdlib>
#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/io/crash_isolation.hpp"
#include "sflsh/io/npz.hpp"

namespace sflsh {

namespace {

using Shape = std::vector<std::int64_t>;

// Where the arrays come from. get() returns C-order, finite doubles of the
// expected shape (-1 = free extent) or throws naming the file and the key.
class ArraySource {
 public:
  explicit ArraySource(std::string path) : path_(std::move(path)) {}
  virtual ~ArraySource() = default;
  const std::string& path() const { return path_; }
  virtual bool has(const std::string& key) const = 0;
  virtual std::vector<double> get(const std::string& key, const Shape& expected, Shape* shape = nullptr) const = 0;
  /// String list `key`, or empty when absent.
  virtual std::vector<std::string> strings(const std::string& key) const = 0;
  /// 24 by V joint regressor (dense (24, V) by default).
  virtual Eigen::SparseMatrix<double, Eigen::RowMajor> regressor(std::int64_t V) const {
    const std::vector<double> d = get("J_regressor", {kSmplJoints, V});
    Eigen::Map<const MatXr> dense(d.data(), kSmplJoints, V);
    return dense.sparseView(0.0, 0.0);  // keep every non-zero, however small
  }

 protected:
  std::string path_;
};

class Hdf5Source : public ArraySource {
 public:
  explicit Hdf5Source(const std::string& path) : ArraySource(path), file_(path, io::Hdf5File::Mode::Read) {}
  const io::Hdf5File& file() const { return file_; }
  bool has(const std::string& key) const override { return file_.has("/" + key); }
  std::vector<double> get(const std::string& key, const Shape& expected, Shape* shape = nullptr) const override {
    if (!has(key)) fail(path_, ": dataset /", key, " is missing, expected shape ", io::format_shape(expected));
    return file_.read_nd("/" + key, expected, shape);
  }
  std::vector<std::string> strings(const std::string& key) const override {
    return has(key) ? file_.read_strings("/" + key) : std::vector<std::string>{};
  }
  // Sparse CSR layout /J_regressor_csr/{indptr,indices,data,shape}, else dense.
  Eigen::SparseMatrix<double, Eigen::RowMajor> regressor(std::int64_t V) const override {
    if (has("J_regressor") || !has("J_regressor_csr")) return ArraySource::regressor(V);
    const std::string g = "J_regressor_csr/";
    const std::vector<double> shape = get(g + "shape", {2});
    if (shape[0] != kSmplJoints || shape[1] != double(V))
      fail(path_, ": dataset /", g, "shape is (", shape[0], ", ", shape[1], "), expected (", kSmplJoints, ", ", V, ")");
    const std::vector<double> indptr = get(g + "indptr", {kSmplJoints + 1});
    Shape nnz_shape;
    const std::vector<double> indices = get(g + "indices", {-1}, &nnz_shape);
    const std::vector<double> data = get(g + "data", nnz_shape);
    const auto nnz = std::int64_t(indices.size());
    if (indptr[0] != 0 || indptr[kSmplJoints] != double(nnz))
      fail(path_, ": dataset /", g, "indptr must start at 0 and end at ", nnz, " (the length of indices)");
    // The whole sequence first: a row end beyond nnz must not be read from.
    for (int r = 0; r < kSmplJoints; ++r)
      if (!(indptr[r + 1] >= indptr[r]) || indptr[r + 1] != std::floor(indptr[r + 1]))
        fail(path_, ": dataset /", g, "indptr is not a non-decreasing integer sequence at entry ", r + 1);
    std::vector<Eigen::Triplet<double>> trips;
    trips.reserve(nnz);
    for (int r = 0; r < kSmplJoints; ++r) {
      for (auto k = std::int64_t(indptr[r]); k < std::int64_t(indptr[r + 1]); ++k) {
        if (indices[k] < 0 || indices[k] >= double(V) || indices[k] != std::floor(indices[k]))
          fail(path_, ": dataset /", g, "indices[", k, "] = ", indices[k], ", expected a vertex index in [0, ", V,
               ")");
        trips.emplace_back(r, int(indices[k]), data[k]);
      }
    }
    Eigen::SparseMatrix<double, Eigen::RowMajor> m(kSmplJoints, V);
    m.setFromTriplets(trips.begin(), trips.end());
    return m;
  }

 private:
  io::Hdf5File file_;
};

class NpzSource : public ArraySource {
 public:
  explicit NpzSource(const std::string& path) : ArraySource(path), arrays_(io::read_npz(path, &strings_)) {}
  bool has(const std::string& key) const override { return arrays_.count(key) > 0; }
  std::vector<double> get(const std::string& key, const Shape& expected, Shape* shape = nullptr) const override {
    auto it = arrays_.find(key);
    if (it == arrays_.end()) {
      // Say what the file does hold: typically an object array (a pickled
      // scipy.sparse regressor) that this reader cannot and should not unpickle.
      std::string held;
      for (const auto& e : io::list_npz(path_))
        held += (held.empty() ? "" : ", ") + e.key + " " + e.dtype + " " + io::format_shape(e.shape);
      fail(path_, ": key '", key, "' is missing or not a numeric array, expected shape ", io::format_shape(expected),
           " (the file holds: ", held.empty() ? "nothing" : held,
           "; convert pickled SMPL files with data_tools/smpl_pkl_to_h5.py)");
    }
    it->second.require_shape(expected, path_, key);
    it->second.require_finite(path_, key);
    if (shape) *shape = it->second.shape;
    return it->second.data;
  }
  std::vector<std::string> strings(const std::string& key) const override {
    auto it = strings_.find(key);
    return it == strings_.end() ? std::vector<std::string>{} : it->second;
  }

 private:
  std::map<std::string, std::vector<std::string>> strings_;
  std::map<std::string, io::NpyArray> arrays_;
};

// Integer view of a numeric array: every value must be an exact integer.
std::vector<std::int64_t> integers(const std::vector<double>& values, const std::string& path, const std::string& key) {
  std::vector<std::int64_t> out(values.size());
  for (size_t i = 0; i < values.size(); ++i) {
    if (values[i] != std::floor(values[i]) || std::abs(values[i]) > 9.0e15)
      fail(path, ": key '", key, "' holds a non-integer value (", values[i], ") at flat index ", i,
           ", expected integer indices");
    out[i] = std::int64_t(values[i]);
  }
  return out;
}

BodyModel assemble(const ArraySource& src) {
  const std::string& path = src.path();
  BodyModel m;
  m.source = path;

  Shape s;
  const std::vector<double> vt = src.get("v_template", {-1, 3}, &s);
  const std::int64_t V = s[0];
  if (V <= 0) fail(path, ": key 'v_template' has shape ", io::format_shape(s), ", expected (V, 3) with V > 0");
  m.v_template = Eigen::Map<const Points>(vt.data(), V, 3);

  const std::vector<std::int64_t> f = integers(src.get("f", {-1, 3}, &s), path, "f");
  m.faces.resize(s[0], 3);
  for (size_t i = 0; i < f.size(); ++i) {
    if (f[i] < 0 || f[i] >= V)
      fail(path, ": key 'f' holds vertex index ", f[i], " at face ", i / 3, ", expected an index in [0, ", V, ")");
    m.faces.data()[i] = int(f[i]);
  }

  // shapedirs (V, 3, B): element [v, c, b] sits at flat index (3v + c) B + b.
  const std::vector<double> sd = src.get("shapedirs", {V, 3, -1}, &s);
  const std::int64_t B = s[2];
  m.shapedirs.assign(B, Points(V, 3));
  for (std::int64_t r = 0; r < 3 * V; ++r)
    for (std::int64_t b = 0; b < B; ++b) m.shapedirs[b].data()[r] = sd[r * B + b];

  // posedirs (V, 3, 207) in C order is the row-major (3V, 207) matrix.
  const std::vector<double> pd = src.get("posedirs", {V, 3, kSmplPoseFeatures});
  m.posedirs = Eigen::Map<const MatXr>(pd.data(), 3 * V, kSmplPoseFeatures);
  if (!m.has_pose_blend_shapes()) m.posedirs = MatX();  // all zero: "none" (see BodyModel::posedirs)

  m.J_regressor = src.regressor(V);

  const std::vector<double> w = src.get("weights", {V, kSmplJoints});
  m.weights = Eigen::Map<const MatXr>(w.data(), V, kSmplJoints);

  // kintree_table (2, 24): row 0 parents (the root's entry is anything: SMPL
  // stores 4294967295), row 1 the joint ids, which must be 0..23 in order.
  const std::vector<double> kt = src.get("kintree_table", {2, kSmplJoints});
  m.parents.assign(kSmplJoints, -1);
  for (int j = 0; j < kSmplJoints; ++j) {
    if (kt[kSmplJoints + j] != j)
      fail(path, ": key 'kintree_table' row 1 (joint ids) holds ", kt[kSmplJoints + j], " at column ", j,
           ", expected ", j, " (joints in SMPL order)");
    if (j == 0) continue;
    if (kt[j] != std::floor(kt[j]) || kt[j] < 0 || kt[j] >= j)
      fail(path, ": key 'kintree_table' gives joint ", j, " the parent ", kt[j], ", expected an integer in [0, ", j,
           ")");
    m.parents[j] = int(kt[j]);
  }

  m.joint_names = src.strings("joint_names");
  if (m.joint_names.empty())
    for (auto n : kSmplJointNames) m.joint_names.emplace_back(n);
  m.shape_meanings = src.strings("shape_meanings");

  try {
    m.validate();
  } catch (const Error& e) {
    fail(path, ": ", e.what());
  }
  return m;
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

// 64-bit FNV-1a, fed 64-bit words (8x fewer rounds than byte-wise FNV on the
// multi-megabyte pose directions; still a stable content key, not crypto).
class Fnv64 {
 public:
  void word(std::uint64_t w) {
    h_ ^= w;
    h_ *= 0x100000001b3ULL;
  }
  void value(double d) {
    if (d == 0.0) d = 0.0;  // -0.0 and 0.0 are the same model
    std::uint64_t w;
    std::memcpy(&w, &d, 8);
    word(w);
  }
  void text(const std::string& s) {
    word(s.size());
    for (unsigned char c : s) word(c);
  }
  void values(const std::string& tag, const double* p, std::int64_t rows, std::int64_t cols) {
    text(tag);
    word(std::uint64_t(rows));
    word(std::uint64_t(cols));
    for (std::int64_t i = 0; i < rows * cols; ++i) value(p[i]);
  }
  std::string hex() const {
    char buf[17];
    std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(h_));
    return buf;
  }

 private:
  std::uint64_t h_ = 0xcbf29ce484222325ULL;
};

}  // namespace

static BodyModel read_body_model_hdf5_in_this_process(const std::string& path) {
  Hdf5Source src(path);
  if (src.has("meta/format_version")) {
    const double version = src.file().read_scalar("/meta/format_version");
    if (version > kBodyModelFormatVersion)
      fail(path, ": /meta/format_version is ", version, ", this sflsh reads body models up to version ",
           kBodyModelFormatVersion);
  }
  return assemble(src);
}

BodyModel read_body_model_npz(const std::string& path) { return assemble(NpzSource(path)); }

void write_body_model_hdf5(const BodyModel& model, const std::string& path) {
  try {
    model.validate();
  } catch (const Error& e) {
    fail(path, ": refusing to write an invalid model: ", e.what());
  }
  const std::int64_t V = model.num_vertices(), B = model.num_betas();
  io::Hdf5File h5(path, io::Hdf5File::Mode::Write);
  h5.write_scalar("/meta/format_version", std::int64_t(kBodyModelFormatVersion));
  h5.write_string("/meta/units", "metres");
  h5.write_string("/meta/source", model.source);

  h5.write_nd("/v_template", model.v_template.data(), {V, 3});
  h5.write_nd("/f", model.faces.data(), {model.faces.rows(), 3});
  std::vector<double> sd(std::size_t(3 * V * B));
  for (std::int64_t r = 0; r < 3 * V; ++r)
    for (std::int64_t b = 0; b < B; ++b) sd[r * B + b] = model.shapedirs[b].data()[r];
  h5.write_nd("/shapedirs", sd.data(), {V, 3, B});
  // Row-major (3V, 207) = C-order (V, 3, 207); an empty matrix is written as
  // zeros so that the file layout never depends on it.
  const MatXr pd = model.posedirs.size() ? MatXr(model.posedirs) : MatXr::Zero(3 * V, kSmplPoseFeatures);
  h5.write_nd("/posedirs", pd.data(), {V, 3, kSmplPoseFeatures});

  Eigen::SparseMatrix<double, Eigen::RowMajor> jr = model.J_regressor;
  jr.makeCompressed();
  std::vector<int> indptr(jr.outerIndexPtr(), jr.outerIndexPtr() + jr.rows() + 1);
  std::vector<int> indices(jr.innerIndexPtr(), jr.innerIndexPtr() + jr.nonZeros());
  std::vector<double> data(jr.valuePtr(), jr.valuePtr() + jr.nonZeros());
  const std::vector<int> jshape = {int(jr.rows()), int(jr.cols())};
  h5.write_nd("/J_regressor_csr/indptr", indptr.data(), {std::int64_t(indptr.size())});
  h5.write_nd("/J_regressor_csr/indices", indices.data(), {std::int64_t(indices.size())});
  h5.write_nd("/J_regressor_csr/data", data.data(), {std::int64_t(data.size())});
  h5.write_nd("/J_regressor_csr/shape", jshape.data(), {2});

  h5.write_nd("/weights", model.weights.data(), {V, std::int64_t(model.weights.cols())});
  std::vector<int> kt(2 * kSmplJoints);
  for (int j = 0; j < kSmplJoints; ++j) {
    kt[j] = model.parents[j];
    kt[kSmplJoints + j] = j;
  }
  h5.write_nd("/kintree_table", kt.data(), {2, kSmplJoints});
  if (!model.joint_names.empty()) h5.write_strings("/joint_names", model.joint_names);
  if (!model.shape_meanings.empty()) h5.write_strings("/shape_meanings", model.shape_meanings);
  h5.commit();
}

BodyModel load_body_model(const std::string& spec) {
  if (spec == "procedural") return make_procedural_body();
  // "procedural:N": the built-in body at about N surface vertices (coarse
  // bodies keep end-to-end tests fast).
  if (spec.rfind("procedural:", 0) == 0) {
    const std::string n = spec.substr(11);
    char* end = nullptr;
    const long v = std::strtol(n.c_str(), &end, 10);
    if (n.empty() || *end != '\0' || v < 1000 || v > 50000)
      fail("--model '", spec, "': expected procedural:N with N (surface vertices) in [1000, 50000]");
    ProceduralBodyOptions o;
    o.target_vertices = int(v);
    BodyModel m = make_procedural_body(o);
    m.source = spec;
    return m;
  }
  const std::string ext = lower_extension(spec);
  if (ext == ".h5" || ext == ".hdf5") return read_body_model_hdf5(spec);
  if (ext == ".npz") return read_body_model_npz(spec);
  if (ext == ".pkl")
    fail(spec, ": SMPL .pkl files must be converted first: /usr/bin/python3 data_tools/smpl_pkl_to_h5.py ", spec,
         " model.h5");
  fail("--model '", spec, "': expected 'procedural', 'procedural:N' or a body model file ending in .h5, .hdf5 or .npz");
}

std::string body_model_hash(const BodyModel& model) {
  // Everything that changes geometry or skinning; `source` (a path) and the
  // documentation strings in shape_meanings do not enter.
  Fnv64 h;
  h.values("v_template", model.v_template.data(), model.v_template.rows(), 3);
  const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> f = model.faces.cast<double>();
  h.values("f", f.data(), f.rows(), 3);
  h.word(std::uint64_t(model.shapedirs.size()));
  for (const auto& d : model.shapedirs) h.values("shapedirs", d.data(), d.rows(), 3);
  if (model.has_pose_blend_shapes())  // all-zero and empty pose directions are the same model
    h.values("posedirs", model.posedirs.data(), model.posedirs.rows(), model.posedirs.cols());
  else
    h.text("posedirs:none");
  h.text("J_regressor");
  h.word(std::uint64_t(model.J_regressor.rows()));
  h.word(std::uint64_t(model.J_regressor.cols()));
  for (int r = 0; r < model.J_regressor.outerSize(); ++r)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(model.J_regressor, r); it; ++it) {
      if (it.value() == 0.0) continue;  // explicit zeros are not content
      h.word(std::uint64_t(it.row()));
      h.word(std::uint64_t(it.col()));
      h.value(it.value());
    }
  h.values("weights", model.weights.data(), model.weights.rows(), model.weights.cols());
  h.text("parents");
  for (int p : model.parents) h.word(std::uint64_t(std::int64_t(p)));
  h.text("joint_names");
  for (const auto& n : model.joint_names) h.text(n);
  return h.hex();
}

BodyModel read_body_model_hdf5(const std::string& path) {
  // A file on which libhdf5 itself crashes is refused, not read (io/crash_isolation.hpp).
  return io::read_in_child_first(path, [&] { return read_body_model_hdf5_in_this_process(path); });
}

}  // namespace sflsh
