#include "sflsh/geometry/sdf.hpp"

#include "sflsh/core/error.hpp"

namespace sflsh::geometry {

WorldSdf::WorldSdf(SdfPtr field, const Eigen::Isometry3d& pose) : field_(std::move(field)), pose_(pose) {
  require(field_ != nullptr, "WorldSdf: no field given");
}

SdfSample WorldSdf::evaluate(const Vec3& x_world, bool want_hessian) const {
  SdfSample s = field_->evaluate(pose_.inverse() * x_world, want_hessian);
  const Mat3 R = pose_.linear();
  s.gradient = R * s.gradient;
  if (s.has_hessian) s.hessian = R * s.hessian * R.transpose();
  return s;
}

}  // namespace sflsh::geometry
