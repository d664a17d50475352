#pragma once
// A tiny body and a prescribed motion for the fit tests (header-only).
// The body: tests/sim's synthetic box (sim/synthetic_avatar.hpp), 3x4x3 cubes
// of 3 cm, 10 hat handles, two regions (x < 0 "soft", x ≥ 0 "firm") with a low
// Fung constant so that saturation acts at the strains the motion reaches.
// The motion: the pelvis bobs 3 cm and the chain bends 0.6 rad.
#include "sflsh/fit/trajectory_sensitivity.hpp"
#include "sim/synthetic_avatar.hpp"

namespace sflsh::test {

inline Avatar fit_avatar() {
  SyntheticAvatarOptions o;
  o.nx = 3, o.ny = 4, o.nz = 3;
  o.cell = 0.03;
  o.handles = 10;
  o.handle_radius = 0.07;
  Avatar a = make_synthetic_avatar(o);
  for (RegionMaterial& m : a.materials) m.fung_c = 150.0;
  return a;
}

/// `steps` steps of 1/60 s of synthetic_motion (lift 3 cm, bend 0.6 rad).
inline BoneSequence fit_bones(const Avatar& a, int steps) {
  BoneSequence seq;
  seq.h = 1.0 / 60.0;
  seq.bones_before = synthetic_motion(a, -seq.h, 0.03, 0.6);
  for (int s = 0; s <= steps; ++s) seq.bones.push_back(synthetic_motion(a, s * seq.h, 0.03, 0.6));
  return seq;
}

}  // namespace sflsh::test
