// `sflsh bench-contact`: reduced model against the full-FEM reference under
// rigid contact: the built-in scenes (a sphere pressed into the belly, a ball
// impact, probes) and the user's scene files (--scene).
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>

#include "command.hpp"
#include "sflsh/bench/contact_benchmark.hpp"
#include "sflsh/bench/scene_contact_benchmark.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/io/input_file.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene_assets/scene_assets.hpp"

namespace sflsh::cli {
namespace {

struct ContactBenchArgs {
  bool quick = false, no_cache = false;
  std::string out = "bench_contact", model = "procedural", betas, cache_dir;
  std::vector<int> handles;
  std::vector<std::string> scenes;
  std::vector<std::string> scene_files;  // --scene
  std::string builtin_only_flag;         // the first flag given that applies to the built-in scenes alone
  int newton_iters = 1;
  std::optional<double> nonlinearity_tolerance;
  double pressure_stiffness = kDefaultPressureStiffness, spacing = kDefaultContactSpacing;
  double patch_radius = ContactPatchOptions().patch_radius;
  int max_patch_nodes = ContactPatchOptions().max_patch_nodes;
  bool no_patch = false, cpu_time = false;
  std::string command_line;
};

/// Output file stems of the scene files: their own, made unique with -2, -3, ...
std::vector<std::string> scene_stems(const std::vector<std::string>& files) {
  std::vector<std::string> stems;
  for (const std::string& f : files) {
    const std::string base = std::filesystem::path(f).stem().string();
    std::string stem = base;
    for (int n = 2; std::find(stems.begin(), stems.end(), stem) != stems.end(); ++n) stem = base + "-" + std::to_string(n);
    stems.push_back(stem);
  }
  return stems;
}

void run_contact_bench(const ContactBenchArgs& a) {
  // Figures are for one core: no TBB or BLAS threads.
  setenv("OPENBLAS_NUM_THREADS", "1", 1);
  setenv("OMP_NUM_THREADS", "1", 1);
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  // --scene alone runs the scene files only; with --scenes, both.
  const bool builtin = a.scene_files.empty() || !a.scenes.empty();
  require(builtin || a.builtin_only_flag.empty(), a.builtin_only_flag,
          " applies to the built-in scenes (--scenes); a scene file (--scene) sets its own solver and contact");

  ContactBenchOptions o;
  o.settings.quick = a.quick;
  o.settings.newton_iters = a.newton_iters;
  o.settings.nonlinearity_tolerance = a.nonlinearity_tolerance;
  o.settings.scenes = a.scenes;
  o.settings.pressure_stiffness = a.pressure_stiffness;
  o.settings.spacing = a.spacing;
  o.settings.patch = !a.no_patch;
  o.settings.patch_radius = a.patch_radius;
  o.settings.max_patch_nodes = a.max_patch_nodes;
  o.settings.cpu_time = a.cpu_time;
  check_contact_sampling(a.pressure_stiffness, a.spacing, "bench-contact (--pressure-stiffness, --spacing)");
  require(std::isfinite(a.patch_radius) && a.patch_radius > 0, "--patch-radius must be a positive number of m, got ",
          a.patch_radius);
  require(a.newton_iters >= 1, "--newton-iters must be >= 1, got ", a.newton_iters);
  require(!a.nonlinearity_tolerance || (std::isfinite(*a.nonlinearity_tolerance) && *a.nonlinearity_tolerance >= 0),
          "--nonlinearity-tolerance must be a finite number >= 0, got ", a.nonlinearity_tolerance.value_or(0));
  o.model = a.model;
  if (!a.betas.empty()) o.betas = parse_betas(a.betas);
  o.handle_counts = a.handles;  // CLI11 checks each is a whole number in [1, 4096]
  if (!a.no_cache) o.precompute.cache_dir = a.cache_dir.empty() ? default_cache_dir() : a.cache_dir;
  io::check_output_folder(a.out, "--out");
  // Every scene file read, prepared and checked before any run.
  std::vector<SceneDescription> scenes;
  for (const std::string& f : a.scene_files) {
    io::require_input_file(f, "--scene");
    scenes.push_back(read_scene_description(f));
  }
  for (SceneDescription& sc : scenes) {
    prepare_scene_assets(sc, a.cache_dir.empty() ? default_cache_dir() : a.cache_dir);
    check_scene_contact_bench(sc);
  }

  const auto rows = builtin ? run_contact_benchmark(o) : std::vector<ContactBenchRow>{};
  SceneContactBenchSettings ss;
  ss.cpu_time = a.cpu_time;
  std::vector<SceneContactBenchResult> results;
  for (const SceneDescription& sc : scenes) results.push_back(run_scene_contact_bench(sc, ss));

  std::error_code ec;  // made only now: a run that fails leaves no empty folder
  std::filesystem::create_directories(a.out, ec);
  if (ec) fail("--out ", a.out, ": cannot create output folder: ", ec.message());
  const std::string csv = (std::filesystem::path(a.out) / "contact_bench.csv").string();
  const std::string md = (std::filesystem::path(a.out) / "contact_bench.md").string();
  const std::string heading = "Command: `" + a.command_line + "` (one core" +
                              (a.cpu_time ? "; ms columns in CPU time of the stepping thread)" : ")");
  if (results.empty()) {
    write_contact_bench_markdown(rows, md, heading);
  } else {
    io::write_text_file(md, [&](std::ostream& f) {
      if (builtin)
        write_contact_bench_markdown(rows, heading, f);
      else
        f << heading << "\n";
      f << "\n";
      write_scene_contact_markdown(results, ss, f);
    });
  }
  if (!results.empty()) {
    const std::vector<std::string> stems = scene_stems(a.scene_files);
    const std::filesystem::path dir(a.out);
    const std::string summary = (dir / "contact_scenes.csv").string();
    write_scene_contact_summary_csv(results, summary);
    std::printf("%-24s %-10s %9s %9s %7s %7s %8s %8s %8s %6s %9s %9s %6s %9s\n", "scene", "object", "F_ref", "F_red",
                "err", "rms", "dent_ref", "dent_red", "depth", "patch", "ms_cont", "ms_none", "x", "ms_full");
    for (size_t i = 0; i < results.size(); ++i) {
      const SceneContactBenchResult& r = results[i];
      for (const SceneContactPair& p : r.pairs)
        std::printf("%-24s %-10s %9.2f %9.2f %6.1f%% %6.1f%% %8.2f %8.2f %8.2f %6d %9.3f %9.3f %6.2f %9.1f\n",
                    stems[i].c_str(), p.object.c_str(), p.peak_full_n, p.peak_reduced_n, 100.0 * p.peak_err,
                    100.0 * p.rms_err, p.dent_full_max_mm, p.dent_reduced_max_mm, p.max_depth_mm, p.max_patch_nodes,
                    r.ms_contact, r.ms_no_contact, r.step_ratio, r.ms_full);
      const std::string scsv = (dir / ("contact_" + stems[i] + ".csv")).string();
      const std::string ssvg = (dir / ("contact_" + stems[i] + ".svg")).string();
      write_scene_contact_series_csv(r, scsv);
      write_scene_contact_plot_svg(r, ssvg);
      std::printf("wrote %s and %s (per step)\n", scsv.c_str(), ssvg.c_str());
    }
    std::printf("(forces in N, dent and depth in mm, times in ms; err: peak force, rms: per step above %.0f %% of "
                "the full FEM's peak)\nwrote %s and %s\n",
                100.0 * ss.force_threshold, summary.c_str(), md.c_str());
  }
  if (!builtin) return;
  write_contact_bench_csv(rows, csv);
  std::printf("%-8s %4s %7s %8s %9s %9s %6s %8s %8s %7s %7s %8s %9s %9s %6s %9s\n", "scene", "K", "dt", "rel_err",
              "dent_ref", "dent_red", "ratio", "F_ref", "F_red", "act_ref", "act_red", "us/s/it", "ms_cont", "ms_none", "x",
              "ms_full");
  for (const auto& r : rows)
    std::printf("%-8s %4d %7.5f %8.3f %9.2f %9.2f %6.3f %8.1f %8.1f %7d %7d %8.3f %9.3f %9.3f %6.2f %9.1f\n",
                r.scene.c_str(), r.handles, r.dt, r.rel_err, r.dent_full_mm, r.dent_reduced_mm, r.dent_ratio,
                r.force_full_n, r.force_reduced_n, r.active_samples_full, r.active_samples, r.us_per_sample_iter, r.ms_contact,
                r.ms_no_contact, r.step_ratio, r.ms_full);
  std::printf("(dent in mm, forces in N, times in ms; us/s/it = µs per active sample per Newton iteration)\n");
  std::printf("wrote %s and %s\n", csv.c_str(), md.c_str());
  bool probe = false;
  for (const auto& r : rows) probe = probe || r.scene == "probe";
  if (probe) {
    const std::string pcsv = (std::filesystem::path(a.out) / "contact_probe.csv").string();
    const std::string psvg = (std::filesystem::path(a.out) / "contact_probe.svg").string();
    write_probe_curves(rows, pcsv, psvg, o.settings.probe_report_depth);
    for (const auto& r : rows)
      if (r.scene == "probe")
        std::printf("probe at %.0f mm: K = %d: reduced %.2f N, full FEM %.2f N, error %.0f %%\n",
                    1e3 * o.settings.probe_report_depth, r.handles, r.force_at_depth_reduced_n,
                    r.force_at_depth_full_n, 100.0 * r.force_err);
    std::printf("wrote %s and %s (force against depth)\n", pcsv.c_str(), psvg.c_str());
  }
}

const CommandRegistrar reg(51, [](CLI::App& app) {
  auto a = std::make_shared<ContactBenchArgs>();
  auto* cmd = app.add_subcommand(
      "bench-contact",
      "Reduced vs. full FEM under contact: built-in scenes (a sphere pressed into the belly, a ball impact, probes) "
      "and scene files of your own (--scene)");
  cmd->add_flag("--quick", a->quick, "Smoke test: K = 32 only and shorter scenes");
  cmd->add_option("--model", a->model, "Body model")->capture_default_str();
  cmd->add_option("--betas", a->betas, "Body shape b0,b1,...");
  cmd->add_option("--handles", a->handles, "Handle counts (default 32,64,128; 32 with --quick)")
      ->delimiter(',')
      ->check(CLI::Range(1, 4096));
  cmd->add_option("--scenes", a->scenes,
                  "Built-in scenes to run: pressed, impact, probe (2 cm, thigh), probe-thigh-1cm, probe-belly, "
                  "probe-belly-1cm, probe-calf, probe-calf-1cm (default: all, unless --scene is given)")
      ->delimiter(',');
  cmd->add_option("--scene", a->scene_files,
                  "A scene file (YAML, as `sflsh simulate`) to run with the reduced solver as written and with the "
                  "full-FEM reference, compared per contact pair and grasping tool (repeatable). Alone it replaces the built-in scenes; "
                  "with --scenes both run. The scene sets its own avatar, solver and contact: the built-in scenes' "
                  "flags (--handles, --quick, --pressure-stiffness, ...) are refused with --scene alone. Writes "
                  "contact_<name>.csv/.svg per scene, contact_scenes.csv and a section of contact_bench.md");
  cmd->add_option("--nonlinearity-tolerance", a->nonlinearity_tolerance,
                  "Reduced solver: an extra Newton iteration when the energy's change departs from the quadratic "
                  "model by more than this share (default automatic; 0: never)");
  cmd->add_option("--newton-iters", a->newton_iters, "Reduced solver's Newton iterations per step")
      ->capture_default_str();
  cmd->add_option("--pressure-stiffness", a->pressure_stiffness,
                  "Contact pressure stiffness (N/m^3, over the skin's area), both solvers")
      ->capture_default_str();
  cmd->add_option("--spacing", a->spacing, "Contact sample spacing on the skin's faces (m), both solvers")
      ->capture_default_str();
  cmd->add_option("--patch-radius", a->patch_radius, "Radius of the full-space patch under a contact (m)")
      ->capture_default_str();
  cmd->add_option("--max-patch-nodes", a->max_patch_nodes,
                  "Nodes in one patch at most (beyond, the nodes nearest the deepest contact are kept)")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  cmd->add_flag("--no-patch", a->no_patch, "Contact on the reduced subspace alone (no full-space patch)");
  cmd->add_flag("--cpu-time", a->cpu_time,
                "The ms columns in CPU time of the stepping thread (robust to other jobs' load), not wall time");
  cmd->add_option("--cache-dir", a->cache_dir, "Template-stage cache folder");
  cmd->add_flag("--no-cache", a->no_cache, "Do not use the template-stage cache");
  cmd->add_option("--out", a->out, "Output folder (contact_bench.csv, contact_bench.md)")->capture_default_str();
  cmd->callback([a, cmd] {
    for (const char* flag : {"--quick", "--model", "--betas", "--handles", "--nonlinearity-tolerance", "--newton-iters",
                             "--pressure-stiffness", "--spacing", "--patch-radius", "--max-patch-nodes", "--no-patch",
                             "--no-cache"})
      if (a->builtin_only_flag.empty() && cmd->count(flag) > 0) a->builtin_only_flag = flag;
    std::string handles;
    for (size_t i = 0; i < a->handles.size(); ++i) handles += (i ? "," : " --handles ") + std::to_string(a->handles[i]);
    a->command_line = std::string("sflsh bench-contact") + (a->quick ? " --quick" : "") +
                      handles +
                      (a->newton_iters != 1 ? " --newton-iters " + std::to_string(a->newton_iters) : "") +
                      (a->betas.empty() ? "" : " --betas " + a->betas);
    for (size_t i = 0; i < a->scenes.size(); ++i) a->command_line += (i ? "," : " --scenes ") + a->scenes[i];
    char extra[160];
    std::snprintf(extra, sizeof extra, "%s%s%s", a->no_patch ? " --no-patch" : "",
                  a->pressure_stiffness != kDefaultPressureStiffness ? " --pressure-stiffness " : "",
                  a->pressure_stiffness != kDefaultPressureStiffness ? std::to_string(a->pressure_stiffness).c_str() : "");
    a->command_line += extra;
    if (a->cpu_time) a->command_line += " --cpu-time";
    if (a->nonlinearity_tolerance)
      a->command_line += " --nonlinearity-tolerance " + std::to_string(*a->nonlinearity_tolerance);
    if (a->spacing != kDefaultContactSpacing) a->command_line += " --spacing " + std::to_string(a->spacing);
    if (a->patch_radius != ContactPatchOptions().patch_radius)
      a->command_line += " --patch-radius " + std::to_string(a->patch_radius);
    if (a->max_patch_nodes != ContactPatchOptions().max_patch_nodes)
      a->command_line += " --max-patch-nodes " + std::to_string(a->max_patch_nodes);
    for (const std::string& f : a->scene_files) a->command_line += " --scene " + f;
    run_contact_bench(*a);
  });
});

}  // namespace
}  // namespace sflsh::cli
