#pragma once
// A dynamic slab resting on the flat top of a kinematic box avatar with
// gravity tilted (an incline), for the contact terms' friction tests.
// Header-only, for tests/sim/*_test.cpp.
#include <cmath>
#include <functional>
#include <memory>

#include "sflsh/sim/rigid_body_terms.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sflsh/sim/soft_tissue_terms.hpp"
#include "sim/two_body_fixture.hpp"

namespace sflsh::test {

/// Where a 0.1 kg slab (12 × 1 × 12 cm: wider than the top, so that no skin
/// sample meets its sides before it has slid 3 cm) laid 0.2 mm into the top
/// of box(6, 6, 0.01) (y = 0.03) ends after 1 s with gravity tilted by `tilt`
/// rad about z; `contact(avatar, half size)` makes the term between the box
/// (bound first) and the slab.
inline Vec3 slab_on_incline(
    double tilt, const std::function<std::shared_ptr<const EnergyTerm>(const Avatar&, const Vec3&)>& contact) {
  const Avatar a = two_body::box(6, 6, 0.01);
  ModelOptions mo;
  mo.h = two_body::kH;
  mo.gravity = 9.81 * Vec3(std::sin(tilt), -std::cos(tilt), 0);
  mo.newton.iterations = 4;
  mo.newton.line_search = true;
  ModelBuilder mb(mo);
  const int body = mb.add_body({"box", std::make_shared<const Avatar>(a), false});
  const int slab = mb.add_body({"slab", nullptr, true});
  add_soft_tissue_terms(mb, body, {true, 0.0});
  const double m = 0.1;
  const Vec3 half(0.06, 0.005, 0.06);
  add_rigid_body_terms(mb, slab, m, m / 3 * Vec3(half.y() * half.y() + half.z() * half.z(),
                                                 half.x() * half.x() + half.z() * half.z(),
                                                 half.x() * half.x() + half.y() * half.y()).asDiagonal().toDenseMatrix());
  mb.add_term(contact(a, half), {body, slab});
  Simulator sim(mb.build());
  State s = sim.scene_state();
  const Vec3 start(0, 0.03 + half.y() - 0.0002, 0);
  s.bodies[slab].q.bones[0].translation() = start;
  s.bodies[slab].q_prev = s.bodies[slab].q;
  sim.set_state(s);
  StepInputs in;
  in.bodies.resize(2);
  in.bodies[body].bones = identity_bones();
  for (int i = 0; i < 60; ++i) sim.step(in);
  return sim.state(slab).bones[0].translation() - start;
}

}  // namespace sflsh::test
