// The template volume's cache file (HDF5): writing, and reading with every
// index range checked.
#include <algorithm>

#include "sflsh/core/error.hpp"
#include "sflsh/io/crash_isolation.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/volume/body_regions.hpp"
#include "sflsh/volume/template_volume.hpp"

namespace sflsh {

void save_template_volume(const TemplateVolume& tv, const std::string& path) {
  io::Hdf5File h5(path, io::Hdf5File::Mode::Write);
  const std::string g = "/template/";
  h5.write_scalar(g + "format_version", std::int64_t(tv.format_version));
  h5.write_string(g + "model_hash", tv.model_hash);
  h5.write_string(g + "units", "metres");
  h5.write_scalar(g + "inner_depth", tv.inner_depth);
  const int nS = int(tv.segments.size());
  Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> seg(nS, 2);
  VecX ext(nS);
  for (int s = 0; s < nS; ++s) {
    seg(s, 0) = tv.segments[s].joint;
    seg(s, 1) = tv.segments[s].child;
    ext[s] = tv.segments[s].extension;
  }
  h5.write_matrix(g + "segments/joints", seg);
  h5.write_matrix(g + "segments/extension", ext);
  h5.write_matrix(g + "surface/coefficients", tv.surface.coefficients);
  h5.write_matrix(g + "surface/segment", tv.surface.segment);
  h5.write_matrix(g + "surface/skeleton_points", tv.surface.skeleton_points);
  h5.write_matrix(g + "surface/thickness", tv.surface.thickness);
  h5.write_matrix(g + "tet/nodes", tv.tet.nodes);
  h5.write_matrix(g + "tet/elements", tv.tet.elements);
  h5.write_matrix(g + "tet/outer_nodes", tv.outer_nodes);
  h5.write_matrix(g + "tet/inner_nodes", tv.inner_nodes);
  h5.write_matrix(g + "node/face", tv.node_face);
  h5.write_matrix(g + "node/face_bary", tv.node_face_bary);
  h5.write_matrix(g + "node/skeleton_coefficients", tv.node_skeleton_coefficients);
  h5.write_matrix(g + "node/depth", tv.node_depth);
  h5.write_matrix(g + "node/residual", tv.node_residual);
  h5.write_matrix(g + "node/segment", tv.node_segment);
  h5.write_matrix(g + "node/weights", tv.node_weights);
  h5.write_matrix(g + "node/role", tv.node_role);
  h5.write_matrix(g + "tet/region", tv.tet_region);
  const int N = tv.tet.num_nodes(), nB = int(tv.node_shapedirs.size());
  std::vector<double> sd(size_t(nB) * N * 3);
  for (int b = 0; b < nB; ++b) std::copy(tv.node_shapedirs[b].data(), tv.node_shapedirs[b].data() + 3 * N, sd.begin() + size_t(b) * 3 * N);
  h5.write_nd(g + "node/shapedirs", sd.data(), {nB, N, 3});
  if (tv.node_posedirs.size() > 0) h5.write_matrix(g + "node/posedirs", tv.node_posedirs);
  h5.commit();
}

static TemplateVolume load_template_volume_in_this_process(const std::string& path) {
  io::Hdf5File h5(path, io::Hdf5File::Mode::Read);
  const std::string g = "/template/";
  TemplateVolume tv;
  const int version = h5.read_int_scalar(g + "format_version", 0, 1 << 20);
  require(version == kTemplateVolumeFormatVersion, path, ": dataset ", g, "format_version is ", version,
          ", expected ", kTemplateVolumeFormatVersion);
  tv.model_hash = h5.read_string(g + "model_hash");
  tv.inner_depth = h5.read_scalar(g + "inner_depth");
  const auto seg = h5.read_int_matrix(g + "segments/joints", -1, 2);
  const MatXr ext = h5.read_matrix(g + "segments/extension", seg.rows(), 1);
  for (int s = 0; s < seg.rows(); ++s) tv.segments.push_back(BoneSegment{seg(s, 0), seg(s, 1), ext(s, 0)});
  tv.tet.nodes = h5.read_as<Points>(g + "tet/nodes", -1, 3);
  tv.tet.elements = h5.read_int_matrix(g + "tet/elements", -1, 4);
  const int N = tv.tet.num_nodes(), T = tv.tet.num_elements();
  require(N > 0 && T > 0, path, ": dataset ", g, "tet/elements is empty");
  require(tv.tet.elements.minCoeff() >= 0 && tv.tet.elements.maxCoeff() < N, path, ": dataset ", g,
          "tet/elements has node indices outside [0, ", N, ")");
  auto vec_i = [&](const std::string& name, long rows) -> VecXi {
    return h5.read_int_matrix(g + name, rows, 1).col(0);
  };
  tv.surface.coefficients = h5.read_matrix(g + "surface/coefficients");
  const long nV = tv.surface.coefficients.rows(), J = tv.surface.coefficients.cols();
  tv.surface.segment = vec_i("surface/segment", nV);
  tv.surface.skeleton_points = h5.read_as<Points>(g + "surface/skeleton_points", nV, 3);
  tv.surface.thickness = h5.read_matrix(g + "surface/thickness", nV, 1).col(0);
  tv.outer_nodes = vec_i("tet/outer_nodes", -1);
  tv.inner_nodes = vec_i("tet/inner_nodes", -1);
  tv.node_face = vec_i("node/face", N);
  tv.node_face_bary = h5.read_as<Points>(g + "node/face_bary", N, 3);
  tv.node_skeleton_coefficients = h5.read_matrix(g + "node/skeleton_coefficients", N, J);
  tv.node_depth = h5.read_matrix(g + "node/depth", N, 1).col(0);
  tv.node_residual = h5.read_as<Points>(g + "node/residual", N, 3);
  tv.node_segment = vec_i("node/segment", N);
  tv.node_weights = h5.read_matrix(g + "node/weights", N, J);
  tv.node_role = vec_i("node/role", N);
  tv.tet_region = vec_i("tet/region", T);
  std::vector<std::int64_t> shape;
  const std::vector<double> sd = h5.read_nd(g + "node/shapedirs", {-1, N, 3}, &shape);
  tv.node_shapedirs.assign(shape[0], Points(N, 3));
  for (long b = 0; b < shape[0]; ++b) std::copy(sd.begin() + b * 3 * N, sd.begin() + (b + 1) * 3 * N, tv.node_shapedirs[b].data());
  if (h5.has(g + "node/posedirs")) tv.node_posedirs = h5.read_matrix(g + "node/posedirs", 3 * N, -1);
  // Index ranges that later stages rely on.
  auto in_range = [&](const VecXi& v, long hi, const char* name) {
    require(v.size() == 0 || (v.minCoeff() >= 0 && v.maxCoeff() < hi), path, ": dataset ", g, name,
            " has entries outside [0, ", hi, ")");
  };
  in_range(tv.outer_nodes, N, "tet/outer_nodes");
  in_range(tv.inner_nodes, N, "tet/inner_nodes");
  in_range(tv.surface.segment, long(tv.segments.size()), "surface/segment");
  in_range(tv.node_segment, long(tv.segments.size()), "node/segment");
  in_range(tv.tet_region, long(body_region_names().size()), "tet/region");
  in_range(tv.node_role, 3, "node/role");
  for (const auto& s : tv.segments)
    require(s.joint >= 0 && s.joint < J && s.child < J, path, ": dataset ", g, "segments/joints out of range");
  return tv;
}

TemplateVolume load_template_volume(const std::string& path) {
  // A file on which libhdf5 itself crashes is refused, not read (io/crash_isolation.hpp).
  return io::read_in_child_first(path, [&] { return load_template_volume_in_this_process(path); });
}

}  // namespace sflsh
