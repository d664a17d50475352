// `sflsh precompute`: body model + shape β → avatar HDF5 file(s).
#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <optional>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <thread>

#include "command.hpp"
#include "support_flags.hpp"
#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/precompute/avatar_summary.hpp"
#include "sflsh/mesh/tet_topology_hash.hpp"
#include "sflsh/precompute/batch_precompute.hpp"
#include "sflsh/precompute/precompute.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/child_processes.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh::cli {
namespace {

struct PrecomputeArgs {
  std::string model = "procedural";
  std::string betas;
  int handles = PrecomputeOptions().handles;
  int elastic_samples_per_cell = PrecomputeOptions().elastic_samples_per_cell;
  int inertia_samples_per_cell = PrecomputeOptions().inertia_samples_per_cell;
  int handles_min_per_region = PrecomputeOptions().placement.min_per_region;
  std::string support_spacing;  // dimensionless; empty = off
  std::string support_radius;  // m; empty = unrestricted supports (the default)
  bool no_fit_cubature = false;
  std::string handles_file, thickness_map, out = "avatar.h5", batch, out_dir, cache_dir;
  bool no_cache = false, template_only = false, dry_run = false;
  double cell_size = 0, facet_size = 0, facet_distance = 0;
  int jobs = 0, task_index = -1;
  int threads = 0;  // per shape (weights stage); 0 = all cores, or cores / workers in a batch
  std::string shard, manifest;
};

PrecomputeOptions make_options(const PrecomputeArgs& a) {
  PrecomputeOptions o;
  o.handles = a.handles;
  require(a.handles >= 1 && a.handles <= 2000, "--handles must be in [1, 2000], got ", a.handles);
  require(a.elastic_samples_per_cell >= 1 && a.elastic_samples_per_cell <= 1000,
          "--elastic-samples-per-cell must be in [1, 1000], got ", a.elastic_samples_per_cell);
  o.elastic_samples_per_cell = a.elastic_samples_per_cell;
  o.fit_elastic_cubature = !a.no_fit_cubature;
  require(a.inertia_samples_per_cell >= 0 && a.inertia_samples_per_cell <= 1000,
          "--inertia-samples-per-cell must be in [0, 1000], got ", a.inertia_samples_per_cell);
  o.inertia_samples_per_cell = a.inertia_samples_per_cell;
  require(a.handles_min_per_region >= 0 && a.handles_min_per_region <= a.handles,
          "--handles-min-per-region must be in [0, --handles = ", a.handles, "], got ", a.handles_min_per_region);
  o.placement.min_per_region = a.handles_min_per_region;
  if (!a.handles_file.empty()) o.handle_positions = read_handles_file(a.handles_file);
  if (!a.thickness_map.empty()) o.thickness = read_thickness_map(a.thickness_map);
  if (!a.no_cache) o.cache_dir = a.cache_dir.empty() ? default_cache_dir() : a.cache_dir;
  for (const auto& [flag, v] : {std::pair<const char*, double>{"--cell-size", a.cell_size},
                                {"--facet-size", a.facet_size}, {"--facet-distance", a.facet_distance}})
    require(std::isfinite(v) && v >= 0 && v <= 1, flag, " must be a length in (0, 1] m (or 0 for the default), got ", v);
  if (a.cell_size > 0) o.template_stage.mesh.cell_size = a.cell_size;
  if (a.facet_size > 0) o.template_stage.mesh.facet_size = a.facet_size;
  if (a.facet_distance > 0) o.template_stage.mesh.facet_distance = a.facet_distance;
  require(a.threads >= 0 && a.threads <= 1024, "--threads must be in [1, 1024] (or 0 for all cores), got ", a.threads);
  o.bbw.threads = a.threads;
  apply_support_flags(a.support_radius, a.support_spacing, o.bbw);
  return o;
}

void build_one(const BodyModel& model, const TemplateVolume& tv, const VecX& betas, const PrecomputeOptions& o,
               PrecomputeReport report, const std::string& out) {
  Avatar avatar = precompute_shape(tv, model, betas, o, &report);
  write_avatar(avatar, out);
  std::cout << summarize_avatar(avatar).to_text("wrote " + out) << report.describe();
}

std::string number(double v) {
  std::ostringstream s;
  s << std::setprecision(17) << v;
  return s.str();
}

/// The command line of a worker that builds data row `row` alone and writes
/// its record to `manifest`: this executable with the same options.
std::vector<std::string> worker_command(const PrecomputeArgs& a, const PrecomputeOptions& o, int row,
                                        const std::string& manifest) {
  std::vector<std::string> c = {self_executable(), "-q", "precompute", "--model", a.model, "--handles",
                                std::to_string(a.handles), "--elastic-samples-per-cell",
                                std::to_string(a.elastic_samples_per_cell), "--inertia-samples-per-cell",
                                std::to_string(a.inertia_samples_per_cell), "--handles-min-per-region",
                                std::to_string(a.handles_min_per_region), "--cache-dir", o.cache_dir};
  if (a.no_fit_cubature) c.push_back("--no-fit-cubature");
  if (!a.support_radius.empty()) c.insert(c.end(), {"--support-radius", a.support_radius});
  if (!a.support_spacing.empty()) c.insert(c.end(), {"--support-spacing", a.support_spacing});
  for (const auto& [flag, value] : {std::pair<const char*, const std::string*>{"--handles-file", &a.handles_file},
                                    {"--thickness-map", &a.thickness_map}})
    if (!value->empty()) c.insert(c.end(), {flag, *value});
  for (const auto& [flag, value] :
       {std::pair<const char*, double>{"--cell-size", a.cell_size}, {"--facet-size", a.facet_size},
        {"--facet-distance", a.facet_distance}})
    if (value > 0) c.insert(c.end(), {flag, number(value)});
  c.insert(c.end(), {"--threads", std::to_string(o.bbw.threads), "--batch", a.batch, "--out-dir", a.out_dir,
                     "--task-index", std::to_string(row), "--manifest", manifest});
  return c;
}

std::string default_manifest(const PrecomputeArgs& a, const BatchShard& shard) {
  std::string name = "manifest.csv";
  if (a.task_index >= 0)
    name = "manifest-task-" + std::to_string(a.task_index) + ".csv";
  else if (shard.count > 1)
    name = "manifest-shard-" + std::to_string(shard.index) + "-of-" + std::to_string(shard.count) + ".csv";
  return (std::filesystem::path(a.out_dir) / name).string();
}

/// Runs the pending rows of `records`, `jobs` at a time, each in a worker
/// process (worker_command); fills in their records. `on_done` is called after each.
void run_in_workers(const PrecomputeArgs& a, const PrecomputeOptions& o, int jobs, std::vector<BatchRecord>& records,
                    const std::function<void(const BatchRecord&)>& on_done) {
  const std::filesystem::path logs = std::filesystem::path(a.out_dir) / "logs";
  std::error_code ec;
  std::filesystem::create_directories(logs, ec);
  if (ec) fail(logs.string(), ": cannot create the worker log folder: ", ec.message());
  auto stem = [&](int row) {
    std::ostringstream s;
    s << "row-" << std::setw(6) << std::setfill('0') << row;
    return (logs / s.str()).string();
  };
  // The workers are the parallelism: one OpenMP thread each inside CHOLMOD
  // (spinning OpenMP threads of several processes would fight over the
  // cores), unless the user set it. The weights stage keeps its own threads.
  setenv("OMP_NUM_THREADS", "1", 0);
  ChildProcesses workers;
  std::map<int, size_t> running;  // pid -> record
  auto collect = [&] {
    const ChildExit e = workers.wait_any();
    BatchRecord& r = records[running.at(e.pid)];
    running.erase(e.pid);
    const std::string base = stem(r.row);
    BatchRecord reported;
    bool have = false;
    try {
      const auto rows = read_batch_manifest(base + ".csv");
      have = rows.size() == 1 && rows[0].row == r.row;
      if (have) reported = rows[0];
    } catch (const Error&) {
    }
    if (have && (e.exit_code == 0) == (reported.status != "failed")) {
      r.status = reported.status;
      r.topology = reported.topology;
      r.error = reported.error;
    } else {
      r.status = "failed";
      r.error = "worker " + e.describe() + (have && !reported.error.empty() ? ": " + reported.error : "");
    }
    r.seconds = e.seconds;
    r.peak_rss_mib = e.peak_rss_mib;
    std::filesystem::remove(base + ".csv", ec);
    if (r.status == "failed")
      r.error += " (log: " + base + ".log)";
    else
      std::filesystem::remove(base + ".log", ec);
    on_done(r);
  };
  for (size_t i = 0; i < records.size(); ++i) {
    if (records[i].status != "pending") continue;
    while (workers.running() >= jobs) collect();
    const std::string base = stem(records[i].row);
    running[workers.start(worker_command(a, o, records[i].row, base + ".csv"), base + ".log")] = i;
  }
  while (workers.running() > 0) collect();
  std::filesystem::remove(logs, ec);  // only when empty: every row succeeded
}

void run_batch(const PrecomputeArgs& a, PrecomputeOptions o) {
  require(!a.out_dir.empty(), "--batch needs --out-dir");
  io::check_output_folder(a.out_dir, "--out-dir");
  require(a.betas.empty(), "--batch and --betas exclude each other");
  require(a.task_index < 0 || a.shard.empty(), "--task-index and --shard exclude each other");
  require(a.jobs >= 0 && a.jobs <= 1024, "--jobs must be in [1, 1024] (or 0 for all cores), got ", a.jobs);
  const BatchShard shard = a.shard.empty() ? BatchShard{} : parse_batch_shard(a.shard);
  o.bbw.show_progress = false;  // the batch prints its own progress
  const BodyModel model = load_body_model(a.model);
  const std::vector<BatchShape> shapes = read_batch_shapes(a.batch, model.num_betas());
  require(a.task_index < int(shapes.size()), a.batch, ": --task-index ", a.task_index, " but the file has ",
          shapes.size(), " data rows (task indices 0 to ", shapes.size() - 1, ")");
  const std::string manifest = a.manifest.empty() ? default_manifest(a, shard) : a.manifest;

  Timer wall;
  // A manifest left by an earlier run must still describe its files (one line naming the row otherwise).
  if (std::error_code ec; std::filesystem::exists(manifest, ec)) verify_batch_manifest(manifest);
  std::vector<BatchRecord> records = plan_batch(shapes, model, o, a.out_dir, shard, a.task_index);
  int pending = 0;
  for (const BatchRecord& r : records) pending += r.status == "pending";
  // Failed rows are reported even with --quiet.
  auto report_failure = [&](const BatchRecord& r) {
    std::cerr << "batch: row " << r.row << " (" << a.batch << " line " << r.line << ") failed: " << r.error << "\n";
  };
  int invalid = 0;
  for (const BatchRecord& r : records) invalid += r.status == "failed";
  // No valid row at all: a bad input file, one error line (not a table).
  if (invalid > 0 && invalid == int(records.size())) {
    const auto first = std::find_if(records.begin(), records.end(), [](const BatchRecord& r) { return r.status == "failed"; });
    fail(a.batch, " line ", first->line, ": ", first->error, invalid > 1 ? " (and " + std::to_string(invalid - 1) +
         " more invalid rows; no valid row to build)" : " (no valid row to build)");
  }
  std::error_code ec;  // made only now: a file with no valid row leaves no folder
  std::filesystem::create_directories(a.out_dir, ec);
  if (ec) fail(a.out_dir, ": cannot create output folder: ", ec.message());
  for (const BatchRecord& r : records)
    if (r.status == "failed") report_failure(r);
  const int cores = int(std::max(1u, std::thread::hardware_concurrency()));
  const int jobs = std::max(1, std::min(pending, a.task_index >= 0 ? 1 : (a.jobs > 0 ? a.jobs : cores)));
  log_info("batch: " + std::to_string(records.size()) + " rows in this run, " + std::to_string(pending) +
           " to build" + (pending > 1 ? " with " + std::to_string(jobs) + (jobs > 1 ? " worker processes" : " process") : "") +
           ", " + std::to_string(int(records.size()) - pending) + " done already, duplicate or invalid");
  // One tet topology per folder (seed §4): the files already there must agree with each other and
  // with what this run builds (its template stage, built or loaded once, before any worker starts:
  // they all load it).
  std::optional<TemplateVolume> tv;
  std::string topology;
  PrecomputeReport template_report;
  if (pending > 0 && !a.dry_run) {
    require(jobs == 1 || !o.cache_dir.empty(),
            "--no-cache with --jobs ", jobs, ": the worker processes share the template stage through the cache; "
            "give a --cache-dir instead (or --jobs 1)");
    tv = cached_template_volume(model, o, &template_report);
    topology = tet_topology_hash(tv->tet.elements);
    if (!template_report.template_from_cache && a.task_index >= 0)
      log_info("batch: note: the template stage was not in the cache and was built by this task; with parallel "
               "tasks run `sflsh precompute --template-only` with the same options first, so they share one build");
  }
  check_batch_topology(a.out_dir, topology,
                       "template stage " + (template_report.template_cache_path.empty()
                                                ? "of " + a.model + " (not cached)"
                                                : template_report.template_cache_path));
  write_batch_manifest(records, manifest);
  if (a.dry_run) {
    std::cout << batch_summary(records, wall.seconds()) << "manifest (plan only, nothing built): " << manifest << "\n";
    return;
  }

  // Workers share the cores: unless --threads says otherwise, each solves its
  // weights on cores / workers threads (two workers each running one thread
  // per core only contend: 20 % more CPU per shape, measured).
  if (jobs > 1 && o.bbw.threads == 0) o.bbw.threads = std::max(1, cores / jobs);

  if (pending > 0) {
    int done = 0, failed = 0;
    Timer timer;
    auto on_done = [&](const BatchRecord& r) {
      ++done;
      if (r.status == "failed") {
        ++failed;
        report_failure(r);
      }
      log_info(batch_progress_line(done, pending, failed, timer.seconds()));
      write_batch_manifest(records, manifest);
    };
    if (jobs == 1) {
      for (BatchRecord& r : records)
        if (r.status == "pending") {
          r = precompute_batch_row(r, shapes[r.row], *tv, model, o);
          on_done(r);
        }
    } else {
      run_in_workers(a, o, jobs, records, on_done);
    }
  }
  write_batch_manifest(records, manifest);
  for (const BatchRecord& r : records)  // every output of this run has the template's tets
    if (!topology.empty() && r.status == "built" && r.topology != topology)
      fail("batch: ", r.file, " (row ", r.row, ") has tet topology ", r.topology, " but the template stage has ",
           topology, " (manifest ", manifest, ")");
  int failed = 0;
  for (const BatchRecord& r : records) failed += r.status == "failed";
  std::cout << batch_summary(records, wall.seconds()) << "manifest: " << manifest << "\n";
  if (failed > 0)
    fail("batch: ", failed, " of ", records.size(), " rows failed (table above; manifest ", manifest, ")");
}

void run_precompute(const PrecomputeArgs& a) {
  const PrecomputeOptions o = make_options(a);
  if (!a.batch.empty() && !a.template_only) return run_batch(a, o);
  require(a.out_dir.empty(), "--out-dir needs --batch");
  for (const auto& [flag, set] : {std::pair<const char*, bool>{"--jobs", a.jobs != 0}, {"--task-index", a.task_index >= 0},
                                  {"--shard", !a.shard.empty()}, {"--manifest", !a.manifest.empty()},
                                  {"--dry-run", a.dry_run}})
    require(!set || !a.batch.empty(), flag, " needs --batch");
  if (!a.template_only) io::check_output_file(a.out, "--out");
  const VecX betas = a.betas.empty() ? VecX() : parse_betas(a.betas);
  const BodyModel model = load_body_model(a.model);
  require(betas.size() <= model.num_betas(), "betas have ", betas.size(), " entries but the model has ",
          model.num_betas(), " shape directions");
  PrecomputeReport report;
  const TemplateVolume tv = cached_template_volume(model, o, &report);
  if (a.template_only) {
    require(!o.cache_dir.empty(), "--template-only writes the template stage to the cache: drop --no-cache");
    std::cout << "template stage " << (report.template_from_cache ? "already in the cache: " : "built and cached: ")
              << report.template_cache_path << "\n";
    return;
  }
  build_one(model, tv, betas, o, report, a.out);
}

const CommandRegistrar reg(20, [](CLI::App& app) {
  auto a = std::make_shared<PrecomputeArgs>();
  auto* cmd = app.add_subcommand("precompute", "Build an avatar file (tet mesh, reduced basis, cubature) for a body shape");
  cmd->add_option("--model", a->model, "Body model: 'procedural' or an SMPL-format .h5/.npz file")->capture_default_str();
  cmd->add_option("--betas", a->betas, "Shape parameters b0,b1,... (missing entries are 0)");
  cmd->add_option("--handles", a->handles, "Number of control-point handles K (3K reduced DoFs)")->capture_default_str();
  cmd->add_option("--elastic-samples-per-cell", a->elastic_samples_per_cell,
                  "Elastic cubature candidates per cell of dominant weight")
      ->capture_default_str();
  cmd->add_option("--inertia-samples-per-cell", a->inertia_samples_per_cell,
                  "Inertia cubature: candidate nodes per cell, weights fitted to the lumped mass matrix "
                  "(0 = one data-oblivious sample per handle)")
      ->capture_default_str();
  cmd->add_option("--handles-min-per-region", a->handles_min_per_region,
                  "Handles at least in every body region with >= 1 % of the allocation weight (soft volume x "
                  "thickness^0.5; the rest go by that weight; "
                  "more gives the limbs and neck finer soft DoFs at the torso's expense)")
      ->capture_default_str();
  cmd->add_option("--support-spacing", a->support_spacing,
                  "Compact support sized by the handle spacing: each handle's radius (along the tet edges) is this "
                  "factor times the distance to its nearest handle");
  cmd->add_option("--support-radius", a->support_radius,
                  "Compact support: each handle's weight is 0 beyond this path length along the tet edges (m); "
                  "needs --handles >= the number of simulated regions (default: unrestricted)");
  cmd->add_flag("--no-fit-cubature", a->no_fit_cubature,
                "Keep the stratified elastic cubature's volume weights (no stiffness fit)");
  cmd->add_option("--handles-file", a->handles_file, "Handle positions, one 'x y z' per line (metres, unposed)");
  cmd->add_option("--thickness-map", a->thickness_map, "Skin thickness scale per body region ('region scale' per line)");
  cmd->add_option("--out", a->out, "Output avatar file")->capture_default_str();
  cmd->add_option("--batch", a->batch,
                  "CSV of shapes, one β vector per line; an optional header, whose 'name' column labels the rows");
  cmd->add_option("--out-dir", a->out_dir,
                  "Output folder for --batch: avatar-<content key>.h5 per row, manifest.csv maps rows to files");
  cmd->add_option("--jobs", a->jobs, "--batch: worker processes (default 0 = all cores; 1 = in this process)")
      ->capture_default_str();
  cmd->add_option("--threads", a->threads,
                  "Threads per shape for the weights stage (default 0 = all cores; with --batch --jobs N, cores / N "
                  "per worker). The result does not depend on it");
  cmd->add_option("--task-index", a->task_index, "--batch: build only data row i (0-based; for job arrays)");
  cmd->add_option("--shard", a->shard, "--batch: build only rows r with r % n == i, given as i/n");
  cmd->add_option("--manifest", a->manifest,
                  "--batch: manifest CSV (default <out-dir>/manifest.csv, manifest-shard-i-of-n.csv, "
                  "manifest-task-i.csv)");
  cmd->add_flag("--dry-run", a->dry_run,
                "--batch: only write the manifest (rows pending, exists, duplicate or failed) and build nothing");
  cmd->add_flag("--template-only", a->template_only,
                "Only build (or find) the template stage in the cache, e.g. before starting parallel tasks");
  cmd->add_option("--cache-dir", a->cache_dir, "Template-stage cache folder (default: $SFLSH_CACHE_DIR or ~/.cache/sflsh)");
  cmd->add_flag("--no-cache", a->no_cache, "Do not read or write the template-stage cache");
  cmd->add_option("--cell-size", a->cell_size, "Tet size bound (m, Mesh_3 cell_size; smaller = more tets)");
  cmd->add_option("--facet-size", a->facet_size, "Surface triangle size bound (m, Mesh_3 facet_size)");
  cmd->add_option("--facet-distance", a->facet_distance, "Surface approximation bound (m, Mesh_3 facet_distance)");
  cmd->callback([a] { run_precompute(*a); });
});

}  // namespace
}  // namespace sflsh::cli
