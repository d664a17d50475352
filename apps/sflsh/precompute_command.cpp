// `sflsh precompute`: body model + shape β → avatar HDF5 file(s).
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "command.hpp"
#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/asset/avatar_summary.hpp"
#include "sflsh/asset/precompute.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh::cli {
namespace {

struct PrecomputeArgs {
  std::string model = "procedural";
  std::string betas;
  int handles = 64;
  int elastic_samples_per_cell = PrecomputeOptions().elastic_samples_per_cell;
  bool no_fit_cubature = false;
  std::string handles_file, thickness_map, out = "avatar.h5", batch, out_dir, cache_dir;
  bool no_cache = false;
  double cell_size = 0, facet_size = 0, facet_distance = 0;
};

/// Reads one β vector per line ("b0,b1,..."); a first line that is not
/// numeric is a header. Throws naming the file and line.
std::vector<VecX> read_betas_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, ": cannot open betas file");
  std::vector<VecX> rows;
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    try {
      rows.push_back(parse_betas(line));
    } catch (const Error& e) {
      if (lineno == 1 && rows.empty()) continue;  // header
      fail(path, ":", lineno, ": ", e.what());
    }
  }
  if (rows.empty()) fail(path, ": no rows of betas found");
  return rows;
}

PrecomputeOptions make_options(const PrecomputeArgs& a) {
  PrecomputeOptions o;
  o.handles = a.handles;
  require(a.handles >= 1 && a.handles <= 2000, "--handles must be in [1, 2000], got ", a.handles);
  require(a.elastic_samples_per_cell >= 1 && a.elastic_samples_per_cell <= 1000,
          "--elastic-samples-per-cell must be in [1, 1000], got ", a.elastic_samples_per_cell);
  o.elastic_samples_per_cell = a.elastic_samples_per_cell;
  o.fit_elastic_cubature = !a.no_fit_cubature;
  if (!a.handles_file.empty()) o.handle_positions = read_handles_file(a.handles_file);
  if (!a.thickness_map.empty()) o.thickness = read_thickness_map(a.thickness_map);
  if (!a.no_cache) o.cache_dir = a.cache_dir.empty() ? default_cache_dir() : a.cache_dir;
  if (a.cell_size > 0) o.template_stage.mesh.cell_size = a.cell_size;
  if (a.facet_size > 0) o.template_stage.mesh.facet_size = a.facet_size;
  if (a.facet_distance > 0) o.template_stage.mesh.facet_distance = a.facet_distance;
  return o;
}

void build_one(const BodyModel& model, const TemplateVolume& tv, const VecX& betas, const PrecomputeOptions& o,
               PrecomputeReport report, const std::string& out) {
  Avatar avatar = precompute_shape(tv, model, betas, o, &report);
  write_avatar(avatar, out);
  std::cout << summarize_avatar(avatar).to_text("wrote " + out) << report.describe();
}

void run_precompute(const PrecomputeArgs& a) {
  const PrecomputeOptions o = make_options(a);
  std::vector<VecX> shapes;
  if (!a.batch.empty()) {
    require(!a.out_dir.empty(), "--batch needs --out-dir");
    require(a.betas.empty(), "--batch and --betas exclude each other");
    io::check_output_folder(a.out_dir, "--out-dir");
    shapes = read_betas_csv(a.batch);
  } else {
    io::check_output_file(a.out, "--out");
    shapes.push_back(a.betas.empty() ? VecX() : parse_betas(a.betas));
  }
  const BodyModel model = load_body_model(a.model);
  for (const auto& b : shapes)
    require(b.size() <= model.num_betas(), "betas have ", b.size(), " entries but the model has ", model.num_betas(),
            " shape directions");
  PrecomputeReport report;
  const TemplateVolume tv = cached_template_volume(model, o, &report);
  if (a.batch.empty()) {
    build_one(model, tv, shapes[0], o, report, a.out);
    return;
  }
  for (size_t i = 0; i < shapes.size(); ++i) {
    std::ostringstream name;
    name << "avatar_" << std::setw(4) << std::setfill('0') << i + 1 << ".h5";
    const std::string out = (std::filesystem::path(a.out_dir) / name.str()).string();
    log_info("shape " + std::to_string(i + 1) + "/" + std::to_string(shapes.size()));
    PrecomputeReport r = report;
    r.template_from_cache = true;  // computed once for the batch
    build_one(model, tv, shapes[i], o, r, out);
  }
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
  cmd->add_flag("--no-fit-cubature", a->no_fit_cubature,
                "Keep the stratified elastic cubature's volume weights (no stiffness fit)");
  cmd->add_option("--handles-file", a->handles_file, "Handle positions, one 'x y z' per line (metres, unposed)");
  cmd->add_option("--thickness-map", a->thickness_map, "Skin thickness scale per body region ('region scale' per line)");
  cmd->add_option("--out", a->out, "Output avatar file")->capture_default_str();
  cmd->add_option("--batch", a->batch, "CSV of shapes, one β vector per line (header allowed)");
  cmd->add_option("--out-dir", a->out_dir, "Output folder for --batch (avatar_0001.h5, ... by data row)");
  cmd->add_option("--cache-dir", a->cache_dir, "Template-stage cache folder (default: $SFLSH_CACHE_DIR or ~/.cache/sflsh)");
  cmd->add_flag("--no-cache", a->no_cache, "Do not read or write the template-stage cache");
  cmd->add_option("--cell-size", a->cell_size, "Tet size bound (m, Mesh_3 cell_size; smaller = more tets)");
  cmd->add_option("--facet-size", a->facet_size, "Surface triangle size bound (m, Mesh_3 facet_size)");
  cmd->add_option("--facet-distance", a->facet_distance, "Surface approximation bound (m, Mesh_3 facet_distance)");
  cmd->callback([a] { run_precompute(*a); });
});

}  // namespace
}  // namespace sflsh::cli
