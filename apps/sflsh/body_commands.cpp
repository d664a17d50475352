// `sflsh body info|export|render`: look at a body model, write its shaped and
// posed surface (OBJ/PLY/glTF) and joints, or render a picture of it.
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>

#include "command.hpp"
#include "sflsh/body/body_model.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/io/joint_export.hpp"
#include "sflsh/io/mesh_export.hpp"
#include "sflsh/io/npz.hpp"
#include "sflsh/io/png_image.hpp"
#include "sflsh/io/render.hpp"
#include "sflsh/meshing/surface_checks.hpp"

namespace sflsh::cli {
namespace {

/// Options shared by the body sub-commands.
struct BodyArgs {
  std::string model = "procedural";
  std::string betas;
  std::string pose_file;
  std::string pose_preset;
  std::string translation;
};

void add_model_options(CLI::App* cmd, BodyArgs& a) {
  cmd->add_option("--model", a.model, "'procedural' (built-in body) or an SMPL-format model file (.h5, .npz)")
      ->capture_default_str();
  cmd->add_option("--betas", a.betas, "Shape coefficients b0,b1,... (missing ones are 0)");
}

void add_pose_options(CLI::App* cmd, BodyArgs& a) {
  auto* file = cmd->add_option("--pose", a.pose_file,
                               "Pose file: .npz with key 'pose' (72 or 24x3 axis-angle, radians; optional 'trans'), "
                               "or a text file with 72 numbers");
  auto* preset = cmd->add_option("--pose-preset", a.pose_preset, "Named pose: tpose, apose, walk, sit");
  file->excludes(preset);
  preset->excludes(file);
  cmd->add_option("--translation", a.translation, "Root translation x,y,z in metres (overrides the pose file's)");
}

/// Parses a comma-separated list of exactly `n` numbers for option `what`.
VecX parse_numbers(const std::string& csv, int n, const std::string& what) {
  std::vector<double> values;
  std::stringstream ss(csv);
  std::string token;
  while (std::getline(ss, token, ',')) {
    char* stop = nullptr;
    errno = 0;
    const double v = std::strtod(token.c_str(), &stop);
    const bool ok = stop != token.c_str() && std::string(stop).find_first_not_of(" \t") == std::string::npos &&
                    errno != ERANGE && std::isfinite(v);
    require(ok, what, ": '", token, "' in '", csv, "' is not a number");
    values.push_back(v);
  }
  require(int(values.size()) == n, what, ": expected ", n, " comma-separated numbers, got ", values.size(), " in '",
          csv, "'");
  return Eigen::Map<VecX>(values.data(), n);
}

/// Reads a pose: .npz (key 'pose', optional 'trans') or text with 72 numbers.
BodyPose read_pose_file(const std::string& path) {
  std::ifstream probe(path);
  require(bool(probe), "--pose ", path, ": cannot open file");
  probe.close();
  BodyPose pose;
  std::vector<double> values;
  if (io::lower_extension(path) == ".npz") {
    const auto arrays = io::read_npz(path);
    auto it = arrays.find("pose");
    require(it != arrays.end(), path, ": key 'pose' is missing (expected 72 or 24x3 axis-angle values)");
    require(it->second.size() == 72, path, ": key 'pose' has ", it->second.size(),
            " values, expected 72 (shape (72,), (24,3) or (1,72))");
    it->second.require_finite(path, "pose");
    values = it->second.data;
    auto t = arrays.find("trans");
    if (t != arrays.end()) {
      require(t->second.size() == 3, path, ": key 'trans' has ", t->second.size(), " values, expected 3");
      t->second.require_finite(path, "trans");
      pose.translation = Vec3(t->second.data[0], t->second.data[1], t->second.data[2]);
    }
  } else {
    std::ifstream is(path);
    std::string line;
    for (int line_no = 1; std::getline(is, line); ++line_no) {
      line = line.substr(0, line.find('#'));
      for (char& c : line)
        if (c == ',') c = ' ';
      std::istringstream ls(line);
      std::string token;
      while (ls >> token) {
        char* stop = nullptr;
        const double v = std::strtod(token.c_str(), &stop);
        require(*stop == '\0' && std::isfinite(v), path, ":", line_no, ": '", token, "' is not a number");
        values.push_back(v);
      }
    }
    require(values.size() == 72, path, ": found ", values.size(),
            " numbers, expected 72 (24 joints x 3 axis-angle components, radians)");
  }
  for (int j = 0; j < 24; ++j) pose.axis_angle.row(j) << values[3 * j], values[3 * j + 1], values[3 * j + 2];
  return pose;
}

struct LoadedBody {
  BodyModel model;
  VecX betas;
  BodyPose pose;
  std::string pose_name;  ///< for titles: preset name, file name or "tpose"
};

LoadedBody load_body(const BodyArgs& a) {
  LoadedBody b;
  // Parse the cheap arguments first so that a typo fails before the model loads.
  b.betas = parse_betas(a.betas);
  if (!a.pose_file.empty()) {
    b.pose = read_pose_file(a.pose_file);
    b.pose_name = a.pose_file;
  } else {
    b.pose_name = a.pose_preset.empty() ? "tpose" : a.pose_preset;
    b.pose = pose_preset(b.pose_name);
  }
  if (!a.translation.empty()) b.pose.translation = parse_numbers(a.translation, 3, "--translation");
  b.model = load_body_model(a.model);
  require(b.betas.size() <= b.model.num_betas(), "--betas: got ", b.betas.size(), " values but model '", a.model,
          "' has ", b.model.num_betas(), " shape directions");
  return b;
}

std::string betas_text(const VecX& betas) {
  if (betas.size() == 0) return "0";
  std::string s;
  for (Eigen::Index i = 0; i < betas.size(); ++i) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%s%g", i ? "," : "", betas[i]);
    s += buf;
  }
  return s;
}

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) >= 0x20) out += c;
  }
  return out + "\"";
}

void run_info(const BodyArgs& a, bool json) {
  const LoadedBody b = load_body(a);
  const Points v_shaped = shape_vertices(b.model, b.betas);
  const SurfaceReport r = check_surface(v_shaped, b.model.faces);
  const BodyModel& m = b.model;
  const char* yes_no[2] = {"no", "yes"};
  if (json) {
    std::printf("{\n  \"model\": %s,\n  \"vertices\": %d,\n  \"faces\": %d,\n  \"joints\": %d,\n",
                json_string(m.source.empty() ? a.model : m.source).c_str(), m.num_vertices(), int(m.faces.rows()),
                m.num_joints());
    std::printf("  \"num_betas\": %d,\n  \"betas\": [", m.num_betas());
    for (Eigen::Index i = 0; i < b.betas.size(); ++i) std::printf("%s%.17g", i ? ", " : "", b.betas[i]);
    std::printf("],\n  \"shape_meanings\": [");
    for (size_t i = 0; i < m.shape_meanings.size(); ++i)
      std::printf("%s%s", i ? ", " : "", json_string(m.shape_meanings[i]).c_str());
    std::printf("],\n  \"pose_blend_shapes\": %s,\n  \"height_m\": %.6f,\n", m.has_pose_blend_shapes() ? "true" : "false",
                r.height());
    std::printf("  \"closed\": %s,\n  \"manifold\": %s,\n  \"oriented\": %s,\n  \"components\": %d,\n  \"genus\": %d,\n",
                r.is_closed ? "true" : "false", r.is_manifold ? "true" : "false",
                r.consistently_oriented ? "true" : "false", r.num_components, r.genus);
    std::printf("  \"self_intersection_tested\": %s,\n  \"self_intersects\": %s,\n  \"volume_m3\": %.6f,\n",
                r.self_intersection_tested ? "true" : "false", r.self_intersects ? "true" : "false", r.signed_volume);
    std::printf("  \"area_m2\": %.6f,\n  \"mean_edge_m\": %.6f\n}\n", r.area, r.mean_edge_length);
    return;
  }
  std::printf("model:        %s\n", m.source.empty() ? a.model.c_str() : m.source.c_str());
  std::printf("vertices:     %d\nfaces:        %d\njoints:       %d\n", m.num_vertices(), int(m.faces.rows()),
              m.num_joints());
  std::printf("shape space:  %d directions (betas used: %s)\n", m.num_betas(), betas_text(b.betas).c_str());
  for (size_t i = 0; i < m.shape_meanings.size(); ++i)
    std::printf("  beta[%zu]: %s\n", i, m.shape_meanings[i].c_str());
  std::printf("pose blend shapes: %s\n", m.has_pose_blend_shapes() ? "yes" : "none (all zero)");
  std::printf("height:       %.3f m (shaped surface, max - min y)\n", r.height());
  std::printf("closed:       %s\nmanifold:     %s\n", yes_no[r.is_closed], yes_no[r.is_manifold]);
  std::printf("surface:      %s\n", r.describe().c_str());
}

/// Checks an output path's folder can be made and its format is known before
/// any work is done, so a typo costs nothing.
void check_joint_path(const std::string& path) {
  const std::string ext = io::lower_extension(path);
  require(ext == ".csv" || ext == ".json", "--joints ", path, ": unknown joint file format '", ext,
          "'; supported: .csv, .json");
  io::check_output_file(path, "--joints");
}

void run_export(const BodyArgs& a, const std::string& out, const std::string& joints_out) {
  io::require_mesh_export_extension(out, "--out " + out);
  io::check_output_file(out, "--out");
  if (!joints_out.empty()) check_joint_path(joints_out);
  const LoadedBody b = load_body(a);
  const PosedBody posed = pose_body(b.model, b.betas, b.pose);
  io::write_mesh(out, posed.v_posed, b.model.faces);
  std::printf("wrote %s (%d vertices, %d faces; betas %s, pose %s)\n", out.c_str(), int(posed.v_posed.rows()),
              int(b.model.faces.rows()), betas_text(b.betas).c_str(), b.pose_name.c_str());
  if (!joints_out.empty()) {
    std::vector<std::string> names = b.model.joint_names;
    if (names.size() != size_t(posed.joints_posed.rows()))
      for (int j = int(names.size()); j < posed.joints_posed.rows(); ++j) names.push_back("joint" + std::to_string(j));
    io::write_joints(joints_out, posed.joints_posed, names, b.model.parents);
    std::printf("wrote %s (%d joints)\n", joints_out.c_str(), int(posed.joints_posed.rows()));
  }
}

void run_render(const BodyArgs& a, const std::string& out, int size) {
  require(io::lower_extension(out) == ".png", "--out ", out, ": the picture is written as PNG; use a .png name");
  io::check_output_file(out, "--out");
  require(size >= 64 && size <= 8192, "--size: expected 64..8192 pixels, got ", size);
  const LoadedBody b = load_body(a);
  const PosedBody posed = pose_body(b.model, b.betas, b.pose);
  io::RenderOptions opt;
  opt.width = size * 5 / 4;
  opt.height = size;
  const double height = posed.v_shaped.col(1).maxCoeff() - posed.v_shaped.col(1).minCoeff();
  char height_text[32];
  std::snprintf(height_text, sizeof height_text, "%.2f m", height);
  opt.title = "sflsh body  height " + std::string(height_text) + "  betas " + betas_text(b.betas) + "  pose " +
              b.pose_name;
  Timer t;
  const io::Image img = io::render_views(posed.v_posed, b.model.faces, opt);
  const double ms = t.ms();
  io::write_png(out, img);
  std::printf("wrote %s (%d x %d, rendered in %.0f ms)\n", out.c_str(), img.width, img.height, ms);
}

CommandRegistrar reg(10, [](CLI::App& app) {
  auto* body = app.add_subcommand("body", "Inspect, export and render a body model");
  body->require_subcommand(1);

  auto args = std::make_shared<BodyArgs>();
  auto json = std::make_shared<bool>(false);
  auto* info = body->add_subcommand("info", "Counts, shape space, height and surface checks of a body model");
  add_model_options(info, *args);
  info->add_flag("--json", *json, "Print JSON instead of text");
  info->callback([args, json] { run_info(*args, *json); });

  auto out = std::make_shared<std::string>();
  auto joints = std::make_shared<std::string>();
  auto* exp = body->add_subcommand("export", "Write the shaped, posed surface (.obj .ply .glb .gltf) and joints");
  add_model_options(exp, *args);
  add_pose_options(exp, *args);
  exp->add_option("--out", *out, "Output surface file; format from the extension")->required();
  exp->add_option("--joints", *joints, "Also write posed joint positions (.csv or .json)");
  exp->callback([args, out, joints] { run_export(*args, *out, *joints); });

  auto size = std::make_shared<int>(800);
  auto* render = body->add_subcommand("render", "Render a shaded front and side view to PNG");
  add_model_options(render, *args);
  add_pose_options(render, *args);
  render->add_option("--out", *out, "Output .png")->required();
  render->add_option("--size", *size, "Image height in pixels (width is 5/4 of it)")->capture_default_str();
  render->callback([args, out, size] { run_render(*args, *out, *size); });
});

}  // namespace
}  // namespace sflsh::cli
