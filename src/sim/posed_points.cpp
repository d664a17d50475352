#include "sflsh/sim/posed_points.hpp"

#include <algorithm>
#include <map>

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"
#include "sflsh/sim/skeleton_pose.hpp"

namespace sflsh {
namespace {

constexpr double kWeightEps = 1e-12;  // weights below this are structural zeros

/// Appends the non-zero entries of `row` (index → weight) to a CSR structure.
void append_row(const std::map<int, double>& row, std::vector<int>& start, std::vector<int>& index,
                std::vector<double>& weight) {
  for (const auto& [i, w] : row)
    if (std::abs(w) > kWeightEps) {
      index.push_back(i);
      weight.push_back(w);
    }
  start.push_back(int(index.size()));
}

/// Basis row of a point inside tet `t` at barycentric `bary` (Dirichlet nodes skipped).
std::map<int, double> basis_row(const Avatar& a, int t, const Eigen::Ref<const Eigen::RowVectorXd>& bary) {
  std::map<int, double> row;
  for (int c = 0; c < 4; ++c) {
    const int n = a.tet.elements(t, c);
    if (a.node_role.size() && a.node_role[n] != int(NodeRole::Simulated)) continue;
    if (bary[c] == 0.0) continue;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, n); it; ++it)
      row[int(it.col())] += bary[c] * it.value();
  }
  return row;
}

void check_common(const Avatar& a, const char* what) {
  require(a.tet.num_nodes() > 0, what, ": avatar has no tet nodes");
  require(a.node_weights.rows() == a.tet.num_nodes(), what, ": node_weights has ", a.node_weights.rows(),
          " rows, expected #N = ", a.tet.num_nodes());
  require(a.W.rows() == a.tet.num_nodes() && a.W.cols() == a.num_handles(), what, ": W is ", a.W.rows(), " by ",
          a.W.cols(), ", expected #N = ", a.tet.num_nodes(), " by #K = ", a.num_handles());
  require(a.node_role.size() == 0 || a.node_role.size() == a.tet.num_nodes(), what, ": node_role has ",
          a.node_role.size(), " entries, expected #N = ", a.tet.num_nodes());
}

}  // namespace

PosedPoints PosedPoints::at_cubature(const Avatar& a, const Cubature& cub) {
  check_common(a, "PosedPoints::at_cubature");
  require(cub.barycentric.rows() == cub.size() && cub.barycentric.cols() == 4 && cub.weights.size() == cub.size(),
          "PosedPoints::at_cubature: cubature arrays disagree (", cub.size(), " elements, ", cub.barycentric.rows(),
          " by ", cub.barycentric.cols(), " barycentric, ", cub.weights.size(), " weights)");
  PosedPoints P;
  P.x_unposed_.resize(cub.size(), 3);
  for (int s = 0; s < cub.size(); ++s) {
    const int t = cub.elements[s];
    require(t >= 0 && t < a.tet.num_elements(), "PosedPoints::at_cubature: sample ", s, " has tet ", t,
            ", expected in [0, ", a.tet.num_elements(), ")");
    Vec3 x = Vec3::Zero();
    std::map<int, double> bones;
    for (int c = 0; c < 4; ++c) {
      const int n = a.tet.elements(t, c);
      const double b = cub.barycentric(s, c);
      x += b * a.tet.nodes.row(n).transpose();
      for (int j = 0; j < a.node_weights.cols(); ++j)
        if (a.node_weights(n, j) != 0.0) bones[j] += b * a.node_weights(n, j);
    }
    P.x_unposed_.row(s) = x.transpose();
    append_row(bones, P.bone_start_, P.bone_index_, P.bone_weight_);
    append_row(basis_row(a, t, cub.barycentric.row(s)), P.handle_start_, P.handle_index_, P.handle_weight_);
  }
  return P;
}

PosedPoints PosedPoints::at_surface(const Avatar& a) {
  check_common(a, "PosedPoints::at_surface");
  const int V = int(a.surface_rest.rows());
  require(a.surface_weights.rows() == V && a.surface_tet.size() == V && a.surface_bary.rows() == V &&
              a.surface_bary.cols() == 4,
          "PosedPoints::at_surface: surface arrays disagree with #V = ", V, " (surface_weights ",
          a.surface_weights.rows(), ", surface_tet ", a.surface_tet.size(), ", surface_bary ", a.surface_bary.rows(),
          " by ", a.surface_bary.cols(), ")");
  PosedPoints P;
  P.x_unposed_ = a.surface_rest;
  for (int v = 0; v < V; ++v) {
    std::map<int, double> bones;
    for (int j = 0; j < a.surface_weights.cols(); ++j)
      if (a.surface_weights(v, j) != 0.0) bones[j] = a.surface_weights(v, j);
    append_row(bones, P.bone_start_, P.bone_index_, P.bone_weight_);
    const int t = a.surface_tet[v];
    require(t >= 0 && t < a.tet.num_elements(), "PosedPoints::at_surface: surface_tet[", v, "] = ", t,
            ", expected in [0, ", a.tet.num_elements(), ")");
    append_row(basis_row(a, t, a.surface_bary.row(v)), P.handle_start_, P.handle_index_, P.handle_weight_);
  }
  return P;
}

PosedPoints PosedPoints::subset(const std::vector<int>& rows) const {
  PosedPoints P;
  P.x_unposed_.resize(int(rows.size()), 3);
  for (size_t i = 0; i < rows.size(); ++i) {
    const int p = rows[i];
    require(p >= 0 && p < size(), "PosedPoints::subset: row ", p, " out of [0, ", size(), ")");
    P.x_unposed_.row(int(i)) = x_unposed_.row(p);
    for (int e = bone_start_[p]; e < bone_start_[p + 1]; ++e) {
      P.bone_index_.push_back(bone_index_[e]);
      P.bone_weight_.push_back(bone_weight_[e]);
    }
    P.bone_start_.push_back(int(P.bone_index_.size()));
    for (int e = handle_start_[p]; e < handle_start_[p + 1]; ++e) {
      P.handle_index_.push_back(handle_index_[e]);
      P.handle_weight_.push_back(handle_weight_[e]);
    }
    P.handle_start_.push_back(int(P.handle_index_.size()));
  }
  return P;
}

PosedPoints PosedPoints::with_truncated_rows(int max_handles, double* max_dropped) const {
  require(max_handles >= 1, "PosedPoints::with_truncated_rows: max_handles = ", max_handles, ", expected >= 1");
  PosedPoints P = *this;
  P.handle_start_.assign(1, 0);
  P.handle_index_.clear();
  P.handle_weight_.clear();
  double worst = 0;
  std::vector<std::pair<double, int>> row;
  for (int p = 0; p < size(); ++p) {
    row.clear();
    double total = 0, kept = 0;
    for (int e = handle_start_[p]; e < handle_start_[p + 1]; ++e) {
      row.emplace_back(handle_weight_[e], handle_index_[e]);
      total += handle_weight_[e];
    }
    const size_t n = std::min<size_t>(row.size(), size_t(max_handles));
    std::partial_sort(row.begin(), row.begin() + n, row.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    for (size_t i = 0; i < n; ++i) kept += row[i].first;
    worst = std::max(worst, total - kept);
    std::sort(row.begin(), row.begin() + n, [](const auto& a, const auto& b) { return a.second < b.second; });
    const double scale = kept > 0 ? total / kept : 1.0;
    for (size_t i = 0; i < n; ++i) {
      P.handle_index_.push_back(row[i].second);
      P.handle_weight_.push_back(row[i].first * scale);
    }
    P.handle_start_.push_back(int(P.handle_index_.size()));
  }
  if (max_dropped) *max_dropped = worst;
  return P;
}

Vec3 PosedPoints::world_point(int p, const Configuration& q) const {
  const Vec3 y = local(p, q.z);
  Vec3 x = Vec3::Zero();
  for (int e = bone_start_[p]; e < bone_start_[p + 1]; ++e) x += bone_weight_[e] * (q.bones[bone_index_[e]] * y);
  return x;
}

int PosedPoints::dominant_bone(int p) const {
  int best = -1;
  double w = 0;
  for (int e = bone_start_[p]; e < bone_start_[p + 1]; ++e)
    if (bone_weight_[e] > w) {
      w = bone_weight_[e];
      best = bone_index_[e];
    }
  return best;
}

Vec3 PosedPoints::local(int p, const VecX& z) const {
  Vec3 y = x_unposed_.row(p).transpose();
  for (int e = handle_start_[p]; e < handle_start_[p + 1]; ++e)
    y += handle_weight_[e] * z.segment<3>(3 * handle_index_[e]);
  return y;
}

Points PosedPoints::soft_displacement(const VecX& z) const {
  Points u(size(), 3);
  for (int p = 0; p < size(); ++p) u.row(p) = (local(p, z) - x_unposed_.row(p).transpose()).transpose();
  return u;
}

Points PosedPoints::world(const Configuration& q, const Points* offsets) const {
  Points x(size(), 3);
  for (int p = 0; p < size(); ++p) {
    if (!offsets) {
      x.row(p) = world_point(p, q).transpose();
      continue;
    }
    const Vec3 y = local(p, q.z) + offsets->row(p).transpose();
    Vec3 xp = Vec3::Zero();
    for (int e = bone_start_[p]; e < bone_start_[p + 1]; ++e) xp += bone_weight_[e] * (q.bones[bone_index_[e]] * y);
    x.row(p) = xp.transpose();
  }
  return x;
}

void PosedPoints::add_jacobian_transpose(const Configuration& q, const DofLayout& layout, const Points& f,
                                         Eigen::Ref<VecX> grad) const {
  const int z0 = layout.z_offset();
  for (int p = 0; p < size(); ++p) {
    const Vec3 y = local(p, q.z);
    const Vec3 fp = f.row(p).transpose();
    Mat3 A = Mat3::Zero();  // Σ_j w_j R_j = ∂x/∂y
    for (int e = bone_start_[p]; e < bone_start_[p + 1]; ++e) {
      const int j = bone_index_[e];
      const double w = bone_weight_[e];
      A += w * q.bones[j].linear();
      if (layout.bones_dynamic) {
        // ∂x/∂ω_j = −[w_j G_j y]×, ∂x/∂v_j = w_j I  ⇒  Jᵀf = (p_j × f, w_j f).
        const Vec3 pj = w * (q.bones[j] * y);
        grad.segment<3>(layout.bone_offset(j)) += pj.cross(fp);
        grad.segment<3>(layout.bone_offset(j) + 3) += w * fp;
      }
    }
    const Vec3 Atf = A.transpose() * fp;
    for (int e = handle_start_[p]; e < handle_start_[p + 1]; ++e)
      grad.segment<3>(z0 + 3 * handle_index_[e]) += handle_weight_[e] * Atf;
  }
}

void PosedPoints::local_jacobian(int p, const Configuration& q, const DofLayout& layout,
                                 Eigen::Matrix<double, 3, Eigen::Dynamic>& J, std::vector<int>& cols) const {
  const int nb = layout.bones_dynamic ? bone_start_[p + 1] - bone_start_[p] : 0;
  const int nh = handle_start_[p + 1] - handle_start_[p];
  J.resize(3, 6 * nb + 3 * nh);
  cols.resize(6 * nb + 3 * nh);
  const Vec3 y = local(p, q.z);
  Mat3 A = Mat3::Zero();  // Σ_j w_j R_j = ∂x/∂y
  int col = 0;
  for (int e = bone_start_[p]; e < bone_start_[p + 1]; ++e) {
    const int j = bone_index_[e];
    const double w = bone_weight_[e];
    A += w * q.bones[j].linear();
    if (layout.bones_dynamic) {
      // ∂x/∂ω_j = −[w_j G_j y]×, ∂x/∂v_j = w_j I (configuration.hpp).
      J.block<3, 3>(0, col) = -hat(w * (q.bones[j] * y));
      J.block<3, 3>(0, col + 3) = w * Mat3::Identity();
      for (int i = 0; i < 6; ++i) cols[col + i] = layout.bone_offset(j) + i;
      col += 6;
    }
  }
  for (int e = handle_start_[p]; e < handle_start_[p + 1]; ++e) {
    J.block<3, 3>(0, col) = handle_weight_[e] * A;
    for (int i = 0; i < 3; ++i) cols[col + i] = layout.z_offset() + 3 * handle_index_[e] + i;
    col += 3;
  }
}

void PosedPoints::jacobian(const Configuration& q, const DofLayout& layout, MatX& J, const VecX& row_scale) const {
  J.setZero(3 * size(), layout.size());
  Eigen::Matrix<double, 3, Eigen::Dynamic> Jp;
  std::vector<int> cols;
  for (int p = 0; p < size(); ++p) {
    local_jacobian(p, q, layout, Jp, cols);
    const double s = row_scale.size() ? row_scale[p] : 1.0;
    for (int c = 0; c < int(cols.size()); ++c) J.block<3, 1>(3 * p, cols[c]) += s * Jp.col(c);
  }
}

Points surface_pose_offsets(const Avatar& a, const std::vector<Isometry>& bones) {
  const int V = int(a.surface_rest.rows());
  Points b = Points::Zero(V, 3);
  if (a.surface_posedirs.size() == 0) return b;
  require(a.surface_posedirs.rows() == 3 * V && a.surface_posedirs.cols() == 207,
          "surface_pose_offsets: surface_posedirs is ", a.surface_posedirs.rows(), " by ", a.surface_posedirs.cols(),
          ", expected #V*3 = ", 3 * V, " by 207");
  require(bones.size() == 24 && a.parents.size() == 24, "surface_pose_offsets: expected 24 bones and parents, got ",
          bones.size(), " and ", a.parents.size());
  VecX feature(207);
  for (int j = 1; j < 24; ++j) {
    // G_j's linear part is the joint's world rotation; relative = parentᵀ · own.
    const Mat3 R = bones[a.parents[j]].linear().transpose() * bones[j].linear() - Mat3::Identity();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) feature[9 * (j - 1) + 3 * r + c] = R(r, c);
  }
  const VecX flat = a.surface_posedirs * feature;  // row 3v + c
  for (int v = 0; v < V; ++v) b.row(v) = flat.segment<3>(3 * v).transpose();
  return b;
}

Mat3 skinning_rotation_blend(const Eigen::Ref<const Eigen::RowVectorXd>& weights, const std::vector<Isometry>& bones) {
  Mat3 A = Mat3::Zero();
  for (int j = 0; j < weights.size(); ++j)
    if (weights[j] != 0.0) A += weights[j] * bones[j].linear();
  return A;
}

Points posed_joints(const Avatar& a, const std::vector<Isometry>& bones) {
  return joint_world_positions(bones, a.joints_rest);
}

}  // namespace sflsh
