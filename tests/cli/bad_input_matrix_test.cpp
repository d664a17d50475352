// The bad-input matrix: one data-driven table that runs every CLI
// entry point against missing, empty, truncated, wrong-type (a PNG) and
// directory inputs, NaN in each numeric field or flag, wrong array shapes,
// unknown joint/region names, out-of-range numbers and unwritable outputs.
// Every case must end with exactly one output line naming the file and/or the
// field, an exit code in 1..127, no output file and no .partial left behind.
//
// Adding a command is one row: an Input slot (command line with "{}" where
// the file goes, the valid file to truncate, what the error must name) gets
// the five file variants; a Flag row is one command line. Inputs are tiny
// (the synthetic box avatar, tiny.bvh, the generated tiny SMPL model); every
// case is expected to fail before any real work, and runs under a timeout.
#include <gtest/gtest.h>

#include <hdf5.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/io/npz.hpp"
#include "sflsh/io/png_image.hpp"
#include "sim/skeleton_fixture.hpp"
#include "sim/synthetic_avatar.hpp"
#include "test_support.hpp"

using namespace sflsh;
namespace fs = std::filesystem;

namespace {

/// One case: the arguments after `sflsh -q`, the fragments the single error
/// line must hold, and the outputs that must not exist afterwards (nor their .partial).
struct Case {
  std::string args;
  std::vector<std::string> fragments;
  std::vector<std::string> outputs;
};

/// A file input of a command: `args` holds "{}" where the path goes; `ext` is
/// the file's extension; `valid` a valid file of that kind (truncated to half
/// for the truncated case; empty = no truncated case); `outputs` the command's
/// outputs, which must not appear.
struct Input {
  std::string args, ext, valid;
  std::vector<std::string> outputs;
};

std::string replace(std::string s, const std::string& what, const std::string& with) {
  const size_t p = s.find(what);
  if (p != std::string::npos) s.replace(p, what.size(), with);
  return s;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void write_text(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

/// The first half of a file: binary files cut in the middle; text files cut
/// after the first word of their middle line (a cut at a line end can leave a
/// shorter but valid table).
std::string truncate(const std::string& text) {
  size_t cut = text.size() / 2;
  if (text.find('\0') != std::string::npos || text.compare(0, 4, "\x89HDF") == 0) return text.substr(0, cut);
  cut = text.rfind('\n', cut);
  cut = cut == std::string::npos ? 0 : cut + 1;
  const size_t word = text.find_first_not_of(" \t", cut);
  const size_t end = text.find_first_of(" \t\n,", word == std::string::npos ? cut : word);
  return text.substr(0, end == std::string::npos ? text.size() / 2 : end);
}

int count_lines(const std::string& text) {
  std::istringstream in(text);
  int n = 0;
  for (std::string line; std::getline(in, line);)
    if (line.find_first_not_of(" \t\r") != std::string::npos) ++n;
  return n;
}

/// Replaces dataset `name` of HDF5 file `path` by `values` of shape `dims`
/// (doubles), through the HDF5 C API (no project code in between).
void replace_h5_dataset(const std::string& path, const std::string& name, const std::vector<double>& values,
                        const std::vector<hsize_t>& dims) {
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0) << path;
  ASSERT_GE(H5Ldelete(f, name.c_str(), H5P_DEFAULT), 0) << name;
  const hid_t space = H5Screate_simple(int(dims.size()), dims.data(), nullptr);
  const hid_t d = H5Dcreate2(f, name.c_str(), H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(d, 0) << name;
  H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  H5Dclose(d);
  H5Sclose(space);
  H5Fclose(f);
}

/// The values and shape of a numeric dataset.
std::vector<double> read_h5_dataset(const std::string& path, const std::string& name, std::vector<hsize_t>* dims) {
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t d = H5Dopen2(f, name.c_str(), H5P_DEFAULT);
  const hid_t space = H5Dget_space(d);
  dims->assign(H5Sget_simple_extent_ndims(space), 0);
  H5Sget_simple_extent_dims(space, dims->data(), nullptr);
  std::vector<double> v(H5Sget_simple_extent_npoints(space));
  H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  H5Sclose(space);
  H5Dclose(d);
  H5Fclose(f);
  return v;
}

/// Every numeric scalar of a YAML tree: its path of keys/indices and a setter.
void numeric_scalars(YAML::Node n, const std::string& path, std::vector<std::pair<std::string, YAML::Node>>& out) {
  if (n.IsMap()) {
    for (auto kv : n) numeric_scalars(kv.second, path.empty() ? kv.first.as<std::string>() : path + "." + kv.first.as<std::string>(), out);
  } else if (n.IsSequence()) {
    for (size_t i = 0; i < n.size(); ++i) numeric_scalars(n[i], path + "[" + std::to_string(i) + "]", out);
  } else if (n.IsScalar()) {
    double v;
    if (YAML::convert<double>::decode(n, v)) out.emplace_back(path, n);
  }
}

/// The last map key of a YAML path ("objects[0].keyframes[1].position[2]" -> "position").
std::string last_key(const std::string& path) {
  std::string p = path.substr(0, path.find('[', path.rfind('.') == std::string::npos ? 0 : path.rfind('.')));
  return p.substr(p.rfind('.') == std::string::npos ? 0 : p.rfind('.') + 1);
}

class BadInputMatrix : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir();
    const auto f = [](const std::string& n) { return dir_->file(n); };
    // The small box avatar with the SMPL T-pose skeleton (as the scene tests use).
    test::SyntheticAvatarOptions o;
    o.handles = 4;
    o.handle_radius = 0.1;
    o.all_tets = false;
    o.samples = 6;
    Avatar a = test::make_synthetic_avatar(o);
    a.joints_rest = test::make_tpose_skeleton().joints_rest;
    write_avatar(a, f("a.h5"));
    // A PNG, to stand where another format is expected.
    io::Image img(4, 4, {200, 10, 10});
    io::write_png(f("picture.png"), img);
    fs::copy_file(test::fixture("motion/tiny.bvh"), f("m.bvh"));
    fs::copy_file(test::generated_fixture("tiny_smpl.npz"), f("model.npz"));
    std::ofstream(f("plain_file")) << "not a folder\n";
    write_text(f("material.yaml"), "all: {young: 5000, poisson: 0.45, density: 1000}\n");
    write_text(f("joints.map"), "Hips pelvis\nSpine spine1\nLeftUpLeg left_hip\nLeftLeg left_knee\n");
    write_text(f("thickness.txt"), "torso 1.2\nhead 0.8\n");
    write_text(f("handles.txt"), "0 1 0\n0.1 0.5 0.05\n-0.1 0.5 0.05\n");
    std::string pose = "0 0 0\n";
    for (int j = 1; j < 24; ++j) pose += "0.1 0 0\n";
    write_text(f("pose.txt"), pose);
    write_text(f("batch.csv"), "name,b0,b1\nx,0.5,0\ny,-0.5,1\n");
    write_text(f("scene.yaml"), scene_text());
    std::string out;
    ASSERT_EQ(test::run_command(test::sflsh_binary() + " -q motion export " + f("m.bvh") + " --out " + f("m.npz"), &out), 0)
        << out;
    ASSERT_EQ(test::run_command(test::sflsh_binary() + " -q simulate --avatar " + f("a.h5") +
                                    " --motion builtin:idle --seconds 0.05 --out " + f("r.h5") + " --checkpoint " +
                                    f("state.h5"),
                                &out),
              0)
        << out;
    fs::remove(f("r.h5"));
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  /// A scene with every kind of numeric field: solver, output, contact, a
  /// body with a placement and a velocity, a dynamic ball and a kinematic box.
  static std::string scene_text() {
    return R"(solver: {dt: 0.02, seconds: 0.04, newton_iters: 1, gravity: [0, -9.81, 0], damping: 0}
output: {out: )" + dir_->file("scene_out.h5") + R"(, render_frames: 2, fps: 30}
contact:
  stiffness: {body_object: 2.0e5, body_body: 1.0e6, self: 1.0e5}
  friction: 0.5
  sample_spacing: 0
bodies:
  - name: box
    avatar: a.h5
    motion: builtin:idle
    bones: kinematic
    placement: {offset: [0, 0, 0], heading_deg: 10}
    velocity: [0, 0, 0]
objects:
  - name: ball
    shape: {type: sphere, radius: 0.05}
    kind: dynamic
    mass: 0.2
    position: [0.0, 0.3, 0.0]
    velocity: [0, -1, 0]
    angular_velocity: [0, 0, 0]
  - name: press
    shape: {type: box, size: [0.1, 0.02, 0.1]}
    kind: kinematic
    keyframes:
      - {time: 0.0, position: [0, 0.3, 0], orientation: [1, 0, 0, 0]}
      - {time: 1.0, position: [0, 0.2, 0]}
)";
  }

  static std::string f(const std::string& name) { return dir_->file(name); }

  /// Runs one case; returns false (after recording failures) when it does not pass.
  static bool check(const Case& c) {
    SCOPED_TRACE("sflsh -q " + c.args);
    std::string output;
    // Work that started shows in the cache folder: precompute (and bench)
    // would build the template stage there. A case that is wrongly accepted
    // would run on: the timeout only cuts it off (exit 124).
    const std::string cache = f("cache");
    const int code = test::run_command("SFLSH_CACHE_DIR=" + cache + " timeout 60 " + test::sflsh_binary() + " -q " +
                                           c.args,
                                       &output);
    bool ok = true;
    auto expect = [&](bool cond, const std::string& what) {
      if (!cond) {
        ADD_FAILURE() << what << " (exit " << code << "):\n" << output;
        ok = false;
      }
    };
    {
      std::error_code ec;
      expect(!fs::exists(cache) || fs::is_empty(cache, ec), "the template stage was started (" + cache + " not empty)");
      fs::remove_all(cache, ec);
    }
    expect(code >= 1 && code <= 127 && code != 124, "exit code not in 1..127 (124: cut off by the timeout)");
    expect(count_lines(output) == 1, "not exactly one output line");
    for (const auto& frag : c.fragments)
      expect(output.find(frag) != std::string::npos, "the error does not name '" + frag + "'");
    for (const auto& p : c.outputs) {
      // An output folder (no extension) must not be made either.
      if (fs::path(p).extension().empty())
        expect(!fs::exists(p), p + " (output folder) was made");
      else
        expect(!(fs::exists(p) && !fs::is_directory(p)), p + " was written");
      expect(!fs::exists(p + ".partial"), p + ".partial was left");
      std::error_code ec;  // so that the next case starts clean
      fs::remove_all(p, ec);
      fs::remove(p + ".partial", ec);
    }
    return ok;
  }

  static test::TempDir* dir_;
};

test::TempDir* BadInputMatrix::dir_ = nullptr;

TEST_F(BadInputMatrix, EveryEntryPointRejectsBadInputWithOneLine) {
  const std::string a = f("a.h5"), bvh = f("m.bvh"), npz = f("m.npz"), r = f("r.h5"), p = f("p.h5");
  const std::string sim = "simulate --avatar " + a + " --out " + r;
  std::vector<Case> cases;

  // --- file inputs: missing, empty, truncated, a PNG, a directory -------------
  const std::vector<Input> inputs = {
      {"simulate --avatar {} --out " + r, ".h5", a, {r}},
      {sim + " --motion {}", ".bvh", bvh, {r}},
      {sim + " --motion {}", ".npz", npz, {r}},
      {sim + " --motion {}", ".fbx", "", {r}},
      {sim + " --motion {}", ".glb", "", {r}},
      {sim + " --motion " + bvh + " --joint-map {}", ".map", "", {r}},
      {sim + " --material {}", ".yaml", f("material.yaml"), {r}},
      {sim + " --motion builtin:idle --resume {} --seconds 0.1", ".h5", f("state.h5"), {r}},
      {"simulate {} --out " + r, ".yaml", f("scene.yaml"), {r}},
      {"stress --avatar {} --steps 2 --out " + f("st"), ".h5", a, {f("st")}},
      {"stress --avatar " + a + " --steps 2 --motion {} --out " + f("st"), ".bvh", bvh, {f("st")}},
      {"inspect {}", ".h5", a, {}},
      {"motion info {}", ".bvh", bvh, {}},
      {"motion info {}", ".npz", npz, {}},
      {"motion info {}", ".fbx", "", {}},
      {"motion info {}", ".gltf", "", {}},
      {"motion info " + bvh + " --joint-map {}", ".map", "", {}},
      {"motion export {} --out " + f("e.npz"), ".bvh", bvh, {f("e.npz")}},
      {"body info --model {}", ".npz", f("model.npz"), {}},
      {"body info --model {}", ".h5", "", {}},
      {"body export --pose {} --out " + f("b.obj"), ".txt", f("pose.txt"), {f("b.obj")}},
      {"body export --pose {} --out " + f("b.obj"), ".npz", "", {f("b.obj")}},
      {"precompute --model {} --out " + p, ".npz", f("model.npz"), {p}},
      {"precompute --thickness-map {} --out " + p, ".txt", f("thickness.txt"), {p}},
      {"precompute --handles-file {} --out " + p, ".txt", f("handles.txt"), {p}},
      {"precompute --batch {} --out-dir " + f("bd"), ".csv", f("batch.csv"), {f("bd")}},
      {"bench --quick --motion {} --out " + f("bo"), ".bvh", bvh, {f("bo")}},
  };
  int slot = 0;
  for (const Input& in : inputs) {
    const std::string base = "in" + std::to_string(slot++);
    const std::string missing = f(base + "_missing" + in.ext), empty = f(base + "_empty" + in.ext),
                      truncated = f(base + "_truncated" + in.ext), png = f(base + "_png" + in.ext),
                      folder = f(base + "_folder" + in.ext);
    write_text(empty, "");
    fs::copy_file(f("picture.png"), png);
    fs::create_directories(folder);
    for (const std::string& file : {missing, empty, png, folder})
      cases.push_back({replace(in.args, "{}", file), {file}, in.outputs});
    if (!in.valid.empty()) {
      write_text(truncated, truncate(read_text(in.valid)));
      cases.push_back({replace(in.args, "{}", truncated), {truncated}, in.outputs});
    }
  }

  // --- numeric flags: NaN, zero, negative, huge ------------------------------
  const std::vector<Case> flags = {
      {sim + " --dt 0", {"--dt"}, {r}},
      {sim + " --dt -1", {"--dt"}, {r}},
      {sim + " --dt nan", {"--dt"}, {r}},
      {sim + " --dt 1/0", {"--dt"}, {r}},
      {sim + " --seconds nan", {"--seconds"}, {r}},
      {sim + " --seconds -1", {"--seconds"}, {r}},
      {sim + " --seconds 0", {"--seconds"}, {r}},
      {sim + " --seconds inf", {"--seconds"}, {r}},
      {sim + " --output-fps nan", {"--output-fps"}, {r}},
      {sim + " --output-fps 0", {"--output-fps"}, {r}},
      {sim + " --speed nan", {"--speed"}, {r}},
      {sim + " --speed 0", {"--speed"}, {r}},
      {sim + " --start nan", {"--start"}, {r}},
      {sim + " --start -1", {"--start"}, {r}},
      {sim + " --end nan", {"--end"}, {r}},
      {sim + " --damping nan", {"--damping"}, {r}},
      {sim + " --damping -1", {"--damping"}, {r}},
      {sim + " --max-rotation-step nan", {"--max-rotation-step"}, {r}},
      {sim + " --newton-iters 0", {"--newton-iters"}, {r}},
      {sim + " --newton-iters 1000000", {"--newton-iters"}, {r}},
      {sim + " --newton-nonlinearity-tol -0.1", {"--newton-nonlinearity-tol"}, {r}},
      {sim + " --newton-nonlinearity-tol nan", {"--newton-nonlinearity-tol"}, {r}},
      {sim + " --render " + f("x.png") + " --render-frames 0", {"--render-frames"}, {r, f("x.png")}},
      {sim + " --bones sideways", {"--bones"}, {r}},
      {sim + " --units furlong --motion " + bvh, {"--units"}, {r}},
      {"stress --avatar " + a + " --dt 0 --out " + f("st"), {"--dt"}, {f("st")}},
      {"stress --avatar " + a + " --dt -1 --out " + f("st"), {"--dt"}, {f("st")}},
      {"stress --avatar " + a + " --dt nan --out " + f("st"), {"--dt"}, {f("st")}},
      {"stress --avatar " + a + " --steps 0 --out " + f("st"), {"--steps"}, {f("st")}},
      {"bench --quick --handles 0 --out " + f("bo"), {"--handles"}, {f("bo")}},
      {"bench --quick --handles 1000000 --out " + f("bo"), {"--handles"}, {f("bo")}},
      {"bench --quick --handles nan --out " + f("bo"), {"--handles"}, {f("bo")}},
      {"bench --quick --variants-handles 0 --out " + f("bo"), {"--variants-handles"}, {f("bo")}},
      {"bench --quick --seconds nan --out " + f("bo"), {"--seconds"}, {f("bo")}},
      {"bench --quick --seconds -1 --out " + f("bo"), {"--seconds"}, {f("bo")}},
      {"bench --quick --betas nan --out " + f("bo"), {"--betas"}, {f("bo")}},
      {"bench-contact --quick --handles 0 --out " + f("bc"), {"--handles"}, {f("bc")}},
      {"bench-contact --quick --handles 1000000 --out " + f("bc"), {"--handles"}, {f("bc")}},
      {"bench-contact --quick --newton-iters 0 --out " + f("bc"), {"--newton-iters"}, {f("bc")}},
      {"bench-contact --quick --nonlinearity-tolerance -1 --out " + f("bc"), {"--nonlinearity-tolerance"}, {f("bc")}},
      {"bench-contact --quick --nonlinearity-tolerance nan --out " + f("bc"), {"--nonlinearity-tolerance"}, {f("bc")}},
      {"bench-contact --quick --pressure-stiffness nan --out " + f("bc"), {"--pressure-stiffness"}, {f("bc")}},
      {"bench-contact --quick --pressure-stiffness 0 --out " + f("bc"), {"--pressure-stiffness"}, {f("bc")}},
      {"bench-contact --quick --patch-radius -1 --out " + f("bc"), {"--patch-radius"}, {f("bc")}},
      {"bench-contact --quick --betas nan --out " + f("bc"), {"--betas"}, {f("bc")}},
      {"precompute --handles 0 --out " + p, {"--handles"}, {p}},
      {"precompute --handles 1000000 --out " + p, {"--handles"}, {p}},
      {"precompute --handles 8 --handles-min-per-region 9 --out " + p, {"--handles-min-per-region"}, {p}},
      {"precompute --handles-min-per-region -1 --out " + p, {"--handles-min-per-region"}, {p}},
      {"precompute --support-radius 0 --out " + p, {"--support-radius"}, {p}},
      {"precompute --support-radius -0.1 --out " + p, {"--support-radius"}, {p}},
      {"precompute --support-radius nan --out " + p, {"--support-radius"}, {p}},
      {"bench --quick --support-radius nan --out " + f("bo"), {"--support-radius"}, {f("bo")}},
      {"bench --quick --linear-solver qr --out " + f("bo"), {"--linear-solver"}, {f("bo")}},
      {"precompute --betas nan --out " + p, {"--betas"}, {p}},
      {"precompute --cell-size nan --out " + p, {"--cell-size"}, {p}},
      {"precompute --cell-size -1 --out " + p, {"--cell-size"}, {p}},
      {"precompute --facet-size nan --out " + p, {"--facet-size"}, {p}},
      {"precompute --facet-distance nan --out " + p, {"--facet-distance"}, {p}},
      {"precompute --elastic-samples-per-cell 0 --out " + p, {"--elastic-samples-per-cell"}, {p}},
      {"body info --betas nan", {"--betas"}, {}},
      {"body export --translation nan,0,0 --out " + f("b.obj"), {"--translation"}, {f("b.obj")}},
      {"body render --size 0 --out " + f("b.png"), {"--size"}, {f("b.png")}},
      {"body render --pose-preset cartwheel --out " + f("b.png"), {"cartwheel"}, {f("b.png")}},
      {"motion info builtin:jump --fps nan", {"--fps"}, {}},
      {"motion info builtin:jump --fps -1", {"--fps"}, {}},
      {"motion info builtin:jump --speed 0", {"--speed"}, {}},
      {"motion info builtin:jump --speed nan", {"--speed"}, {}},
      {"motion info builtin:jump --start nan", {"--start"}, {}},
      {"motion info builtin:jump --start -1", {"--start"}, {}},
      {"motion info builtin:jump --end nan", {"--end"}, {}},
      {"motion info builtin:jump --seconds nan", {"--seconds"}, {}},
      {"motion info builtin:jump --seconds 0", {"--seconds"}, {}},
      {"motion info builtin:cartwheel", {"cartwheel"}, {}},
      {"stream-listen --rate nan", {"--rate"}, {}},
      {"stream-listen --rate 0", {"--rate"}, {}},
      {"stream-listen --seconds nan", {"--seconds"}, {}},
      {"stream-listen --seconds -1", {"--seconds"}, {}},
      {"stream-listen --max-speed nan", {"--max-speed"}, {}},
      {"stream-listen --spring nan", {"--spring"}, {}},
      {"stream-listen --port -1 --seconds 0.01", {"--port"}, {}},
      {"stream-listen --port 70000 --seconds 0.01", {"--port"}, {}},
  };
  cases.insert(cases.end(), flags.begin(), flags.end());

  // --- unwritable outputs: a folder, a path under a plain file ---------------
  const std::string under = f("plain_file") + "/x";
  const std::vector<Case> outputs = {
      {"simulate --avatar " + a + " --out " + f("in0_folder.h5"), {"--out", "in0_folder.h5"}, {}},
      {sim + " --checkpoint " + under + ".h5", {"--checkpoint", "plain_file"}, {r}},
      {sim + " --export " + under + ".glb", {"--export", "plain_file"}, {r}},
      {sim + " --render " + under + ".png", {"--render", "plain_file"}, {r}},
      {"simulate " + f("scene.yaml") + " --out " + under + ".h5", {"--out", "plain_file"}, {}},
      {"stress --avatar " + a + " --out " + under, {"--out", "plain_file"}, {}},
      {"bench --quick --out " + under, {"--out", "plain_file"}, {}},
      {"bench-contact --quick --out " + under, {"--out", "plain_file"}, {}},
      {"precompute --out " + under + ".h5", {"--out", "plain_file"}, {}},
      {"body export --out " + under + ".obj", {"--out", "plain_file"}, {}},
      {"body render --out " + under + ".png", {"--out", "plain_file"}, {}},
      {"motion export " + bvh + " --out " + under + ".npz", {"--out", "plain_file"}, {}},
      {"stream-listen --seconds 0.01 --record " + under + ".csv", {"--record", "plain_file"}, {}},
  };
  cases.insert(cases.end(), outputs.begin(), outputs.end());

  // --- NaN in each numeric field and wrong shapes, per file format ----------
  const double nan = std::numeric_limits<double>::quiet_NaN();
  int variant = 0;
  auto variant_path = [&](const std::string& ext) { return f("v" + std::to_string(variant++) + ext); };
  // Avatar HDF5: NaN in a dataset, a dataset of the wrong width.
  for (const std::string ds : {"/tet/nodes", "/surface/vertices", "/basis/weights", "/material/parameters",
                               "/cubature/elastic/weights", "/skeleton/joints_rest"}) {
    std::vector<hsize_t> dims;
    std::vector<double> v = read_h5_dataset(a, ds, &dims);
    const std::string nan_file = variant_path(".h5"), shape_file = variant_path(".h5");
    fs::copy_file(a, nan_file);
    fs::copy_file(a, shape_file);
    v[v.size() / 2] = nan;
    replace_h5_dataset(nan_file, ds, v, dims);
    std::vector<hsize_t> bad = dims;
    bad.back() += 1;
    std::vector<double> grown(v.size() / dims.back() * bad.back(), 0.5);
    replace_h5_dataset(shape_file, ds, grown, bad);
    for (const std::string& file : {nan_file, shape_file}) {
      cases.push_back({"inspect " + file, {file, ds}, {}});
      cases.push_back({"simulate --avatar " + file + " --out " + r, {file, ds}, {r}});
    }
  }
  // Body model npz: NaN in each array, a wrong shape.
  {
    const auto model = io::read_npz(f("model.npz"));
    for (const auto& [key, arr] : model) {
      if (arr.size() == 0) continue;
      auto m = model;
      m[key].data[m[key].data.size() / 2] = nan;
      m[key].dtype = "<f8";  // an integer table (kintree_table) then holds a NaN too
      const std::string nan_file = variant_path(".npz");
      io::write_npz(nan_file, m);
      cases.push_back({"body info --model " + nan_file, {nan_file, key}, {}});
      if (arr.shape.size() >= 2 || arr.size() > 1) {
        auto s = model;
        // The last axis, except where it is free (shapedirs: any number of betas).
        (key == "shapedirs" ? s[key].shape.front() : s[key].shape.back()) += 1;
        s[key].data.resize(s[key].size(), 0.0);
        const std::string shape_file = variant_path(".npz");
        io::write_npz(shape_file, s);
        cases.push_back({"body info --model " + shape_file, {shape_file, key}, {}});
      }
    }
  }
  // AMASS npz motion: NaN in a frame of each array, wrong widths.
  {
    const auto motion = io::read_npz(npz);
    for (const auto& [key, arr] : motion) {
      auto m = motion;
      m[key].data[m[key].data.size() - 1] = nan;
      m[key].dtype = "<f8";
      const std::string nan_file = variant_path(".npz");
      io::write_npz(nan_file, m);
      cases.push_back({"motion info " + nan_file, {nan_file, key}, {}});
      cases.push_back({sim + " --motion " + nan_file, {nan_file, key}, {r}});
      if (arr.shape.size() == 2) {
        auto s = motion;
        s[key].shape.back() -= 1;
        s[key].data.resize(s[key].size());
        const std::string shape_file = variant_path(".npz");
        io::write_npz(shape_file, s);
        cases.push_back({"motion info " + shape_file, {shape_file, key}, {}});
      }
    }
  }
  // BVH: NaN in an offset, in the frame time and in a frame; too few values in a frame.
  {
    const std::string text = read_text(bvh);
    const std::vector<std::tuple<std::string, std::string, std::string>> edits = {
        {"OFFSET 0.0 10.0 0.0", "OFFSET 0.0 nan 0.0", "OFFSET"},
        {"Frame Time: 0.04", "Frame Time: nan", "Frame Time"},
        {"Frame Time: 0.04", "Frame Time: 0", "Frame Time"},
        {"Frames: 3", "Frames: -3", "Frames"},
        {"1.5 91 -2 90", "1.5 nan -2 90", "frame 2"},
        {"1.5 91 -2 90", "1.5 inf -2 90", "frame 2"},
        {"3 92 -4 0 0 0 0 0 0 0 0 0 0 0 0", "3 92 -4 0 0 0 0 0 0 0 0 0 0 0", "frame 3"},
    };
    for (const auto& [from, to, field] : edits) {
      const std::string file = variant_path(".bvh");
      ASSERT_NE(text.find(from), std::string::npos) << from;
      write_text(file, replace(text, from, to));
      cases.push_back({"motion info " + file, {file, field}, {}});
      cases.push_back({sim + " --motion " + file, {file, field}, {r}});
    }
  }
  // Text tables: NaN, wrong counts, unknown names.
  const std::vector<std::tuple<std::string, std::string, std::string, std::string>> tables = {
      // command with {}, file content, extension, what the error must name
      {"precompute --thickness-map {} --out " + p, "torso nan\n", ".txt", "torso"},
      {"precompute --thickness-map {} --out " + p, "tail 1.1\n", ".txt", "tail"},
      {"precompute --handles-file {} --out " + p, "0 1 nan\n", ".txt", "nan"},
      {"precompute --handles-file {} --out " + p, "0 1\n", ".txt", ":1"},
      {"precompute --batch {} --out-dir " + f("bd"), "b0,b1\nnan,0\n", ".csv", "nan"},
      {"precompute --batch {} --out-dir " + f("bd"), "b0,b1\n0.5\n", ".csv", "line 2"},
      {"body export --out " + f("b.obj") + " --pose {}", "0 0 nan\n", ".txt", "nan"},
      {"body export --out " + f("b.obj") + " --pose {}", "0 0 0\n", ".txt", "72"},
      {sim + " --motion " + bvh + " --joint-map {}", "Hips hip_of_a_horse\n", ".map", "hip_of_a_horse"},
      {sim + " --motion " + bvh + " --joint-map {}", "Tail pelvis\n", ".map", "Tail"},
      {"motion info " + bvh + " --joint-map {}", "Hips hip_of_a_horse\n", ".map", "hip_of_a_horse"},
      {sim + " --material {}", "regions: {tail: {young: 1000}}\n", ".yaml", "tail"},
      {sim + " --material {}", "all: {shininess: 3}\n", ".yaml", "shininess"},
  };
  for (const auto& [args, content, ext, field] : tables) {
    const std::string file = variant_path(ext);
    write_text(file, content);
    cases.push_back({replace(args, "{}", file), {file, field}, {r, p, f("bd"), f("b.obj")}});
  }
  for (const std::string key : {"young", "young_along", "young_through", "young_around", "poisson", "fung_c", "density"}) {
    const std::string file = variant_path(".yaml");
    write_text(file, "all: {" + key + ": .nan}\n");
    cases.push_back({sim + " --material " + file, {file, key}, {r}});
  }
  // The scene file: NaN in every numeric field, one at a time; unknown names.
  {
    std::vector<std::pair<std::string, YAML::Node>> scalars;
    const YAML::Node probe = YAML::Load(scene_text());
    numeric_scalars(probe, "", scalars);
    for (size_t i = 0; i < scalars.size(); ++i) {
      YAML::Node root = YAML::Load(scene_text());
      std::vector<std::pair<std::string, YAML::Node>> s;
      numeric_scalars(root, "", s);
      s[i].second = ".nan";
      YAML::Emitter e;
      e << root;
      const std::string file = variant_path(".yaml");
      write_text(file, e.c_str());
      cases.push_back({"simulate " + file, {file, last_key(s[i].first)}, {f("scene_out.h5")}});
    }
    for (const auto& [from, to, field] : std::vector<std::tuple<std::string, std::string, std::string>>{
             {"motion: builtin:idle", "motion: builtin:cartwheel", "cartwheel"},
             {"stiffness: {body_object", "pairs: [[box, nobody]]\n  stiffness: {body_object", "nobody"},
             {"size: [0.1, 0.02, 0.1]", "size: [0.1, 0.02]", "size"},
             {"orientation: [1, 0, 0, 0]", "orientation: [0, 0, 0, 0]", "orientation"},
             {"kind: dynamic", "kind: floating", "kind"}}) {
      const std::string file = variant_path(".yaml");
      write_text(file, replace(scene_text(), from, to));
      cases.push_back({"simulate " + file, {file, field}, {f("scene_out.h5")}});
    }
  }

  // One at a time: cases share output names (r.h5, p.h5), which a wrongly
  // accepted case would write. Every case must fail before the work starts
  // (check(): nothing in the template-stage cache).
  int passed = 0;
  for (const Case& c : cases) passed += check(c);
  std::printf("bad-input matrix: %d of %zu cases pass\n", passed, cases.size());
  RecordProperty("cases", int(cases.size()));
  RecordProperty("passed", passed);
  EXPECT_EQ(passed, int(cases.size()));
}

}  // namespace
