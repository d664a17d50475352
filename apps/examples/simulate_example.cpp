// The library API in a few lines: load an avatar, make a state, step it, read
// positions. Usage: simulate_example avatar.h5 [builtin:jump]
#include <cstdio>
#include <memory>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/motion/load_motion.hpp"
#include "sflsh/scene/simulation_run.hpp"
#include "sflsh/sim/simulator.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s avatar.h5 [motion]\n", argv[0]);
    return 2;
  }
  try {
    auto avatar = std::make_shared<sflsh::Avatar>(sflsh::read_avatar(argv[1]));
    const sflsh::MotionClip motion = sflsh::load_motion(argc > 2 ? argv[2] : "builtin:jump");
    // One avatar, bones prescribed by the motion, soft tissue dynamic.
    sflsh::Simulator sim(sflsh::avatar_model(avatar, sflsh::SimulatorOptions{}));
    sim.reset(sflsh::target_bones(*avatar, motion.sample(0.0)));
    for (int s = 1; s <= 120; ++s) {
      const sflsh::BodyPose pose = motion.sample(s * sim.h());
      const sflsh::StepReport report = sim.step(sflsh::target_bones(*avatar, pose), pose);
      if (s % 30 == 0) {
        const sflsh::Points u = sim.soft_displacement();  // #V by 3, unposed space
        std::printf("t = %.2f s  step %.2f ms  max soft displacement %.1f mm\n", sim.time(), report.ms_total,
                    1e3 * u.rowwise().norm().maxCoeff());
      }
    }
    const sflsh::Points skin = sim.posed_surface();  // #V by 3, world, metres
    std::printf("posed skin: %ld vertices, pelvis at y = %.3f m\n", long(skin.rows()), sim.joints()(0, 1));
  } catch (const sflsh::Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
