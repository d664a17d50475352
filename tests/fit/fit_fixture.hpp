#pragma once
// A tiny body and a prescribed motion for the fit tests (header-only).
// The body: tests/sim's synthetic box (sim/synthetic_avatar.hpp), 3x4x3 cubes
// of 3 cm, 10 hat handles, two regions (x < 0 "soft", x ≥ 0 "firm") with a low
// Fung constant so that saturation acts at the strains the motion reaches.
// The motion: the pelvis bobs 3 cm and the chain bends 0.6 rad.
#include <string>
#include <vector>

#include "sflsh/fit/trajectory_sensitivity.hpp"
#include "sflsh/io/hdf5_file.hpp"
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

/// An observation file in the result layout: /frames/time, /frames/positions
/// (each frame #V by 3) and /meta/motion.
inline void write_observation_file(const std::string& path, const std::vector<double>& t, const std::vector<Points>& x,
                                   const std::string& motion = "builtin:jump") {
  io::Hdf5File f(path, io::Hdf5File::Mode::Write);
  f.write("/frames/time", t.data(), long(t.size()), 1);
  std::vector<double> flat;
  for (const Points& P : x)
    for (long v = 0; v < P.rows(); ++v)
      for (int c = 0; c < 3; ++c) flat.push_back(P(v, c));
  f.write_nd("/frames/positions", flat.data(), {long(x.size()), x[0].rows(), 3});
  f.write_string("/meta/motion", motion);
  f.commit();
}

}  // namespace sflsh::test
