#include "sflsh/asset/avatar_file.hpp"

#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/io/crash_isolation.hpp"
#include "sflsh/mesh/tet_topology_hash.hpp"

namespace sflsh {
namespace {

using io::Hdf5File;
using IntMat = Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

constexpr const char* kToolVersion = "sflsh 0.1.0";

void write_vec_i(Hdf5File& f, const std::string& name, const VecXi& v) { f.write_nd(name, v.data(), {v.size()}); }
void write_vec_d(Hdf5File& f, const std::string& name, const VecX& v) { f.write_nd(name, v.data(), {v.size()}); }

VecXi read_vec_i(const Hdf5File& f, const std::string& name, std::int64_t n = -1) {
  IntMat m = f.read_int_matrix(name, n, 1);
  return Eigen::Map<VecXi>(m.data(), m.rows());
}
VecX read_vec_d(const Hdf5File& f, const std::string& name, std::int64_t n = -1) {
  MatXr m = f.read_matrix(name, n, 1);
  return Eigen::Map<VecX>(m.data(), m.rows());
}

void write_cubature(Hdf5File& f, const std::string& g, const Cubature& c) {
  write_vec_i(f, g + "/elements", c.elements);
  f.write_matrix(g + "/barycentric", c.barycentric);
  write_vec_d(f, g + "/weights", c.weights);
}

Cubature read_cubature(const Hdf5File& f, const std::string& g) {
  Cubature c;
  c.elements = read_vec_i(f, g + "/elements");
  const auto s = c.elements.size();
  c.barycentric = f.read_matrix(g + "/barycentric", s, 4);
  c.weights = read_vec_d(f, g + "/weights", s);
  return c;
}

}  // namespace

void write_avatar(const Avatar& a, const std::string& path) {
  validate_avatar(a, path + " (before writing)");
  Hdf5File f(path, Hdf5File::Mode::Write);
  f.write_scalar("/meta/format_version", std::int64_t(kAvatarFormatVersion));
  f.write_string("/meta/units", "metres, kilograms, seconds, pascals");
  write_vec_d(f, "/meta/betas", a.betas);
  f.write_string("/meta/model_hash", a.model_hash);
  f.write_string("/meta/model_source", a.model_source);
  f.write_string("/meta/tool_version", kToolVersion);
  f.write_string("/meta/topology_hash", tet_topology_hash(a.tet.elements));

  f.write_matrix("/skeleton/joints_rest", a.joints_rest);
  f.write_nd("/skeleton/parents", a.parents.data(), {std::int64_t(a.parents.size())});
  f.write_strings("/skeleton/joint_names", a.joint_names);
  MatXr caps(a.capsules.size(), 8);
  for (size_t i = 0; i < a.capsules.size(); ++i) {
    const auto& c = a.capsules[i];
    caps.row(i) << c.bone, c.p0.x(), c.p0.y(), c.p0.z(), c.p1.x(), c.p1.y(), c.p1.z(), c.radius;
  }
  f.write_nd("/skeleton/capsules", caps.data(), {caps.rows(), 8});

  f.write_matrix("/surface/vertices", a.surface_rest);
  f.write_matrix("/surface/faces", a.surface_faces);
  f.write_matrix("/surface/weights", a.surface_weights);
  if (a.surface_posedirs.size() > 0) f.write_matrix("/surface/posedirs", a.surface_posedirs);
  write_vec_i(f, "/surface/tet", a.surface_tet);
  f.write_matrix("/surface/barycentric", a.surface_bary);

  f.write_matrix("/tet/nodes", a.tet.nodes);
  f.write_matrix("/tet/elements", a.tet.elements);
  write_vec_i(f, "/tet/surface_nodes", a.surface_nodes);
  f.write_matrix("/tet/node_weights", a.node_weights);
  write_vec_i(f, "/tet/node_role", a.node_role);
  write_vec_i(f, "/tet/region", a.tet_region);
  f.write_matrix("/tet/frames", a.tet_frames);

  std::vector<std::string> names;
  MatXr params(a.materials.size(), 6);
  for (size_t r = 0; r < a.materials.size(); ++r) {
    const auto& m = a.materials[r];
    names.push_back(m.name);
    params.row(r) << m.young_along, m.young_through, m.young_around, m.poisson, m.fung_c, m.density;
  }
  f.write_strings("/material/names", names);
  f.write_nd("/material/parameters", params.data(), {params.rows(), 6});

  f.write_matrix("/basis/handles", a.handles);
  const std::int64_t N = a.W.rows(), K = a.W.cols(), nnz = a.W.nonZeros();
  if (2 * nnz + N + 1 < N * K) {  // CSR pays
    Eigen::SparseMatrix<double, Eigen::RowMajor> W = a.W;
    W.makeCompressed();
    f.write_nd("/basis/weights_csr/indptr", W.outerIndexPtr(), {N + 1});
    f.write_nd("/basis/weights_csr/indices", W.innerIndexPtr(), {nnz});
    f.write_nd("/basis/weights_csr/data", W.valuePtr(), {nnz});
    const int shape[2] = {int(N), int(K)};
    f.write_nd("/basis/weights_csr/shape", shape, {2});
  } else {
    f.write_matrix("/basis/weights", MatXr(a.W));
  }
  write_cubature(f, "/cubature/elastic", a.elastic);
  write_cubature(f, "/cubature/inertia", a.inertia);
  f.commit();
}

static Avatar read_avatar_in_this_process(const std::string& path) {
  Hdf5File f(path, Hdf5File::Mode::Read);
  Avatar a;
  if (!f.has("/meta/format_version")) fail(path, ": not an sflsh avatar file (dataset /meta/format_version is missing)");
  const double version = f.read_scalar("/meta/format_version");
  if (version != kAvatarFormatVersion)
    fail(path, ": dataset /meta/format_version is ", version, ", this sflsh reads version ", kAvatarFormatVersion,
         " (re-run `sflsh precompute`)");
  a.format_version = int(version);
  a.betas = read_vec_d(f, "/meta/betas");
  a.model_hash = f.read_string("/meta/model_hash");
  a.model_source = f.read_string("/meta/model_source");

  a.joints_rest = f.read_matrix("/skeleton/joints_rest", -1, 3);
  const auto J = a.joints_rest.rows();
  VecXi parents = read_vec_i(f, "/skeleton/parents", J);
  a.parents.assign(parents.data(), parents.data() + J);
  a.joint_names = f.read_strings("/skeleton/joint_names");
  MatXr caps = f.read_matrix("/skeleton/capsules", -1, 8);
  for (Eigen::Index i = 0; i < caps.rows(); ++i)
    a.capsules.push_back({int(caps(i, 0)), caps.row(i).segment<3>(1).transpose(), caps.row(i).segment<3>(4).transpose(),
                          caps(i, 7)});

  a.surface_rest = f.read_matrix("/surface/vertices", -1, 3);
  const auto V = a.surface_rest.rows();
  a.surface_faces = f.read_int_matrix("/surface/faces", -1, 3);
  a.surface_weights = f.read_matrix("/surface/weights", V, J);
  if (f.has("/surface/posedirs")) a.surface_posedirs = f.read_matrix("/surface/posedirs", 3 * V, -1);
  a.surface_tet = read_vec_i(f, "/surface/tet", V);
  a.surface_bary = f.read_matrix("/surface/barycentric", V, 4);

  a.tet.nodes = f.read_matrix("/tet/nodes", -1, 3);
  const auto N = a.tet.nodes.rows();
  a.tet.elements = f.read_int_matrix("/tet/elements", -1, 4);
  const auto T = a.tet.elements.rows();
  a.surface_nodes = read_vec_i(f, "/tet/surface_nodes");
  a.node_weights = f.read_matrix("/tet/node_weights", N, J);
  a.node_role = read_vec_i(f, "/tet/node_role", N);
  a.tet_region = read_vec_i(f, "/tet/region", T);
  a.tet_frames = f.read_matrix("/tet/frames", T, 9);
  // Files written before /meta/topology_hash existed have none; where it is, it must be the tets'.
  if (f.has("/meta/topology_hash")) {
    const std::string stored = f.read_string("/meta/topology_hash"), actual = tet_topology_hash(a.tet.elements);
    if (stored != actual)
      fail(path, ": dataset /meta/topology_hash is ", stored, " but /tet/elements hashes to ", actual,
           " (the file was altered; re-run `sflsh precompute`)");
  }

  auto names = f.read_strings("/material/names");
  MatXr params = f.read_matrix("/material/parameters", std::int64_t(names.size()), 6);
  for (size_t r = 0; r < names.size(); ++r)
    a.materials.push_back({names[r], params(r, 0), params(r, 1), params(r, 2), params(r, 3), params(r, 4), params(r, 5)});

  a.handles = f.read_matrix("/basis/handles", -1, 3);
  const auto K = a.handles.rows();
  if (f.has("/basis/weights_csr")) {
    VecXi shape = read_vec_i(f, "/basis/weights_csr/shape", 2);
    if (shape[0] != N || shape[1] != K)
      fail(path, ": dataset /basis/weights_csr/shape is (", shape[0], ", ", shape[1], "), expected (", N, ", ", K, ")");
    VecXi indptr = read_vec_i(f, "/basis/weights_csr/indptr", N + 1);
    VecXi indices = read_vec_i(f, "/basis/weights_csr/indices");
    VecX data = read_vec_d(f, "/basis/weights_csr/data", indices.size());
    if (indptr[0] != 0 || indptr[N] != indices.size())
      fail(path, ": dataset /basis/weights_csr/indptr does not span ", indices.size(), " entries");
    std::vector<Eigen::Triplet<double>> trip;
    trip.reserve(indices.size());
    for (Eigen::Index r = 0; r < N; ++r) {
      if (indptr[r + 1] < indptr[r]) fail(path, ": dataset /basis/weights_csr/indptr decreases at row ", r);
      for (int p = indptr[r]; p < indptr[r + 1]; ++p) {
        if (indices[p] < 0 || indices[p] >= K)
          fail(path, ": dataset /basis/weights_csr/indices has column ", indices[p], " outside [0, ", K, ")");
        trip.emplace_back(int(r), indices[p], data[p]);
      }
    }
    a.W.resize(N, K);
    a.W.setFromTriplets(trip.begin(), trip.end());
  } else {
    a.W = f.read_matrix("/basis/weights", N, K).sparseView();
  }
  a.elastic = read_cubature(f, "/cubature/elastic");
  a.inertia = read_cubature(f, "/cubature/inertia");
  validate_avatar(a, path);
  return a;
}

void validate_avatar(const Avatar& a, const std::string& where) {
  const auto J = a.joints_rest.rows();
  const auto V = a.surface_rest.rows();
  const auto N = a.tet.nodes.rows();
  const auto T = a.tet.elements.rows();
  const auto K = a.handles.rows();
  require(J > 0 && a.joints_rest.cols() == 3, where, ": /skeleton/joints_rest must be (J, 3) with J > 0");
  require(a.parents.size() == size_t(J), where, ": /skeleton/parents has ", a.parents.size(), " entries, expected ", J);
  require(a.joint_names.size() == size_t(J), where, ": /skeleton/joint_names has ", a.joint_names.size(),
          " entries, expected ", J);
  for (Eigen::Index j = 0; j < J; ++j)
    require(a.parents[j] < j && (j == 0 ? a.parents[j] < 0 : a.parents[j] >= 0), where,
            ": /skeleton/parents[", j, "] = ", a.parents[j], " is not a valid parent (expected -1 for the root, else < ", j, ")");
  for (const auto& c : a.capsules)
    require(c.bone >= 0 && c.bone < J && c.radius > 0, where, ": /skeleton/capsules has an invalid capsule (bone ", c.bone,
            ", radius ", c.radius, ")");
  require(a.surface_faces.rows() > 0 && V > 0, where, ": /surface is empty");
  require(a.surface_faces.minCoeff() >= 0 && a.surface_faces.maxCoeff() < V, where,
          ": /surface/faces indexes outside [0, ", V, ")");
  require(a.surface_weights.rows() == V && a.surface_weights.cols() == J, where, ": /surface/weights must be (", V, ", ", J, ")");
  require(a.surface_posedirs.size() == 0 || a.surface_posedirs.rows() == 3 * V, where,
          ": /surface/posedirs must have ", 3 * V, " rows");
  require(a.surface_tet.size() == V && a.surface_bary.rows() == V && a.surface_bary.cols() == 4, where,
          ": /surface/tet and /surface/barycentric must have ", V, " rows");
  require(N > 0 && T > 0, where, ": /tet is empty");
  require(a.surface_tet.minCoeff() >= 0 && a.surface_tet.maxCoeff() < T, where, ": /surface/tet indexes outside [0, ", T, ")");
  require(a.tet.elements.minCoeff() >= 0 && a.tet.elements.maxCoeff() < N, where,
          ": /tet/elements indexes outside [0, ", N, ")");
  require(a.surface_nodes.size() == 0 || (a.surface_nodes.minCoeff() >= 0 && a.surface_nodes.maxCoeff() < N), where,
          ": /tet/surface_nodes indexes outside [0, ", N, ")");
  require(a.node_weights.rows() == N && a.node_weights.cols() == J, where, ": /tet/node_weights must be (", N, ", ", J, ")");
  require(a.node_role.size() == N && a.node_role.minCoeff() >= 0 && a.node_role.maxCoeff() <= 2, where,
          ": /tet/node_role must hold ", N, " values in {0, 1, 2}");
  const int R = int(a.materials.size());
  require(R > 0, where, ": /material is empty");
  require(a.tet_region.size() == T && a.tet_region.minCoeff() >= 0 && a.tet_region.maxCoeff() < R, where,
          ": /tet/region must hold ", T, " indices in [0, ", R, ")");
  require(a.tet_frames.rows() == T && a.tet_frames.cols() == 9, where, ": /tet/frames must be (", T, ", 9)");
  for (const auto& m : a.materials) {
    const std::string problem = m.range_problem();
    require(problem.empty(), where, ": /material/parameters of region '", m.name, "' are out of range: ", problem);
  }
  require(a.W.rows() == N && a.W.cols() == K, where, ": /basis weights must be (", N, ", ", K, ")");
  for (const Cubature* c : {&a.elastic, &a.inertia}) {
    const char* name = c == &a.elastic ? "/cubature/elastic" : "/cubature/inertia";
    require(c->barycentric.rows() == c->size() && c->weights.size() == c->size(), where, ": ", name, " arrays disagree in length");
    require(c->size() == 0 || (c->elements.minCoeff() >= 0 && c->elements.maxCoeff() < T), where, ": ", name,
            "/elements indexes outside [0, ", T, ")");
    require(c->size() == 0 || c->weights.minCoeff() >= 0, where, ": ", name, "/weights must be non-negative");
  }
}

Avatar read_avatar(const std::string& path) {
  // A file on which libhdf5 itself crashes is refused, not read (io/crash_isolation.hpp).
  return io::read_in_child_first(path, [&] { return read_avatar_in_this_process(path); });
}

}  // namespace sflsh
