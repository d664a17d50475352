#pragma once
// `sflsh bench-contact`: the reduced model against the full-FEM
// reference under rigid contact, i.e. how well K handles represent a local
// dent. Two scenes on one avatar shape with kinematic bones in the rest pose
// and gravity off (so the soft displacement is the contact response alone):
//
//   pressed: a kinematic sphere (radius 8 cm) starts 1 cm in front of the belly,
//            moves 4 cm along the inward normal over 0.5 s (3 cm deep) and is
//            held 0.5 s; time step 1/60 s.
//   impact:  a kinematic ball (radius 11 cm) starts 2 cm in front, moves in at
//            3 m/s until 3 cm deep, then leaves at 3 m/s; 0.3 s in all, time
//            step 1/240 s (the contact lasts ~30 ms: 7 steps).
//   probe:   a kinematic sphere probe (radius 2 cm) starts 2 mm in front of the
//            left thigh, presses 15 mm deep along the inward normal over 1.5 s
//            (quasi-static: 1 cm/s) and is held 0.25 s; time step 1/60 s. The
//            force–depth curve is compared: |force| of the contact
//            per step against the probe's kinematic depth below the
//            undeformed skin; force_err = |F_red − F_full| / F_full at 10 mm.
//
// The belly point p is the front-most skin vertex (largest z; the body faces
// +z) with |x| < 5 cm between the pelvis and spine2 joint heights whose tet
// has a Simulated node; the inward normal is −z. The thigh point is the
// front-most skin vertex of the left thigh between 40 % and 60 % of the way
// from knee to hip, within 4 cm (in x) of the thigh's axis, whose tet has a
// Simulated node; its inward normal is −z as well. Contact: both solvers sample
// the skin's faces with one pressure stiffness and spacing (the reduced one
// through sim/energies/contact_patch.hpp, with or without its patch; the full
// FEM through FullFemObstacle). The calf point is the back-most skin vertex of
// the left calf between 50 % and 70 % of the way from ankle to knee, within
// 3 cm (in x) of its axis; inward normal +z.
//
// Per scene and handle count K, compared at every step:
//   rel_err     = ‖u − u_ref‖ / ‖u_ref‖ over skin vertices and steps (u: soft
//                 displacement of the skin, unposed = world here; vertices
//                 outside the simulated region have u = 0 in both);
//   dent        = max over steps and over skin vertices within 1.5 r of p of
//                 the inward displacement −u·n (mm); dent_ratio = reduced / full;
//   us_per_sample_iter = time in the reduced contact term / Σ_steps (active
//                 samples × Newton iterations), over the steps with contact;
//   step_ratio  = median reduced step time over the steps with contact /
//                 median step time of the same steps of the scene without the object.
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/precompute/precompute.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "sflsh/sim/soft_tissue_terms.hpp"

namespace sflsh {

/// Scene and solver settings of the contact benchmark.
struct ContactBenchSettings {
  bool quick = false;            ///< shorter scenes (pressed 0.25 s + 0.1 s hold; impact 0.1 s)
  int newton_iters = 1;          ///< reduced solver's Newton iterations per step (1: the default simulator)
  /// The reduced solver's NewtonOptions::nonlinearity_tolerance (unset: automatic;
  /// 0: never an extra Newton iteration).
  std::optional<double> nonlinearity_tolerance;
  double pressed_radius = 0.08;  ///< m
  double pressed_depth = 0.03;   ///< m, final depth below the undeformed belly
  double impact_radius = 0.11;   ///< m
  double impact_speed = 3.0;     ///< m/s
  double impact_depth = 0.03;    ///< m, deepest kinematic penetration of the ball
  double pressed_dt = 1.0 / 60.0, impact_dt = 1.0 / 240.0;  ///< s
  double probe_radius = 0.02;     ///< m
  double probe_depth = 0.015;     ///< m, deepest kinematic depth of the probe
  double probe_dt = 1.0 / 60.0;   ///< s
  /// The reduced solver's SoftTissueOptions::mean_dilatation (false: every
  /// tet's own volume change, as the full-FEM reference integrates it).
  bool mean_dilatation = SoftTissueOptions().mean_dilatation;
  double probe_report_depth = 0.01;  ///< m: force_err is taken there
  /// Contact in both solvers: pressure stiffness κ (N/m³) and face sample
  /// spacing (m), skin_face_samples.hpp; the reduced solver's full-space patch
  /// (sim/energies/contact_patch.hpp).
  double pressure_stiffness = kDefaultPressureStiffness;
  double spacing = kDefaultContactSpacing;
  bool patch = true;
  double patch_radius = ContactPatchOptions().patch_radius;
  int max_patch_nodes = ContactPatchOptions().max_patch_nodes;
  std::vector<std::string> scenes;   ///< which scenes to run (empty: pressed, impact, probe)
  /// The ms columns: the stepping thread's CPU time instead of wall time (on a
  /// shared machine other jobs' load inflates wall time, not CPU time).
  bool cpu_time = false;
};

struct ContactBenchOptions {
  ContactBenchSettings settings;
  std::string model = "procedural";
  VecX betas;
  std::vector<int> handle_counts;  ///< empty: {32, 64, 128} ({32} with settings.quick)
  PrecomputeOptions precompute;    ///< template/shape options (cache dir, ...)
};

struct ContactBenchRow {
  std::string scene;             ///< pressed | impact
  int handles = 0;               ///< K
  double dt = 0;                 ///< s
  int steps = 0;
  double rel_err = 0;
  double dent_full_mm = 0, dent_reduced_mm = 0, dent_ratio = 0;
  double force_full_n = 0, force_reduced_n = 0;  ///< peak |contact force| over the steps (N)
  int active_samples = 0;        ///< reduced: largest number of penetrating samples at the end of a step
  int active_samples_full = 0;   ///< the same for the full-FEM reference
  double us_per_sample_iter = 0; ///< µs in the reduced contact term per active sample per Newton iteration
  double ms_contact = 0, ms_no_contact = 0, step_ratio = 0;  ///< reduced step medians (steps with contact)
  double ms_full = 0;            ///< full-FEM median step time (steps with contact)
  /// Per step: the object's kinematic depth below the undeformed skin point
  /// (mm; negative = not touching yet) and |contact force| (N) of both solvers.
  std::vector<double> curve_depth_mm, curve_force_full_n, curve_force_reduced_n;
  /// The forces at settings.probe_report_depth (first crossing, interpolated)
  /// and their relative difference |F_red − F_full| / F_full (probe scene).
  double force_at_depth_full_n = 0, force_at_depth_reduced_n = 0, force_err = 0;
  /// RMS of (F_red − F_full) / F_full over the loading ramp's steps at 2–10 mm (probe scenes).
  double force_rms_err = 0;
  int max_patch_nodes = 0;  ///< reduced: the largest contact patch (nodes)
};

/// Runs both scenes on `avatars` (one per handle count; they must share the
/// tet mesh, skin and skeleton, as precompute_shape at several K gives) and
/// returns one row per scene and avatar. Progress on stderr.
std::vector<ContactBenchRow> run_contact_scenes(const std::vector<std::shared_ptr<const Avatar>>& avatars,
                                                const ContactBenchSettings& settings);

/// Precomputes the avatar at every handle count and runs run_contact_scenes.
std::vector<ContactBenchRow> run_contact_benchmark(const ContactBenchOptions& options);

/// CSV with the header scene,handles,dt,steps,rel_err,dent_full_mm,dent_reduced_mm,
/// dent_ratio,force_full_n,force_reduced_n,active_samples,active_samples_full,us_per_sample_iter,
/// ms_contact,ms_no_contact,step_ratio,ms_full (written as PATH.partial, then renamed).
void write_contact_bench_csv(const std::vector<ContactBenchRow>& rows, const std::string& path);
/// The probe's force–depth curves (rows of scene "probe"): CSV
/// depth_mm,full_n,K<k>_n... (one row per step) and an SVG plot.
void write_probe_curves(const std::vector<ContactBenchRow>& rows, const std::string& csv_path,
                        const std::string& svg_path, double report_depth);
/// The rows as a Markdown table, `heading` (Markdown) above it.
void write_contact_bench_markdown(const std::vector<ContactBenchRow>& rows, const std::string& path,
                                  const std::string& heading);
/// The same Markdown to a stream.
void write_contact_bench_markdown(const std::vector<ContactBenchRow>& rows, const std::string& heading,
                                  std::ostream& out);

}  // namespace sflsh
