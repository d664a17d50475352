#include "sflsh/sim/skeleton_terms.hpp"

#include <cmath>

#include <Eigen/Eigenvalues>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/energies/bone_gravity.hpp"
#include "sflsh/sim/energies/joint_constraint.hpp"
#include "sflsh/sim/energies/joint_limit.hpp"
#include "sflsh/sim/energies/tracking.hpp"
#include "sflsh/sim/joint_limits_table.hpp"
#include "sflsh/sim/energies/inertia.hpp"
#include "sflsh/sim/posed_points.hpp"

namespace sflsh {

double estimate_body_mass(const Avatar& avatar) {
  constexpr double kBodyDensity = 1000.0;  // kg/m³ (DESIGN.md §4: soft tissue ~1000)
  const Points& x = avatar.surface_rest;
  const Triangles& f = avatar.surface_faces;
  require(x.rows() > 0 && f.rows() > 0, "estimate_body_mass: the avatar has no skin surface; give the body mass");
  double volume = 0.0;  // Σ_f a·(b×c)/6 over outward triangles
  for (Eigen::Index i = 0; i < f.rows(); ++i) {
    const Vec3 a = x.row(f(i, 0)).transpose(), b = x.row(f(i, 1)).transpose(), c = x.row(f(i, 2)).transpose();
    volume += a.dot(b.cross(c)) / 6.0;
  }
  require(volume > 0 && std::isfinite(volume), "estimate_body_mass: skin surface encloses volume ", volume,
          " m^3, expected a closed outward-oriented surface");
  return kBodyDensity * volume;
}

namespace {

/// Point-mass inertia tensor m (|d|² I − d dᵀ) (kg m²).
Mat3 point_inertia(double m, const Vec3& d) { return m * (d.squaredNorm() * Mat3::Identity() - d * d.transpose()); }

/// Adds each rigid body to the tensors of joint i and all its ancestors (about the joints).
void add_subtree_bodies(const Avatar& avatar, const std::vector<BoneBody>& bodies, std::vector<Mat3>& I) {
  for (int i = 0; i < int(bodies.size()); ++i)
    for (int j = i; j >= 0; j = avatar.parents[j])
      I[j] += bodies[i].inertia_rest + point_inertia(bodies[i].mass, bodies[i].com_rest - avatar.joints_rest.row(j).transpose());
}

std::vector<double> largest_moments(const std::vector<Mat3>& I) {
  std::vector<double> out(I.size());
  for (size_t j = 0; j < I.size(); ++j)
    out[j] = Eigen::SelfAdjointEigenSolver<Mat3>(I[j], Eigen::EigenvaluesOnly).eigenvalues()(2);
  return out;
}

}  // namespace

std::vector<double> joint_subtree_inertia(const Avatar& avatar, const std::vector<BoneBody>& bodies) {
  const int J = int(avatar.parents.size());
  require(int(bodies.size()) == J && avatar.joints_rest.rows() == J, "joint_subtree_inertia: ", bodies.size(),
          " bodies for ", J, " joints");
  std::vector<Mat3> I(J, Mat3::Zero());
  for (int i = 0; i < J; ++i) {
    // Body i is moved by joint i and all its ancestors. (Written out, not
    // add_subtree_bodies: this exact expression keeps the results of the
    // Segments rule bit-identical to the earlier code, tests/scene/golden_run_test.cpp.)
    for (int j = i; j >= 0; j = avatar.parents[j]) {
      const Vec3 d = bodies[i].com_rest - avatar.joints_rest.row(j).transpose();
      I[j] += bodies[i].inertia_rest + bodies[i].mass * (d.squaredNorm() * Mat3::Identity() - d * d.transpose());
    }
  }
  return largest_moments(I);
}

std::vector<double> joint_carried_inertia(const Avatar& avatar, const std::vector<BoneBody>& skeleton) {
  const int J = int(avatar.parents.size());
  require(int(skeleton.size()) == J && avatar.joints_rest.rows() == J, "joint_carried_inertia: ", skeleton.size(),
          " bodies for ", J, " joints");
  require(avatar.inertia.size() > 0, "joint_carried_inertia: the avatar has no inertia cubature");
  const PosedPoints points = PosedPoints::at_cubature(avatar, avatar.inertia);
  const VecX mass = cubature_masses(avatar, avatar.inertia);
  std::vector<Mat3> I(J, Mat3::Zero());
  VecX W(J);  // W[j]: share of the sample's skinning weights in joint j's subtree
  for (int s = 0; s < points.size(); ++s) {
    W.setZero();
    const PosedPoints::Rows r = points.rows(s);
    for (int k = 0; k < r.num_bones; ++k)
      for (int j = r.bones[k]; j >= 0; j = avatar.parents[j]) W[j] += r.bone_weights[k];
    const Vec3 x = points.unposed().row(s).transpose();
    for (int j = 0; j < J; ++j)
      if (W[j] != 0.0) I[j] += point_inertia(mass[s] * W[j] * W[j], x - avatar.joints_rest.row(j).transpose());
  }
  add_subtree_bodies(avatar, skeleton, I);
  return largest_moments(I);
}

void add_skeleton_terms(std::vector<EnergyTermPtr>& terms, const Avatar& avatar, const SkeletonTermsOptions& o) {
  require(o.skeleton_mass_fraction > 0 && o.skeleton_mass_fraction <= 1, "add_skeleton_terms: skeleton mass fraction ",
          o.skeleton_mass_fraction, " must be in (0, 1]");
  require(o.limit_frequency_hz >= 0 && o.tracking_frequency_hz >= 0, "add_skeleton_terms: frequencies must be >= 0");
  const double body_mass = o.body_mass > 0 ? o.body_mass : estimate_body_mass(avatar);
  const std::vector<BoneBody> skeleton = bone_bodies(avatar, o.skeleton_mass_fraction * body_mass);
  // Spring stiffnesses scale with everything a joint moves (the flesh rides
  // on the bones), not just the skeleton.
  const bool carried = o.spring_inertia == SkeletonTermsOptions::SpringInertia::Carried && avatar.inertia.size() > 0;
  const std::vector<double> I_joint = carried ? joint_carried_inertia(avatar, skeleton)
                                              : joint_subtree_inertia(avatar, bone_bodies(avatar, body_mass));
  auto springs = [&](double f_hz) {
    const double w2 = std::pow(2.0 * M_PI * f_hz, 2);
    std::vector<double> k(I_joint.size());
    for (std::size_t j = 0; j < k.size(); ++j) k[j] = I_joint[j] * w2;
    return k;
  };

  if (o.bone_inertia) terms.push_back(std::make_unique<BoneInertia>(skeleton));
  if (o.bone_gravity) terms.push_back(std::make_unique<BoneGravity>(skeleton));
  if (o.joint_constraints)
    terms.push_back(std::make_unique<JointConstraint>(avatar, o.joint_stiffness_ratio, body_mass));
  if (o.joint_limits)
    terms.push_back(std::make_unique<JointLimit>(avatar, smpl_joint_ranges(), springs(o.limit_frequency_hz)));
  require(o.root_force_limit >= 0 && std::isfinite(o.root_force_limit), "add_skeleton_terms: root force limit ",
          o.root_force_limit, " N, expected >= 0");
  if (o.tracking) {
    std::vector<double> k_rot = springs(o.tracking_frequency_hz);
    double k_pos = body_mass * std::pow(2.0 * M_PI * o.tracking_frequency_hz, 2);
    if (!o.track_root) k_rot[0] = k_pos = 0;
    terms.push_back(std::make_unique<Tracking>(avatar, std::move(k_rot), k_pos, o.root_force_limit));
  }
}

void add_skeleton_terms(ModelBuilder& builder, int body, const SkeletonTermsOptions& options) {
  std::vector<EnergyTermPtr> terms;
  add_skeleton_terms(terms, builder.avatar(body), options);
  for (EnergyTermPtr& t : terms) builder.add_term(std::move(t), body);
}

}  // namespace sflsh
