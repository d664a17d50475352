#pragma once
// `sflsh bench-contact --scene scene.yaml`: a user's scene file run with the
// reduced solver as written (the scene loop of `sflsh simulate scene.yaml`)
// and with the full-FEM reference (`--solver full`,
// reference/scene_reference_run.hpp), compared per contact pair — each static
// or kinematic object and each tool with a shape that touches the scene's one
// body — at every step:
//
//   force     |contact force on the body| (N) in both solvers; peak_err =
//             |peak_red − peak_full| / peak_full; rms_err = RMS of
//             (F_red − F_full) / F_full over the steps where the full FEM's
//             force exceeds force_threshold × its peak;
//   dent      per step, the largest soft displacement |u| (mm; unposed, the
//             contact patch's share included) of the skin vertices whose
//             deformed position lies within dent_reach of the object's surface
//             in that solver; reported: its maximum over the steps;
//   depth     where it has a plain meaning — a kinematic object or tool on a
//             body without a motion — the object's travel since the full FEM's
//             first step with contact, along the full FEM's contact force at
//             its peak (mm; negative before contact). For a sphere pressed
//             into the skin it is its depth below the undeformed skin, low by
//             less than one step's travel (contact starts within the step
//             before the first step that reports it). Otherwise NaN;
//   patch     the reduced run's largest contact patch (nodes; 0 without
//             contact.patch: the per-sample penalty).
//
// Time per step of the reduced scene loop (SceneSession::advance: the tools'
// poses, the Newton step and its checks; no output frames are made), median
// over the steps where the reduced run has contact, with the scene as written
// and with the compared objects and tools removed (same steps); and the full
// FEM's median step (its solve) over its steps with contact. Wall time, or the
// stepping thread's CPU time (cpu_time).
#include <iosfwd>
#include <string>
#include <vector>

#include "sflsh/scene/scene_description.hpp"

namespace sflsh {

struct SceneContactBenchSettings {
  bool cpu_time = false;          ///< the ms figures in thread CPU time, not wall time
  double force_threshold = 0.05;  ///< share of the full FEM's peak force above which rms_err counts a step
  double dent_reach = 0.01;       ///< m: skin this close to the object's surface counts for the dent
  bool progress = true;
  /// TEST ONLY: SceneSessionOptions::inject_nan_at_step of the reduced run (0: off).
  long inject_nan_at_step = 0;
};

/// One contact pair (the body and one object or tool) of a scene.
struct SceneContactPair {
  std::string object;             ///< the object's or tool's name
  bool kinematic = false;         ///< a kinematic object or a tool (not static)
  // Per step (one entry per step of the scene):
  std::vector<double> force_full_n, force_reduced_n;   ///< |contact force on the body|
  std::vector<double> dent_full_mm, dent_reduced_mm;   ///< largest |u| of the skin near the object
  std::vector<double> depth_mm;   ///< header comment; NaN where undefined
  std::vector<int> patch_nodes;   ///< reduced: the contact patch's nodes
  // Summary:
  double peak_full_n = 0, peak_reduced_n = 0, peak_err = 0;
  double rms_err = 0;             ///< NaN when no step is above the threshold
  int rms_steps = 0;              ///< steps rms_err is taken over
  double dent_full_max_mm = 0, dent_reduced_max_mm = 0;
  double max_depth_mm = 0;        ///< NaN when depth is undefined
  int max_patch_nodes = 0;
  int contact_steps_full = 0, contact_steps_reduced = 0;
};

struct SceneContactBenchResult {
  std::string scene;              ///< the scene file
  std::string body;               ///< its body's name
  double dt = 0;                  ///< s
  std::vector<double> time;       ///< s, end of each step
  bool patch = false;             ///< the reduced run's contact: contact.patch, or the per-sample penalty
  std::string removed;            ///< what the run without contact left out (names, comma-separated)
  std::vector<SceneContactPair> pairs;
  double ms_contact = 0, ms_no_contact = 0, step_ratio = 0;  ///< reduced medians over its contact steps
  double ms_full = 0;             ///< full FEM median over its contact steps
  int contact_steps = 0;          ///< reduced steps with contact in some pair
};

/// Checks what can be checked before any run: the reference takes the scene
/// (check_scene_reference), and its body touches some object or tool with a
/// shape. Throws one line naming the scene.
void check_scene_contact_bench(const SceneDescription& scene);

/// Runs `scene` (read by read_scene_description, prepared by
/// prepare_scene_assets) with both solvers and once more without its
/// contacts (header comment). Throws one line naming the scene on a refusal,
/// a non-finite value (with the step) or a scene in which the full FEM never
/// touches.
SceneContactBenchResult run_scene_contact_bench(const SceneDescription& scene, const SceneContactBenchSettings& settings);

/// The per-step series as CSV: step,time_s,object,depth_mm,force_full_n,
/// force_reduced_n,dent_full_mm,dent_reduced_mm,patch_nodes (one row per step
/// and pair; written as PATH.partial, then renamed).
void write_scene_contact_series_csv(const SceneContactBenchResult& result, const std::string& path);
/// Force against depth (the loading part, up to the deepest step) when every
/// pair has a depth, else against time: full FEM dashed, reduced solid, per pair.
void write_scene_contact_plot_svg(const SceneContactBenchResult& result, const std::string& path);
/// One row per scene and pair: CSV scene,object,peak_full_n,peak_reduced_n,peak_err,rms_err,
/// rms_steps,dent_full_mm,dent_reduced_mm,max_depth_mm,max_patch_nodes,ms_contact,ms_no_contact,step_ratio,ms_full.
void write_scene_contact_summary_csv(const std::vector<SceneContactBenchResult>& results, const std::string& path);
/// The Markdown section of the scene files' results (tables and what each column is).
void write_scene_contact_markdown(const std::vector<SceneContactBenchResult>& results,
                                  const SceneContactBenchSettings& settings, std::ostream& out);

}  // namespace sflsh
