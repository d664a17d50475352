#include "sflsh/sim/momentum.hpp"

#include "sflsh/sim/energies/bone_inertia.hpp"
#include "sflsh/sim/energies/inertia.hpp"

namespace sflsh {

Vec3 linear_momentum(const Model& model, const State& state) {
  const double h = model.options().h;
  Vec3 p = Vec3::Zero();
  for (const Model::BoundTerm& t : model.terms()) {
    const BodyState& s = state.bodies.at(t.bodies[0]);
    if (const auto* in = dynamic_cast<const InertiaTerm*>(t.term.get())) {
      const Points x = in->points().world(s.q), x0 = in->points().world(s.q_prev);
      p += ((x - x0).transpose() * in->masses()) / h;
    } else if (const auto* bi = dynamic_cast<const BoneInertia*>(t.term.get())) {
      for (size_t i = 0; i < bi->bodies().size(); ++i) {
        const BoneBody& b = bi->bodies()[i];
        p += b.mass * (s.q.bones[i] * b.com_rest - s.q_prev.bones[i] * b.com_rest) / h;
      }
    }
  }
  return p;
}

double inertial_mass(const Model& model) {
  double m = 0;
  for (const Model::BoundTerm& t : model.terms()) {
    if (const auto* in = dynamic_cast<const InertiaTerm*>(t.term.get())) m += in->masses().sum();
    if (const auto* bi = dynamic_cast<const BoneInertia*>(t.term.get())) m += total_mass(bi->bodies());
  }
  return m;
}

}  // namespace sflsh
