#include "sflsh/sim/skeleton_pose.hpp"

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"

namespace sflsh {

namespace {

void check_skeleton(const Points& joints_rest, const std::vector<int>& parents, std::size_t num_bones,
                    const char* what) {
  require(joints_rest.rows() == Eigen::Index(parents.size()), what, ": ", joints_rest.rows(),
          " rest joints but ", parents.size(), " parents");
  require(num_bones == parents.size(), what, ": ", num_bones, " bone transforms, expected ", parents.size());
}

}  // namespace

std::vector<Isometry> bone_transforms_from_pose(const Points& joints_rest, const std::vector<int>& parents,
                                                const BodyPose& pose) {
  check_skeleton(joints_rest, parents, parents.size(), "bone_transforms_from_pose");
  // joint_world_transforms reads only the kinematic tree of the model.
  BodyModel tree;
  tree.parents = parents;
  const std::vector<Eigen::Matrix4d> A = joint_world_transforms(tree, joints_rest, pose);
  std::vector<Isometry> G(A.size());
  for (std::size_t j = 0; j < A.size(); ++j) G[j].matrix() = A[j];
  return G;
}

Mat3 local_rotation(const std::vector<Isometry>& bones, const std::vector<int>& parents, int j) {
  const int p = parents[j];
  return p < 0 ? Mat3(bones[j].linear()) : Mat3(bones[p].linear().transpose() * bones[j].linear());
}

BodyPose pose_from_bone_transforms(const std::vector<Isometry>& bones, const Points& joints_rest,
                                   const std::vector<int>& parents) {
  check_skeleton(joints_rest, parents, bones.size(), "pose_from_bone_transforms");
  BodyPose pose;
  const int J = int(parents.size());
  pose.axis_angle.resize(J, 3);
  for (int j = 0; j < J; ++j) pose.axis_angle.row(j) = rotation_log(local_rotation(bones, parents, j)).transpose();
  const Vec3 root = joints_rest.row(0).transpose();
  pose.translation = bones[0] * root - root;
  return pose;
}

Points joint_world_positions(const std::vector<Isometry>& bones, const Points& joints_rest) {
  require(Eigen::Index(bones.size()) == joints_rest.rows(), "joint_world_positions: ", bones.size(),
          " bone transforms but ", joints_rest.rows(), " rest joints");
  Points x(joints_rest.rows(), 3);
  for (Eigen::Index j = 0; j < joints_rest.rows(); ++j)
    x.row(j) = (bones[j] * Vec3(joints_rest.row(j).transpose())).transpose();
  return x;
}

std::vector<Isometry> bones_one_step_before(const std::vector<Isometry>& at_start,
                                            const std::vector<Isometry>& after_one_step) {
  require(at_start.size() == after_one_step.size(), "bones_one_step_before: ", at_start.size(), " bones at the start, ",
          after_one_step.size(), " one step later");
  std::vector<Isometry> before;
  before.reserve(at_start.size());
  for (size_t j = 0; j < at_start.size(); ++j) before.push_back(at_start[j] * after_one_step[j].inverse() * at_start[j]);
  return before;
}

}  // namespace sflsh
