// Replays every fuzz target (fuzz/fuzz_targets.hpp) over
//  - the committed findings of scripts/fuzz.sh (tests/fuzz_regressions/<target>/)
//    and, when SFLSH_FUZZ_REPLAY_DIR points at them, new ones (each must parse
//    or throw sflsh::Error), and
//  - valid files made here (and the project's own test files), each also cut
//    short at several lengths and with bytes overwritten at spread positions:
//    a small, deterministic mutation pass that runs on every build.
// With SFLSH_FUZZ_SEED_DIR set, the valid files are also written to
// $SFLSH_FUZZ_SEED_DIR/<target>/ (scripts/fuzz.sh seeds its corpora so).
#include <gtest/gtest.h>
#include <hdf5.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "fuzz_targets.hpp"
#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/io/npz.hpp"
#include "sflsh/geometry/primitive_meshes.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/io/mesh_export.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sflsh/teleop/pose_file.hpp"
#include "sflsh/teleop/stream_message.hpp"
#include "sim/synthetic_avatar.hpp"
#include "test_support.hpp"

using namespace sflsh;
namespace fs = std::filesystem;

namespace {

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

const fuzz::Target& target(const std::string& name) {
  for (const auto& t : fuzz::all_targets())
    if (t.name == name) return t;
  throw std::runtime_error("no fuzz target " + name);
}

void run(const fuzz::Target& t, const std::string& bytes) {
  t.run(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
}

// The valid input, 12 truncations and 64 single-byte overwrites (positions
// spread over the file, values cycling through 0x00, 0xff, 0x7f, 0x80, ...).
void run_with_mutations(const fuzz::Target& t, const std::string& bytes) {
  run(t, bytes);
  for (int k = 0; k < 12; ++k) run(t, bytes.substr(0, bytes.size() * k / 12));
  const unsigned char values[] = {0x00, 0xff, 0x7f, 0x80, 0x01, 0x40};
  for (int k = 0; k < 64 && !bytes.empty(); ++k) {
    std::string m = bytes;
    m[(bytes.size() * size_t(k)) / 64 + size_t(k) % 7 < bytes.size() ? (bytes.size() * size_t(k)) / 64 + size_t(k) % 7
                                                                       : bytes.size() - 1] = char(values[k % 6]);
    run(t, m);
  }
}

// Writes `bytes` as a seed for scripts/fuzz.sh when SFLSH_FUZZ_SEED_DIR is set.
void offer_seed(const std::string& target_name, const std::string& file_name, const std::string& bytes) {
  const char* dir = std::getenv("SFLSH_FUZZ_SEED_DIR");
  if (!dir || !*dir) return;
  const fs::path d = fs::path(dir) / target_name;
  fs::create_directories(d);
  std::ofstream(d / file_name, std::ios::binary) << bytes;
}

void check_valid_file(const std::string& target_name, const std::string& file_name, const std::string& bytes) {
  SCOPED_TRACE(target_name + " " + file_name);
  offer_seed(target_name, file_name, bytes);
  run_with_mutations(target(target_name), bytes);
}

SimulationResult tiny_result() {
  SimulationResult r;
  r.avatar = "a.h5";
  r.motion = "builtin:jump";
  r.dt = 1.0 / 60;
  r.faces.resize(1, 3);
  r.faces << 0, 1, 2;
  r.surface_rest = Points::Random(3, 3);
  for (int f = 0; f < 3; ++f) {
    r.frame_time.push_back(f / 30.0);
    r.frame_step_ms.push_back(1.0);
    r.frame_positions.push_back(Points::Constant(3, 3, 0.1 * f));
    r.frame_displacement.push_back(Points::Constant(3, 3, 0.001 * f));
    r.frame_joints.push_back(Points::Constant(24, 3, 0.2 * f));
    r.frame_reduced.push_back(VecX::Constant(6, 0.01 * f));
    r.frame_target_pelvis.push_back(Vec3(0, 0.9, 0.1 * f));
  }
  r.num_frames = 3;
  for (int s = 0; s < 4; ++s) {
    r.step_time.push_back((s + 1) / 60.0);
    r.step_energy.push_back(s);
    r.step_grad_norm.push_back(0.5 * s);
    r.step_decrement.push_back(0.1 * s);
    r.step_outcome.push_back(s % 3);
    r.step_ms.push_back(1.5);
  }
  return r;
}

}  // namespace

TEST(FuzzReplay, RegressionInputsParseOrThrowTheProjectError) {
  // The committed findings (tests/fuzz_regressions/<target>/, every run) and,
  // when SFLSH_FUZZ_REPLAY_DIR points at them, new ones of scripts/fuzz.sh
  // (build-fuzz/crashes/<target>/).
  std::vector<fs::path> roots = {fs::path(test::source_dir()) / "tests" / "fuzz_regressions"};
  if (const char* dir_env = std::getenv("SFLSH_FUZZ_REPLAY_DIR")) roots.emplace_back(dir_env);
  int replayed = 0, committed = 0;
  for (const fs::path& root : roots)
    for (const auto& t : fuzz::all_targets()) {
      const fs::path dir = root / t.name;
      if (!fs::is_directory(dir)) continue;
      for (const auto& e : fs::directory_iterator(dir)) {
        if (!e.is_regular_file() || e.path().filename() == "README.md") continue;
        SCOPED_TRACE(e.path().string());
        run(t, read_bytes(e.path()));
        ++replayed;
        if (root == roots[0]) ++committed;
      }
    }
  std::printf("replayed %d regression inputs (%d committed)\n", replayed, committed);
  EXPECT_GT(committed, 0) << "tests/fuzz_regressions/ is missing";
}

TEST(FuzzReplay, ValidAndMutatedProjectFiles) {
  test::TempDir tmp;
  // BVH: the committed test motions.
  for (const auto& e : fs::directory_iterator(fs::path(test::source_dir()) / "tests" / "data" / "motion"))
    if (e.path().extension() == ".bvh") check_valid_file("bvh", e.path().filename().string(), read_bytes(e.path()));
  // npz: the generated tiny SMPL model (deflated arrays) and an uncompressed archive with an int array.
  const std::string tiny_npz = test::generated_fixture("tiny_smpl.npz");
  check_valid_file("npz", "tiny_smpl.npz", read_bytes(tiny_npz));
  io::NpyArray a;
  a.shape = {2, 3};
  a.dtype = "<i4";
  a.data = {1, 2, 3, 4, 5, 6};
  io::write_npz(tmp.file("small.npz"), {{"a", a}}, false);
  check_valid_file("npz", "small.npz", read_bytes(tmp.file("small.npz")));
  // Body model, avatar and result HDF5 files.
  write_body_model_hdf5(read_body_model_npz(tiny_npz), tmp.file("body.h5"));
  check_valid_file("body_model_h5", "tiny_body.h5", read_bytes(tmp.file("body.h5")));
  test::SyntheticAvatarOptions o;
  o.nx = 1, o.ny = 2, o.nz = 1, o.handles = 3;
  write_avatar(test::make_synthetic_avatar(o), tmp.file("avatar.h5"));
  check_valid_file("avatar_h5", "synthetic_avatar.h5", read_bytes(tmp.file("avatar.h5")));
  write_simulation_result(tiny_result(), tmp.file("result.h5"));
  check_valid_file("result_h5", "tiny_result.h5", read_bytes(tmp.file("result.h5")));
  // Material files.
  check_valid_file("material", "all_and_regions.yaml",
                   "all:\n  young: 2.0e4\n  poisson: 0.45\nregions:\n  belly: {young_along: 1.0e4, young_through: 5.0e3, "
                   "young_around: 8.0e3, fung_c: 1.0e3}\n  thigh: {young: 3.0e4, density: 1050}\n");
  check_valid_file("material", "flow.yaml", "{regions: {chest: {poisson: 0.3}, upper_arm: {density: 990}}}\n");
  // Scenes: the shipped ones (they name avatar.h5 and pinch.csv, present in the target's folder).
  const fs::path scenes = fs::path(test::source_dir()) / "apps" / "scenes";
  for (const fs::path dir : {scenes, scenes / "figures"})
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".yaml") check_valid_file("scene_yaml", e.path().filename().string(), read_bytes(e.path()));
  // Meshes: a box as OBJ and PLY (io::write_mesh) and as ASCII STL; byte 0 picks the format.
  const geometry::PrimitiveMesh box = geometry::box_mesh(Vec3(0.05, 0.02, 0.03), 2);
  io::write_mesh(tmp.file("box.obj"), box.vertices, box.faces);
  io::write_mesh(tmp.file("box.ply"), box.vertices, box.faces);
  check_valid_file("mesh", "box.obj", std::string(1, '\0') + read_bytes(tmp.file("box.obj")));
  check_valid_file("mesh", "box.ply", std::string(1, '\2') + read_bytes(tmp.file("box.ply")));
  std::ostringstream stl;
  stl << "solid box\n";
  for (Eigen::Index f = 0; f < box.faces.rows(); ++f) {
    stl << " facet normal 0 0 0\n  outer loop\n";
    for (int k = 0; k < 3; ++k) stl << "   vertex " << box.vertices.row(box.faces(f, k)) << "\n";
    stl << "  endloop\n endfacet\n";
  }
  stl << "endsolid box\n";
  check_valid_file("mesh", "box.stl", std::string(1, '\1') + stl.str());
  // Pose stream: three poses and a feedback message, each after its length byte.
  std::string datagrams;
  for (int k = 0; k < 3; ++k) {
    teleop::PoseMessage m;
    m.sequence = std::uint64_t(k + 1);
    m.sample.time = 0.01 * k;
    m.sample.position = Vec3(0.1, 1.0 + 0.001 * k, 0.1);
    m.sample.closure = 0.5;
    const auto bytes = teleop::encode_pose(m);
    datagrams += char(bytes.size());
    datagrams.append(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  }
  const auto feedback = teleop::encode_feedback(teleop::FeedbackMessage{3, 0.02, Vec3(1, 2, 3), Vec3(0, 0, 1)});
  datagrams += char(feedback.size());
  datagrams.append(reinterpret_cast<const char*>(feedback.data()), feedback.size());
  check_valid_file("stream", "three_poses_and_feedback.bin", datagrams);
  // Pose files: the shipped CSV and the same samples as JSON lines.
  const fs::path pinch = scenes / "figures" / "pinch.csv";
  check_valid_file("pose_file", "pinch.csv", read_bytes(pinch));
  std::string jsonl = "# pinch.csv as JSON lines\n";
  for (const auto& sample : teleop::read_pose_file(pinch.string()))
    jsonl += teleop::format_pose_row(sample, teleop::PoseFileFormat::kJsonLines) + "\n";
  check_valid_file("pose_file", "pinch.jsonl", jsonl);
  // Viewer control messages: one of each type, as the page sends them.
  const std::pair<const char*, const char*> controls[] = {
      {"tool.json", R"({"type":"tool","seq":42,"t":1.5,"tool":0,"pos":[0.1,-0.2,0.3],"quat":[0,1,0,0],"closure":0.25})"},
      {"pause.json", R"({"type":"pause","seq":1,"paused":true})"},
      {"step.json", R"({"type":"step","seq":2})"},
      {"reset.json", R"({"type":"reset","seq":3})"},
      {"stiffness.json", R"({"type":"stiffness","seq":4,"scale":2.5})"},
      {"seek.json", R"({"type":"seek","seq":5,"time":0.75})"},
      {"speed.json", R"({"type":"speed","seq":6,"speed":0.5})"}};
  for (const auto& [name, text] : controls) check_valid_file("control_message", name, text);
}

TEST(FuzzReplay, AHugeDeclaredDatasetInATinyFileIsRejectedBeforeAllocating) {
  // A file of a few kB whose chunked dataset declares 2^36 x 3 doubles (1.6 TB)
  // that were never written (HDF5 then stores no chunks, only the extent).
  test::TempDir tmp;
  const std::string path = tmp.file("huge.h5");
  {
    const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    const hsize_t dims[2] = {hsize_t(1) << 36, 3}, chunk[2] = {1024, 3};
    const hid_t space = H5Screate_simple(2, dims, nullptr);
    const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, 2, chunk);
    const hid_t ds = H5Dcreate2(file, "/nodes", H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    ASSERT_GE(ds, 0);
    H5Dclose(ds);
    H5Pclose(dcpl);
    H5Sclose(space);
    H5Fclose(file);
  }
  ASSERT_LT(fs::file_size(path), 100000u);
  const io::Hdf5File f(path, io::Hdf5File::Mode::Read);
  EXPECT_EQ(f.shape("/nodes"), (std::vector<std::int64_t>{std::int64_t(1) << 36, 3}));
  test::expect_error([&] { f.read_matrix("/nodes", -1, 3); }, {"huge.h5", "/nodes", "declares"});
  // The same bytes as an in-memory image.
  const std::string bytes = read_bytes(path);
  const io::Hdf5MemoryImage image("huge-in-memory.h5", bytes.data(), bytes.size());
  const io::Hdf5File g(image.name(), io::Hdf5File::Mode::Read);
  test::expect_error([&] { g.read_matrix("/nodes", -1, 3); }, {"huge-in-memory.h5", "/nodes", "declares"});
}

// libhdf5 copies a dataset's values for the bytes its shape needs, whatever the file says is
// stored (heap over-reads found by scripts/fuzz.sh): Hdf5File checks first. A chunk written raw
// and unfiltered, 40 bytes where the chunk needs 4 × 3 doubles = 96, is one error naming both
// sizes; so are the fuzzers' inputs (a compact dataset holding 0 bytes, a gzip-declared chunk
// stored unfiltered, chunks larger than the dataset), which crashed libhdf5 in-process before.
TEST(FuzzReplay, StoredBytesShorterThanTheShapeNeedsAreAnError) {
  test::TempDir tmp;
  const std::string path = tmp.file("short_chunk.h5");
  {
    const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    const hsize_t dims[2] = {4, 3};
    const hid_t space = H5Screate_simple(2, dims, nullptr);
    const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, 2, dims);
    const hid_t ds = H5Dcreate2(file, "/short", H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    ASSERT_GE(ds, 0);
    const double five[5] = {1, 2, 3, 4, 5};
    const hsize_t origin[2] = {0, 0};
    ASSERT_GE(H5Dwrite_chunk(ds, H5P_DEFAULT, 0, origin, sizeof five, five), 0);
    H5Dclose(ds);
    H5Pclose(dcpl);
    H5Sclose(space);
    H5Fclose(file);
  }
  const io::Hdf5File f(path, io::Hdf5File::Mode::Read);
  test::expect_error([&] { f.read_matrix("/short", 4, 3); }, {"short_chunk.h5", "/short", "chunk 0 holds 40 bytes, a chunk needs 96"});
  const fs::path reg = fs::path(test::source_dir()) / "tests" / "fuzz_regressions";
  test::expect_error([&] { read_avatar((reg / "avatar_h5" / "libhdf5-null-memcpy-contiguous-read.h5").string()); },
                     {"/tet/node_weights holds 0 bytes of data"});
  test::expect_error(
      [&] { read_body_model_hdf5((reg / "body_model_h5" / "libhdf5-unfiltered-chunk-shorter-than-the-chunk.h5").string()); },
      {"/posedirs chunk 0 holds 25430 bytes, a chunk needs 99360"});
  test::expect_error(
      [&] { read_body_model_hdf5((reg / "body_model_h5" / "libhdf5-chunk-larger-than-the-dataset-segv.h5").string()); },
      {"/posedirs declares chunks of 4099 along dimension 1, larger than its 3"});
}
