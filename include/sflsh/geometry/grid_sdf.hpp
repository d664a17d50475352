#pragma once
// A signed distance field sampled on a regular grid (baked mesh SDFs,
// mesh/mesh_sdf_bake.hpp). Between nodes it is the tensor-product
// Catmull–Rom (cubic Hermite) interpolant: it passes through the node values,
// is C¹ (φ and ∇φ continuous across cells, unlike trilinear), and reproduces
// linear fields exactly (ghost nodes beyond the grid are extrapolated
// linearly). evaluate() returns the exact gradient and Hessian of that
// interpolant, so they agree with finite differences of distance().
// Outside the grid box, φ(x) = φ(p) + |x − p| with p the clamped point (a
// continuous extension; the grid should be padded so that contact never
// happens there).
//
// File (HDF5, names fixed):
//   /meta/format   "sflsh grid sdf"      /meta/version  1
//   /sdf/origin    (1,3)  m, world position of node (0,0,0) in the local frame
//   /sdf/spacing   scalar m, node spacing (cubic voxels)
//   /sdf/dims      (1,3)  int, nodes along x, y, z (each >= 2)
//   /sdf/values    (nz,ny,nx) m, φ at node (i,j,k) = values[k][j][i]
#include <string>
#include <vector>

#include "sflsh/geometry/sdf.hpp"

namespace sflsh::geometry {

class GridSdf : public Sdf {
 public:
  /// Node (i, j, k) sits at origin + spacing·(i, j, k) and holds
  /// values[i + nx·(j + ny·k)] (m). Throws unless each dim is >= 2, spacing
  /// is finite and > 0, origin and values are finite and values has nx·ny·nz
  /// entries.
  GridSdf(const Vec3& origin, double spacing, const Eigen::Vector3i& dims, std::vector<double> values);

  SdfSample evaluate(const Vec3& x, bool want_hessian = false) const override;
  /// The grid's box (its corner nodes).
  Aabb bounds() const override;

  const Vec3& origin() const { return origin_; }
  double spacing() const { return h_; }
  const Eigen::Vector3i& dims() const { return dims_; }
  const std::vector<double>& values() const { return values_; }
  /// φ at node (i, j, k) (indices are not checked).
  double node_value(int i, int j, int k) const { return values_[index(i, j, k)]; }
  /// Position of node (i, j, k) (m, local frame).
  Vec3 node_position(int i, int j, int k) const { return origin_ + h_ * Vec3(i, j, k); }

 private:
  std::size_t index(int i, int j, int k) const {
    return std::size_t(i) + std::size_t(dims_.x()) * (std::size_t(j) + std::size_t(dims_.y()) * std::size_t(k));
  }
  /// The interpolant and its derivatives at a point inside the grid box.
  SdfSample interpolate(const Vec3& p, bool want_hessian) const;

  Vec3 origin_;
  double h_;
  Eigen::Vector3i dims_;
  std::vector<double> values_;
};

/// Writes `grid` to the HDF5 file `path` (format above; atomic: nothing is
/// left at `path` on failure).
void write_grid_sdf(const GridSdf& grid, const std::string& path);

/// Reads a grid written by write_grid_sdf. Throws one sflsh::Error naming the
/// file and the dataset for a missing or truncated file, a wrong format tag or
/// version, dims < 2 or not matching the values' shape, a non-positive
/// spacing, or a non-finite value.
GridSdf read_grid_sdf(const std::string& path);

}  // namespace sflsh::geometry
