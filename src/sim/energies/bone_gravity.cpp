#include "sflsh/sim/energies/bone_gravity.hpp"

#include "sflsh/core/error.hpp"

namespace sflsh {

BoneGravity::BoneGravity(std::vector<BoneBody> bodies) : bodies_(std::move(bodies)) {}

double BoneGravity::compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const {
  require(q.bones.size() == bodies_.size(), "BoneGravity: configuration has ", q.bones.size(), " bones, expected ",
          bodies_.size());
  const bool assemble = ctx.layout.bones_dynamic && grad;
  if (assemble)
    require(grad->size() == ctx.layout.size(), "BoneGravity: gradient has ", grad->size(), " entries, expected ",
            ctx.layout.size());
  double V = 0.0;
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    const Vec3 c = q.bones[i] * bodies_[i].com_rest;
    const Vec3 force = bodies_[i].mass * ctx.gravity;  // V = −f·c
    V -= force.dot(c);
    if (assemble) grad->segment<6>(ctx.layout.bone_offset(int(i))) -= point_jacobian(c).transpose() * force;
  }
  return V;
}

}  // namespace sflsh
