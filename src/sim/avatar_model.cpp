#include "sflsh/sim/avatar_model.hpp"

#include "sflsh/core/error.hpp"

namespace sflsh {

ModelOptions model_options(const SimulatorOptions& o) {
  ModelOptions m;
  m.h = o.h;
  m.gravity = o.gravity;
  m.newton = o.newton;
  return m;
}

std::shared_ptr<const Model> avatar_model(std::shared_ptr<const Avatar> avatar, const SimulatorOptions& o,
                                          const SkeletonTermsOptions* skeleton, const std::string& name) {
  require(avatar != nullptr, "avatar_model: null avatar");
  require(o.h > 0, "SimulatorOptions::h = ", o.h, " s, expected > 0");
  require(o.damping >= 0, "SimulatorOptions::damping = ", o.damping, " s, expected >= 0");
  ModelBuilder builder(model_options(o));
  const int body = builder.add_body({name, std::move(avatar), o.bones_dynamic});
  if (o.soft_tissue_terms) add_soft_tissue_terms(builder, body, {true, o.damping, o.mean_dilatation});
  if (skeleton) add_skeleton_terms(builder, body, *skeleton);
  return builder.build();
}

}  // namespace sflsh
