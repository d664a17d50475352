#include "sflsh/geometry/grid_sdf.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/io/crash_isolation.hpp"

namespace sflsh::geometry {
namespace {

constexpr const char* kFormat = "sflsh grid sdf";
constexpr int kVersion = 1;

/// Catmull–Rom weights of the four nodes i−1, i, i+1, i+2 at t ∈ [0, 1] in
/// cell i, with their first and second derivatives in t, and the nodes they
/// fall on after folding ghost nodes (outside [0, n)) in by linear
/// extrapolation: v₋₁ = 2v₀ − v₁, vₙ = 2vₙ₋₁ − vₙ₋₂.
struct AxisStencil {
  std::array<int, 4> node{};
  std::array<double, 4> w{}, dw{}, ddw{};
};

AxisStencil axis_stencil(int cell, double t, int n) {
  const double t2 = t * t, t3 = t2 * t;
  const std::array<double, 4> w = {0.5 * (-t3 + 2 * t2 - t), 0.5 * (3 * t3 - 5 * t2 + 2), 0.5 * (-3 * t3 + 4 * t2 + t),
                                   0.5 * (t3 - t2)};
  const std::array<double, 4> dw = {0.5 * (-3 * t2 + 4 * t - 1), 0.5 * (9 * t2 - 10 * t), 0.5 * (-9 * t2 + 8 * t + 1),
                                    0.5 * (3 * t2 - 2 * t)};
  const std::array<double, 4> ddw = {-3 * t + 2, 9 * t - 5, -9 * t + 4, 3 * t - 1};
  AxisStencil s;
  for (int a = 0; a < 4; ++a) s.node[a] = cell - 1 + a;
  s.w = w;
  s.dw = dw;
  s.ddw = ddw;
  auto fold = [&](int ghost, int near, int far) {
    // Ghost weight c moves to near (2c) and far (−c).
    for (auto* arr : {&s.w, &s.dw, &s.ddw}) {
      (*arr)[near] += 2 * (*arr)[ghost];
      (*arr)[far] -= (*arr)[ghost];
      (*arr)[ghost] = 0;
    }
    s.node[ghost] = s.node[near];
  };
  if (s.node[0] < 0) fold(0, 1, 2);
  if (s.node[3] > n - 1) fold(3, 2, 1);
  return s;
}

}  // namespace

GridSdf::GridSdf(const Vec3& origin, double spacing, const Eigen::Vector3i& dims, std::vector<double> values)
    : origin_(origin), h_(spacing), dims_(dims), values_(std::move(values)) {
  require(dims.minCoeff() >= 2, "grid SDF: dims must be >= 2 along every axis, got ", dims.transpose());
  require(std::isfinite(spacing) && spacing > 0, "grid SDF: spacing must be finite and > 0, got ", spacing);
  require(origin.allFinite(), "grid SDF: origin must be finite");
  const std::size_t n = std::size_t(dims.x()) * std::size_t(dims.y()) * std::size_t(dims.z());
  require(values_.size() == n, "grid SDF: ", values_.size(), " values for dims ", dims.transpose(), " (expected ", n, ")");
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(values_[i])) fail("grid SDF: value ", i, " is not finite");
}

Aabb GridSdf::bounds() const { return Aabb(origin_, origin_ + h_ * (dims_ - Eigen::Vector3i::Ones()).cast<double>()); }

SdfSample GridSdf::interpolate(const Vec3& p, bool want_hessian) const {
  std::array<AxisStencil, 3> st;
  for (int a = 0; a < 3; ++a) {
    const double u = (p[a] - origin_[a]) / h_;
    const int cell = std::clamp(int(std::floor(u)), 0, dims_[a] - 2);
    st[a] = axis_stencil(cell, u - cell, dims_[a]);
  }
  SdfSample s;
  Vec3 g = Vec3::Zero();
  Mat3 H = Mat3::Zero();
  double v = 0;
  for (int c = 0; c < 4; ++c) {
    for (int b = 0; b < 4; ++b) {
      for (int a = 0; a < 4; ++a) {
        const double f = node_value(st[0].node[a], st[1].node[b], st[2].node[c]);
        const double wx = st[0].w[a], wy = st[1].w[b], wz = st[2].w[c];
        const double dx = st[0].dw[a], dy = st[1].dw[b], dz = st[2].dw[c];
        v += f * wx * wy * wz;
        g += f * Vec3(dx * wy * wz, wx * dy * wz, wx * wy * dz);
        if (want_hessian) {
          H(0, 0) += f * st[0].ddw[a] * wy * wz;
          H(1, 1) += f * wx * st[1].ddw[b] * wz;
          H(2, 2) += f * wx * wy * st[2].ddw[c];
          H(0, 1) += f * dx * dy * wz;
          H(0, 2) += f * dx * wy * dz;
          H(1, 2) += f * wx * dy * dz;
        }
      }
    }
  }
  s.distance = v;
  s.gradient = g / h_;  // d/dx = (1/h) d/du
  s.has_hessian = true;
  if (want_hessian) {
    H(1, 0) = H(0, 1);
    H(2, 0) = H(0, 2);
    H(2, 1) = H(1, 2);
    s.hessian = H / (h_ * h_);
  }
  return s;
}

SdfSample GridSdf::evaluate(const Vec3& x, bool want_hessian) const {
  const Aabb box = bounds();
  const Vec3 p = x.cwiseMax(box.min).cwiseMin(box.max);
  SdfSample s = interpolate(p, want_hessian);
  const Vec3 out = x - p;
  const double dist = out.norm();
  if (dist == 0) return s;
  // φ(x) = φ(p(x)) + |x − p(x)|, ∂p/∂x = diag(not clamped) = I − C.
  Mat3 C = Mat3::Zero();
  for (int a = 0; a < 3; ++a) C(a, a) = out[a] != 0 ? 1.0 : 0.0;
  const Mat3 I_C = Mat3::Identity() - C;
  const Vec3 w = out / dist;
  s.distance += dist;
  s.gradient = I_C * s.gradient + w;
  if (want_hessian) s.hessian = I_C * s.hessian * I_C + (C - w * w.transpose()) / dist;
  return s;
}

void write_grid_sdf(const GridSdf& grid, const std::string& path) {
  io::Hdf5File f(path, io::Hdf5File::Mode::Write);
  f.write_string("/meta/format", kFormat);
  f.write_scalar("/meta/version", std::int64_t(kVersion));
  f.write_matrix("/sdf/origin", grid.origin().transpose());
  f.write_scalar("/sdf/spacing", grid.spacing());
  f.write_matrix("/sdf/dims", grid.dims().transpose());
  const Eigen::Vector3i d = grid.dims();
  f.write_nd("/sdf/values", grid.values().data(), {d.z(), d.y(), d.x()});
  f.commit();
}

static GridSdf read_grid_sdf_in_this_process(const std::string& path) {
  io::Hdf5File f(path, io::Hdf5File::Mode::Read);
  require(f.has("/meta/format") && f.read_string("/meta/format") == kFormat, path,
          ": /meta/format is not '", kFormat, "' (not a grid SDF file)");
  const double version = f.read_scalar("/meta/version");
  require(version == kVersion, path, ": /meta/version is ", version, ", this build reads version ", kVersion);
  const Vec3 origin = f.read_matrix("/sdf/origin", 1, 3).row(0).transpose();
  const double spacing = f.read_scalar("/sdf/spacing");
  require(std::isfinite(spacing) && spacing > 0, path, ": /sdf/spacing must be finite and > 0, got ", spacing);
  const Eigen::Vector3i dims = f.read_int_matrix("/sdf/dims", 1, 3).row(0).transpose();
  require(dims.minCoeff() >= 2, path, ": /sdf/dims must be >= 2 along every axis, got ", dims.transpose());
  std::vector<double> values = f.read_nd("/sdf/values", {dims.z(), dims.y(), dims.x()});
  return GridSdf(origin, spacing, dims, std::move(values));
}

GridSdf read_grid_sdf(const std::string& path) {
  // A file on which libhdf5 itself crashes is refused, not read (io/crash_isolation.hpp).
  return io::read_in_child_first(path, [&] { return read_grid_sdf_in_this_process(path); });
}

}  // namespace sflsh::geometry
