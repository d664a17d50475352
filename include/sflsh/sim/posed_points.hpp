#pragma once
// Body points carried by skinning and the reduced soft-tissue basis (DESIGN.md §4):
//   x_world(q) = Σ_j w_j G_j (x̄ + U(x̄) z + b),   U(x̄) z = Σ_k W_k(x̄) z_k,
// precomputed as sparse rows (only the bones with non-zero skinning weight and
// the handles with non-zero basis weight) so evaluation costs O(nnz) per point.
//
// Dirichlet roles: rows of W at nodes whose role is not Simulated (Bone,
// Skinned) are ignored, i.e. u = 0 there, whatever the stored W says.
//
// Pose blend shapes b: the asset stores them only for the surface
// (surface_posedirs), so volume points (cubature samples) carry none and the
// dynamics never see them; surface output adds b(θ) evaluated at the current
// bones (an offset constant with respect to the step, not differentiated).
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/sim/configuration.hpp"

namespace sflsh {

class PosedPoints {
 public:
  PosedPoints() = default;

  /// Points at cubature samples: skinning weights and basis rows interpolated
  /// barycentrically from the sample's tet nodes.
  static PosedPoints at_cubature(const Avatar& avatar, const Cubature& cubature);
  /// The skin surface vertices: x̄ = surface_rest, skinning weights =
  /// surface_weights, basis rows interpolated through (surface_tet, surface_bary).
  static PosedPoints at_surface(const Avatar& avatar);

  /// The points `rows` (indices into this set, in that order) as a set of their own.
  PosedPoints subset(const std::vector<int>& rows) const;
  /// A copy whose basis rows keep only each point's `max_handles` (>= 1)
  /// largest weights, scaled so that every row's sum is unchanged. The
  /// largest weight dropped from a row (before scaling) goes to `max_dropped`
  /// when non-null: the bound on how far a point moves differently, per metre
  /// of handle displacement.
  PosedPoints with_truncated_rows(int max_handles, double* max_dropped = nullptr) const;

  int size() const { return int(x_unposed_.rows()); }
  /// World position of point p for configuration q (m).
  Vec3 world_point(int p, const Configuration& q) const;
  /// The bone with the largest skinning weight at point p (−1 if it has none).
  int dominant_bone(int p) const;
  /// Point p's sparse rows: bones (index, skinning weight) and handles
  /// (index, basis weight); pointers into this set, valid while it lives.
  struct Rows {
    const int* bones;
    const double* bone_weights;
    int num_bones;
    const int* handles;
    const double* handle_weights;
    int num_handles;
  };
  Rows rows(int p) const {
    return {bone_index_.data() + bone_start_[p], bone_weight_.data() + bone_start_[p],
            bone_start_[p + 1] - bone_start_[p],  handle_index_.data() + handle_start_[p],
            handle_weight_.data() + handle_start_[p], handle_start_[p + 1] - handle_start_[p]};
  }
  /// x̄ + U z of point p (m, unposed).
  Vec3 unposed_displaced(int p, const VecX& z) const { return local(p, z); }
  /// #P by 3 unposed rest positions x̄ (m).
  const Points& unposed() const { return x_unposed_; }

  /// #P by 3 soft displacement u = U z (m, unposed space) for z (3K).
  Points soft_displacement(const VecX& z) const;
  /// #P by 3 world positions for configuration q; `offsets` (#P by 3, e.g. pose
  /// blend shapes) is added to x̄ + U z before skinning when non-null.
  Points world(const Configuration& q, const Points* offsets = nullptr) const;

  /// Adds Σ_p (∂x_p/∂δ)ᵀ f_p to `grad` (layout.size()), where f is #P by 3 and δ
  /// the tangent step at q (configuration.hpp): the generalized force of f.
  void add_jacobian_transpose(const Configuration& q, const DofLayout& layout, const Points& f, Eigen::Ref<VecX> grad) const;
  /// Dense Jacobian J (3P by layout.size()): row 3p + c = ∂x_p[c]/∂δ at q.
  /// Row block p is multiplied by row_scale[p] when row_scale is non-empty.
  void jacobian(const Configuration& q, const DofLayout& layout, MatX& J, const VecX& row_scale = VecX()) const;
  /// Jacobian of point p restricted to the DoFs it depends on: J (3 by #cols)
  /// with cols[i] = the layout index of column i (bones with weight, then handles).
  void local_jacobian(int p, const Configuration& q, const DofLayout& layout, Eigen::Matrix<double, 3, Eigen::Dynamic>& J,
                      std::vector<int>& cols) const;
  /// Number of DoFs point p depends on under `layout`.
  int local_size(int p, const DofLayout& layout) const {
    return (layout.bones_dynamic ? 6 * (bone_start_[p + 1] - bone_start_[p]) : 0) +
           3 * (handle_start_[p + 1] - handle_start_[p]);
  }

 private:
  Vec3 local(int p, const VecX& z) const;  // x̄ + U z

  Points x_unposed_;
  // CSR rows: bones (index, weight) and handles (index, weight) per point.
  std::vector<int> bone_start_{0}, bone_index_;
  std::vector<double> bone_weight_;
  std::vector<int> handle_start_{0}, handle_index_;
  std::vector<double> handle_weight_;
};

/// #V by 3 pose blend-shape offsets of the surface, b = surface_posedirs ·
/// pose_feature, with the pose feature (flattened row-major R_rel − I of joints
/// 1..23) taken from the relative rotations of `bones` (24 world transforms).
/// Zero when the asset has no pose blend shapes.
Points surface_pose_offsets(const Avatar& avatar, const std::vector<Isometry>& bones);

/// Σ_j w_j R_j, the blend of the bones' rotations by one row of skinning
/// weights: how an unposed offset of a skinned point turns into a world one.
Mat3 skinning_rotation_blend(const Eigen::Ref<const Eigen::RowVectorXd>& weights, const std::vector<Isometry>& bones);

/// 24 by 3 world joint positions G_j · joints_rest[j] (m): joint_world_positions on the avatar.
Points posed_joints(const Avatar& avatar, const std::vector<Isometry>& bones);

}  // namespace sflsh
