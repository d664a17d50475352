#include "sflsh/fit/reference_observations.hpp"

#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/scene/simulation_run.hpp"
#include "sflsh/reference/full_fem.hpp"

namespace sflsh {

void write_reference_observations(std::shared_ptr<const Avatar> avatar, const MotionClip& motion,
                                  const std::string& motion_spec, double seconds, double h, double fps,
                                  const std::string& path) {
  require(h > 0 && seconds > 0 && fps > 0, "reference observations: need h, seconds and fps > 0");
  const double per = 1.0 / (fps * h);
  const int steps_per_frame = int(std::lround(per));
  require(steps_per_frame >= 1 && std::abs(per - steps_per_frame) < 1e-6, "reference observations: 1/fps = ",
          1.0 / fps, " s is not a whole number of steps of ", h, " s");
  FullFemOptions o;
  o.h = h;
  o.gradient_tolerance = 1e-6;  // as `sflsh bench`'s reference
  FullFem fem(avatar, o);
  fem.reset(target_bones(*avatar, motion.sample(0)));
  std::vector<double> time = {0.0};
  std::vector<Points> frames = {fem.posed_surface()};
  const long steps = std::lround(seconds / h);
  Progress progress("full-FEM reference", steps);
  for (long s = 1; s <= steps; ++s) {
    fem.step(target_bones(*avatar, motion.sample(s * h)));
    if (s % steps_per_frame == 0) {
      time.push_back(s * h);
      frames.push_back(fem.posed_surface());
    }
    progress.update(s);
  }
  progress.finish();
  io::Hdf5File f(path, io::Hdf5File::Mode::Write);
  f.write("/frames/time", time.data(), long(time.size()), 1);
  std::vector<double> flat;
  flat.reserve(frames.size() * frames[0].size());
  for (const Points& P : frames)
    for (long v = 0; v < P.rows(); ++v)
      for (int c = 0; c < 3; ++c) flat.push_back(P(v, c));
  f.write_nd("/frames/positions", flat.data(), {long(frames.size()), frames[0].rows(), 3});
  f.write_string("/meta/motion", motion_spec);
  f.write_scalar("/meta/dt", h);
  f.write_string("/meta/bones", "kinematic");
  f.write_matrix("/surface/rest", avatar->surface_rest);
  f.commit();
}

}  // namespace sflsh
