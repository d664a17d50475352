#include "sflsh/sim/rigid_body_terms.hpp"

#include <cmath>

#include <Eigen/Eigenvalues>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/energies/bone_gravity.hpp"
#include "sflsh/sim/energies/bone_inertia.hpp"

namespace sflsh {

void add_rigid_body_terms(ModelBuilder& builder, int body, double mass, const Mat3& inertia, bool gravity) {
  require(mass > 0 && std::isfinite(mass), "rigid object: mass ", mass, " kg, expected > 0");
  require(inertia.allFinite() && (inertia - inertia.transpose()).norm() <= 1e-9 * inertia.norm(),
          "rigid object: the inertia tensor is not finite and symmetric");
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(inertia);
  require(eig.eigenvalues().minCoeff() > 0, "rigid object: the inertia tensor is not positive definite (smallest moment ",
          eig.eigenvalues().minCoeff(), " kg m^2)");
  const std::vector<BoneBody> bodies{{mass, Vec3::Zero(), inertia}};
  builder.add_term(std::make_unique<BoneInertia>(bodies), body);
  if (gravity && builder.options().gravity.squaredNorm() > 0) builder.add_term(std::make_unique<BoneGravity>(bodies), body);
}

}  // namespace sflsh
