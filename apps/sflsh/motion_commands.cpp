// `sflsh motion info FILE` and `sflsh motion export FILE --out poses.npz`:
// what a motion file holds (joints, frames, rate, mapping to SMPL) and its SMPL
// pose parameters as an AMASS-like .npz.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "command.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/motion/amass.hpp"
#include "sflsh/motion/load_motion.hpp"

namespace sflsh::cli {
namespace {

struct MotionArgs {
  std::string file;
  std::string out;
  bool json = false;
  MotionOptions options;
};

void add_load_options(CLI::App* cmd, MotionArgs& a) {
  cmd->add_option("FILE", a.file, "Motion: builtin:NAME, AMASS .npz, .bvh, .fbx/.dae/.gltf/.glb")->required();
  cmd->add_option("--fps", a.options.fps, "Resample to this rate (0: keep the file's)");
  cmd->add_option("--start", a.options.start, "Start time in the file (s)");
  cmd->add_option("--end", a.options.end, "End time in the file (s; default: the end)");
  cmd->add_option("--speed", a.options.speed, "Playback speed factor");
  cmd->add_option("--units", a.options.units, "BVH/assimp length unit: auto, m, cm, mm, inch, cmu")
      ->check(CLI::IsMember({"auto", "m", "cm", "mm", "inch", "cmu"}));
  cmd->add_option("--joint-map", a.options.joint_map, "Joint map file: 'file_joint smpl_joint' per line");
  cmd->add_option("--seconds", a.options.builtin_seconds, "Length of built-in motions (s)");
}

/// The command's own numbers, checked before anything is read.
void check_load_options(const MotionArgs& a) {
  require(std::isfinite(a.options.builtin_seconds) && a.options.builtin_seconds > 0,
          "--seconds must be a positive number of seconds, got ", a.options.builtin_seconds);
}

void export_npz(const MotionArgs& a) {
  require(io::lower_extension(a.out) == ".npz", a.out, ": --out must be a .npz file");
  io::check_output_file(a.out, "--out");
  check_load_options(a);
  const MotionClip clip = load_motion(a.file, a.options);
  if (const auto parent = std::filesystem::path(a.out).parent_path(); !parent.empty())
    std::filesystem::create_directories(parent);
  write_amass(a.out, clip, a.options.rest_joints);  // atomic: nothing half-written on failure
  std::printf("wrote %s: %d frames at %g fps (AMASS/SMPL layout: poses %d by 72 axis-angle, trans %d by 3 m, Z up)\n",
              a.out.c_str(), clip.num_frames(), clip.fps, clip.num_frames(), clip.num_frames());
}

CommandRegistrar reg(60, [](CLI::App& app) {
  auto* motion = app.add_subcommand("motion", "Inspect and convert motion files (AMASS, BVH, FBX, built-ins)");
  motion->require_subcommand(1);
  auto args = std::make_shared<MotionArgs>();

  auto* info = motion->add_subcommand("info", "Print joints, frames, rate, duration and the mapping to SMPL");
  add_load_options(info, *args);
  info->add_flag("--json", args->json, "Print JSON instead of text");
  info->callback([args] {
    check_load_options(*args);
    MotionReport report;
    load_motion(args->file, args->options, &report);
    std::fputs((args->json ? report.to_json() + "\n" : report.describe()).c_str(), stdout);
  });

  auto* exp = motion->add_subcommand("export", "Write SMPL pose parameters as an AMASS-style .npz (poses T by 72, trans T by 3, mocap_framerate; Z up)");
  add_load_options(exp, *args);
  exp->add_option("--out", args->out, "Output .npz")->required();
  exp->callback([args] { export_npz(*args); });
});

}  // namespace
}  // namespace sflsh::cli
