// The SMPL forward function (Loper et al. 2015, "SMPL: A Skinned Multi-Person
// Linear Model", §3 eqs. 1-4 and 10), on a BodyModel's arrays:
//   v_shaped  = T̄ + B_S(β)                         (shape blend shapes, eq. 8)
//   J         = 𝒥 v_shaped                          (joint regressor, eq. 10)
//   v_unposed = v_shaped + B_P(θ)                   (pose blend shapes, eq. 9:
//               posedirs · vec(R_j(θ) − I), j = 1..23, row-major)
//   G_j       = Π_{k ∈ chain(j)} [R_k | J_k − J_parent(k)]   (eq. 4)
//   A_j       = G_j · [I | −J_j]                    (rest-joint subtraction)
//   v_posed   = Σ_j w_vj A_j v_unposed + translation (LBS, eq. 2; the
//               translation is added after blending, as in SMPL's code)
#include "sflsh/body/body_model.hpp"

#include <algorithm>
#include <cmath>

#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"

namespace sflsh {

namespace {

// Tolerances for validate(): SMPL files store float32 weights whose rows sum
// to 1 up to ~1e-6; 1e-4 leaves room for conversions without hiding real bugs.
constexpr double kWeightSumTolerance = 1e-4;
constexpr double kWeightMinimum = -1e-6;

bool all_finite(const double* p, Eigen::Index n) {
  for (Eigen::Index i = 0; i < n; ++i)
    if (!std::isfinite(p[i])) return false;
  return true;
}

}  // namespace

bool BodyModel::has_pose_blend_shapes() const {
  // Scanned in vectorized blocks with an early exit: real SMPL models answer
  // in the first block; only an all-zero matrix is read completely.
  const Eigen::Map<const Eigen::ArrayXd> all(posedirs.data(), posedirs.size());
  constexpr Eigen::Index kBlock = 1 << 14;
  for (Eigen::Index i = 0; i < all.size(); i += kBlock)
    if (all.segment(i, std::min(kBlock, all.size() - i)).abs().maxCoeff() > 0.0) return true;
  return false;
}

void BodyModel::validate() const {
  const Eigen::Index V = v_template.rows(), J = num_joints();
  require(V > 0, "body model: v_template is empty, expected (V, 3) with V > 0");
  require(all_finite(v_template.data(), v_template.size()), "body model: v_template holds non-finite values");
  require(J == kSmplJoints, "body model: kintree_table has ", J, " joints, expected (2, ", kSmplJoints, ")");
  for (int j = 1; j < J; ++j)
    require(parents[j] >= 0 && parents[j] < j, "body model: kintree_table parent of joint ", j, " is ", parents[j],
            ", expected an index in [0, ", j, ")");
  require(parents[0] == -1, "body model: kintree_table parent of the root is ", parents[0], ", expected -1");
  require(joint_names.empty() || int(joint_names.size()) == J, "body model: joint_names has ", joint_names.size(),
          " entries, expected ", J);

  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int c = 0; c < 3; ++c)
      require(faces(f, c) >= 0 && faces(f, c) < V, "body model: f[", f, ", ", c, "] = ", faces(f, c),
              " is out of range, expected a vertex index in [0, ", V, ")");

  for (size_t b = 0; b < shapedirs.size(); ++b) {
    require(shapedirs[b].rows() == V, "body model: shapedirs direction ", b, " has ", shapedirs[b].rows(),
            " rows, expected shapedirs of shape (", V, ", 3, B)");
    require(all_finite(shapedirs[b].data(), shapedirs[b].size()), "body model: shapedirs direction ", b,
            " holds non-finite values");
  }
  require(shape_meanings.empty() || shape_meanings.size() == shapedirs.size(), "body model: shape_meanings has ",
          shape_meanings.size(), " entries, expected one per shape direction (", shapedirs.size(), ")");

  require(posedirs.size() == 0 || (posedirs.rows() == 3 * V && posedirs.cols() == kSmplPoseFeatures),
          "body model: posedirs is ", posedirs.rows(), " by ", posedirs.cols(), ", expected ", 3 * V, " by ",
          kSmplPoseFeatures, " (file shape (", V, ", 3, ", kSmplPoseFeatures, ")) or empty");
  require(all_finite(posedirs.data(), posedirs.size()), "body model: posedirs holds non-finite values");

  require(J_regressor.rows() == J && J_regressor.cols() == V, "body model: J_regressor is ", J_regressor.rows(),
          " by ", J_regressor.cols(), ", expected (", J, ", ", V, ")");
  for (int k = 0; k < J_regressor.outerSize(); ++k)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(J_regressor, k); it; ++it)
      require(std::isfinite(it.value()), "body model: J_regressor holds a non-finite value at (", it.row(), ", ",
              it.col(), ")");

  require(weights.rows() == V && weights.cols() == J, "body model: weights is ", weights.rows(), " by ",
          weights.cols(), ", expected (", V, ", ", J, ")");
  for (Eigen::Index v = 0; v < V; ++v) {
    double sum = 0.0;
    for (Eigen::Index j = 0; j < J; ++j) {
      const double w = weights(v, j);
      require(std::isfinite(w) && w >= kWeightMinimum, "body model: weights[", v, ", ", j, "] = ", w,
              ", expected a finite value >= 0");
      sum += w;
    }
    require(std::abs(sum - 1.0) <= kWeightSumTolerance, "body model: weights row ", v, " sums to ", sum,
            ", expected 1 (within ", kWeightSumTolerance, ")");
  }
}

Points shape_vertices(const BodyModel& model, const VecX& betas) {
  require(betas.size() <= model.num_betas(), "betas: ", betas.size(), " values given, the model '", model.source,
          "' has only ", model.num_betas(), " shape directions");
  Points v = model.v_template;
  for (Eigen::Index b = 0; b < betas.size(); ++b)
    if (betas[b] != 0.0) v.noalias() += betas[b] * model.shapedirs[b];
  return v;
}

Points regress_joints(const BodyModel& model, const Points& v_shaped) {
  require(v_shaped.rows() == model.J_regressor.cols(), "regress_joints: ", v_shaped.rows(),
          " vertices given, the joint regressor expects ", model.J_regressor.cols());
  return model.J_regressor * v_shaped;
}

VecX pose_feature(const Points& axis_angle) {
  require(axis_angle.rows() == kSmplJoints, "pose: axis_angle has ", axis_angle.rows(), " rows, expected (",
          kSmplJoints, ", 3)");
  VecX f(kSmplPoseFeatures);
  for (int j = 1; j < kSmplJoints; ++j) {
    const Mat3 d = rodrigues(axis_angle.row(j).transpose()) - Mat3::Identity();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) f[(j - 1) * 9 + r * 3 + c] = d(r, c);  // row-major, as numpy's ravel
  }
  return f;
}

std::vector<Eigen::Matrix4d> joint_world_transforms(const BodyModel& model, const Points& joints_rest,
                                                    const BodyPose& pose) {
  const int J = model.num_joints();
  require(joints_rest.rows() == J, "joint_world_transforms: ", joints_rest.rows(), " rest joints, expected ", J);
  require(pose.axis_angle.rows() == J, "pose: axis_angle has ", pose.axis_angle.rows(), " rows, expected (", J,
          ", 3)");
  // Chain of [R_j | J_j - J_parent] (SMPL eq. 4); parents[j] < j lets one pass
  // in joint order see every parent before its children.
  std::vector<Eigen::Matrix4d> G(J);
  for (int j = 0; j < J; ++j) {
    Eigen::Matrix4d local = Eigen::Matrix4d::Identity();
    local.topLeftCorner<3, 3>() = rodrigues(pose.axis_angle.row(j).transpose());
    const int p = model.parents[j];
    const Vec3 jr = joints_rest.row(j).transpose();
    local.topRightCorner<3, 1>() = p < 0 ? jr : Vec3(jr - joints_rest.row(p).transpose());
    G[j] = p < 0 ? local : Eigen::Matrix4d(G[p] * local);
  }
  // Rest-joint subtraction (SMPL's `pack(G · [J_j; 0])`), then the root
  // translation, so A_j maps unposed-shaped points straight to world.
  for (int j = 0; j < J; ++j) {
    const Vec3 jr = joints_rest.row(j).transpose();
    G[j].topRightCorner<3, 1>() += pose.translation - G[j].topLeftCorner<3, 3>() * jr;
  }
  return G;
}

PosedBody pose_body(const BodyModel& model, const VecX& betas, const BodyPose& pose) {
  PosedBody out;
  out.v_shaped = shape_vertices(model, betas);
  out.joints_rest = regress_joints(model, out.v_shaped);
  out.joint_transforms = joint_world_transforms(model, out.joints_rest, pose);

  const Eigen::Index V = model.num_vertices();
  const int J = model.num_joints();
  Points v_unposed = out.v_shaped;
  if (model.has_pose_blend_shapes()) {
    // posedirs is #V*3 by 207 with row 3v+c; v_unposed's row-major storage is
    // the same #V*3 vector.
    Eigen::Map<VecX> flat(v_unposed.data(), 3 * V);
    flat.noalias() += model.posedirs * pose_feature(pose.axis_angle);
  }

  // Joint transforms as row-major 3x4 blocks for a tight LBS loop. The root
  // translation is added after blending, as SMPL does: float32 weight rows sum
  // to 1 only within ~1e-7, and blending the translation would scale it by that.
  std::vector<double> A(std::size_t(J) * 12);
  for (int j = 0; j < J; ++j)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        A[j * 12 + r * 4 + c] = out.joint_transforms[j](r, c) - (c == 3 ? pose.translation[r] : 0.0);

  out.v_posed.resize(V, 3);
  for (Eigen::Index v = 0; v < V; ++v) {
    double T[12] = {0};
    const double* w = model.weights.row(v).data();
    for (int j = 0; j < J; ++j) {
      if (w[j] == 0.0) continue;  // skinning weights are mostly zero
      const double* a = &A[j * 12];
      for (int k = 0; k < 12; ++k) T[k] += w[j] * a[k];
    }
    const double x = v_unposed(v, 0), y = v_unposed(v, 1), z = v_unposed(v, 2);
    for (int r = 0; r < 3; ++r)
      out.v_posed(v, r) = T[r * 4] * x + T[r * 4 + 1] * y + T[r * 4 + 2] * z + T[r * 4 + 3] + pose.translation[r];
  }

  // Posed joints: G_j applied to the rest joint (the translation column before
  // the rest-joint subtraction), which already includes the root translation.
  out.joints_posed.resize(J, 3);
  for (int j = 0; j < J; ++j)
    out.joints_posed.row(j) =
        (out.joint_transforms[j].topLeftCorner<3, 3>() * out.joints_rest.row(j).transpose() +
         out.joint_transforms[j].topRightCorner<3, 1>())
            .transpose();
  return out;
}

}  // namespace sflsh
