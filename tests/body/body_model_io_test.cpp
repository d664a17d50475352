// Body model files: HDF5 round trip, SMPL .npz (float32, deflated), the
// .pkl converter in data_tools/, content hashes, and every kind of broken
// input (truncated, missing key, wrong shape, NaN, bad faces) failing with a
// message that names the file, the key and the expected shape.
#include "sflsh/body/body_model_io.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/io/npz.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

using test::TempDir;
using NpzArrays = std::map<std::string, io::NpyArray>;

using test::generated_fixture;

using test::expect_error;

void expect_same_model(const BodyModel& a, const BodyModel& b) {
  EXPECT_EQ(a.v_template, b.v_template);
  EXPECT_EQ(a.faces, b.faces);
  ASSERT_EQ(a.num_betas(), b.num_betas());
  for (int i = 0; i < a.num_betas(); ++i) EXPECT_EQ(a.shapedirs[i], b.shapedirs[i]) << i;
  EXPECT_EQ(a.posedirs, b.posedirs);
  EXPECT_EQ(MatXr(a.J_regressor), MatXr(b.J_regressor));
  EXPECT_EQ(a.weights, b.weights);
  EXPECT_EQ(a.parents, b.parents);
  EXPECT_EQ(a.joint_names, b.joint_names);
  EXPECT_EQ(body_model_hash(a), body_model_hash(b));
}

// The tiny fixture's arrays as an editable .npz map (SMPL key names and shapes).
NpzArrays tiny_arrays() { return io::read_npz(generated_fixture("tiny_smpl.npz")); }

TEST(BodyModelIo, ReadsSmplNpzFloat32Deflated) {
  const BodyModel m = read_body_model_npz(generated_fixture("tiny_smpl.npz"));
  EXPECT_EQ(m.num_vertices(), 20);
  EXPECT_EQ(m.faces.rows(), 30);
  EXPECT_EQ(m.num_betas(), 4);
  EXPECT_EQ(m.num_joints(), 24);
  EXPECT_EQ(m.parents[0], -1);  // the file stores 4294967295
  EXPECT_EQ(m.parents[23], 21);
  EXPECT_EQ(m.joint_names[16], "left_shoulder");
  EXPECT_EQ(m.source, generated_fixture("tiny_smpl.npz"));
  // Spot values against the raw arrays: shapedirs is Fortran-ordered in the
  // file, posedirs (V, 3, 207) maps to row 3v + c.
  const NpzArrays raw = tiny_arrays();
  const auto& sd = raw.at("shapedirs").data;
  const auto& pd = raw.at("posedirs").data;
  EXPECT_EQ(m.shapedirs[3](7, 2), sd[(7 * 3 + 2) * 4 + 3]);
  EXPECT_EQ(m.posedirs(3 * 11 + 1, 200), pd[(11 * 3 + 1) * 207 + 200]);
  EXPECT_EQ(MatXr(m.J_regressor)(5, 9), raw.at("J_regressor").data[5 * 20 + 9]);
  EXPECT_GT(m.J_regressor.nonZeros(), 24);
  EXPECT_LT(m.J_regressor.nonZeros(), 24 * 20 / 2);  // stored sparse
}

TEST(BodyModelIo, Hdf5RoundTripKeepsEverything) {
  TempDir dir;
  BodyModel m = read_body_model_npz(generated_fixture("tiny_smpl.npz"));
  m.shape_meanings = {"height", "girth", "muscle", "chest"};
  m.joint_names[0] = "hips";  // non-default names survive
  const std::string path = dir.file("tiny.h5");
  write_body_model_hdf5(m, path);
  EXPECT_FALSE(std::filesystem::exists(path + ".partial"));
  const BodyModel back = read_body_model_hdf5(path);
  expect_same_model(m, back);
  EXPECT_EQ(back.shape_meanings, m.shape_meanings);
  EXPECT_EQ(back.source, path);
  io::Hdf5File f(path, io::Hdf5File::Mode::Read);
  EXPECT_EQ(f.read_string("/meta/units"), "metres");
  EXPECT_EQ(f.read_scalar("/meta/format_version"), kBodyModelFormatVersion);
  EXPECT_EQ(f.shape("/shapedirs"), (std::vector<std::int64_t>{20, 3, 4}));
  EXPECT_EQ(load_body_model(path).v_template, m.v_template);

  // All-zero pose directions are read back as "none" (empty), same hash.
  BodyModel z = m;
  z.posedirs.setZero();
  write_body_model_hdf5(z, dir.file("z.h5"));
  const BodyModel zb = read_body_model_hdf5(dir.file("z.h5"));
  EXPECT_EQ(zb.posedirs.size(), 0);
  EXPECT_FALSE(zb.has_pose_blend_shapes());
  EXPECT_EQ(body_model_hash(zb), body_model_hash(z));
  EXPECT_NE(body_model_hash(zb), body_model_hash(m));
  write_body_model_hdf5(zb, dir.file("z2.h5"));  // empty is written as zeros (V, 3, 207)
  EXPECT_EQ(io::Hdf5File(dir.file("z2.h5"), io::Hdf5File::Mode::Read).shape("/posedirs"),
            (std::vector<std::int64_t>{20, 3, 207}));

  // A model without shape directions round-trips too.
  m.shapedirs.clear();
  m.shape_meanings.clear();
  write_body_model_hdf5(m, dir.file("b0.h5"));
  EXPECT_EQ(read_body_model_hdf5(dir.file("b0.h5")).num_betas(), 0);
}

TEST(BodyModelIo, Hdf5DenseRegressorIsAccepted) {
  TempDir dir;
  const BodyModel m = read_body_model_npz(generated_fixture("tiny_smpl.npz"));
  const NpzArrays raw = tiny_arrays();
  const std::string path = dir.file("dense.h5");
  {
    io::Hdf5File f(path, io::Hdf5File::Mode::Write);
    for (const char* key : {"v_template", "f", "shapedirs", "posedirs", "J_regressor", "weights"})
      f.write_nd(std::string("/") + key, raw.at(key).data.data(), raw.at(key).shape);
    std::vector<double> kt = raw.at("kintree_table").data;
    kt[0] = -1;
    f.write_nd("/kintree_table", kt.data(), {2, 24});
    f.commit();
  }
  expect_same_model(m, read_body_model_hdf5(path));
}

TEST(BodyModelIo, HashFollowsContentNotSource) {
  const BodyModel a = read_body_model_npz(generated_fixture("tiny_smpl.npz"));
  BodyModel b = a;
  b.source = "elsewhere.h5";
  b.shape_meanings = {"a", "b", "c", "d"};
  const std::string h = body_model_hash(a);
  EXPECT_EQ(h.size(), 16u);
  EXPECT_EQ(h, body_model_hash(b));
  b.posedirs(17, 100) += 1e-9;
  EXPECT_NE(h, body_model_hash(b));
  BodyModel c = a;
  c.faces(0, 0) = c.faces(0, 1);
  EXPECT_NE(h, body_model_hash(c));
  BodyModel d = a;
  d.J_regressor.coeffRef(0, 0) += 0.5;
  EXPECT_NE(h, body_model_hash(d));
}

TEST(BodyModelIo, NpzWrittenByUsFloat32Compressed) {
  TempDir dir;
  NpzArrays raw = tiny_arrays();
  for (auto& [k, a] : raw) a.dtype = k == "f" || k == "kintree_table" ? "<i8" : "<f4";
  io::write_npz(dir.file("ours.npz"), raw, true);
  expect_same_model(read_body_model_npz(generated_fixture("tiny_smpl.npz")), read_body_model_npz(dir.file("ours.npz")));
}

// Each broken .npz must name the file, the key and what was expected.
TEST(BodyModelIo, BrokenNpzInputsFailWithClearMessages) {
  TempDir dir;
  const std::string p = dir.file("bad.npz");
  auto check = [&](auto edit, std::initializer_list<std::string> fragments) {
    NpzArrays raw = tiny_arrays();
    edit(raw);
    io::write_npz(p, raw, true);
    expect_error([&] { read_body_model_npz(p); }, fragments);
  };
  check([](NpzArrays& a) { a.erase("weights"); }, {"bad.npz", "'weights'", "missing", "(20, 24)", "v_template"});
  check([](NpzArrays& a) { a.erase("v_template"); }, {"bad.npz", "'v_template'", "(any, 3)"});
  check([](NpzArrays& a) { a["posedirs"].shape = {20, 3, 207 * 3}; a["posedirs"].data.resize(20 * 3 * 621); },
        {"bad.npz", "'posedirs'", "(20, 3, 621)", "expected (20, 3, 207)"});
  check([](NpzArrays& a) { a["J_regressor"].shape = {20, 24}; }, {"'J_regressor'", "expected (24, 20)"});
  check([](NpzArrays& a) { a["kintree_table"].shape = {24, 2}; }, {"'kintree_table'", "expected (2, 24)"});
  check([](NpzArrays& a) { a["shapedirs"].shape = {20, 12}; }, {"'shapedirs'", "expected (20, 3, any)"});
  check([](NpzArrays& a) { a["v_template"].data[7] = std::nan(""); }, {"bad.npz", "'v_template'", "non-finite", "index 7"});
  check([](NpzArrays& a) { a["f"].data[4] = 2.5; }, {"bad.npz", "'f'", "non-integer"});
  check([](NpzArrays& a) { a["f"].data[5] = 20; }, {"bad.npz", "'f'", "index 20", "face 1", "[0, 20)"});
  check([](NpzArrays& a) { a["kintree_table"].data[6] = 6; }, {"'kintree_table'", "joint 6", "[0, 6)"});
  check([](NpzArrays& a) { a["weights"].data[0] += 0.5; }, {"bad.npz", "weights row 0"});

  // Truncated archive, not-an-archive, missing file.
  const std::string good = generated_fixture("tiny_smpl.npz");
  const auto size = std::filesystem::file_size(good);
  std::filesystem::copy_file(good, dir.file("cut.npz"));
  std::filesystem::resize_file(dir.file("cut.npz"), size * 2 / 3);
  expect_error([&] { read_body_model_npz(dir.file("cut.npz")); }, {"cut.npz", "truncated"});
  std::ofstream(dir.file("text.npz")) << "hello";
  expect_error([&] { read_body_model_npz(dir.file("text.npz")); }, {"text.npz"});
  expect_error([&] { load_body_model(dir.file("nope.npz")); }, {"nope.npz", "not found"});
}

// The same failures through the HDF5 reader.
TEST(BodyModelIo, BrokenHdf5InputsFailWithClearMessages) {
  TempDir dir;
  const NpzArrays raw = tiny_arrays();
  const std::string p = dir.file("bad.h5");
  auto check = [&](const std::string& skip, auto edit, std::initializer_list<std::string> fragments) {
    {
      io::Hdf5File f(p, io::Hdf5File::Mode::Write);
      for (const auto& [key, arr] : raw) {
        if (key == skip || key == "gender") continue;
        io::NpyArray a = arr;
        if (key == "kintree_table") a.data[0] = -1;
        edit(key, a);
        f.write_nd("/" + key, a.data.data(), a.shape);
      }
      f.commit();
    }
    expect_error([&] { read_body_model_hdf5(p); }, fragments);
  };
  auto none = [](const std::string&, io::NpyArray&) {};
  check("posedirs", none, {"bad.h5", "/posedirs", "missing", "(20, 3, 207)"});
  check("", [](const std::string& k, io::NpyArray& a) { if (k == "weights") { a.shape = {24, 20}; } },
        {"bad.h5", "/weights", "(24, 20)", "expected (20, 24)"});
  check("", [](const std::string& k, io::NpyArray& a) { if (k == "shapedirs") a.data[3] = NAN; },
        {"bad.h5", "/shapedirs", "non-finite"});
  check("", [](const std::string& k, io::NpyArray& a) { if (k == "f") a.data[0] = 0.5; }, {"bad.h5", "'f'", "non-integer"});
  check("", [](const std::string& k, io::NpyArray& a) { if (k == "f") a.data[2] = -3; }, {"bad.h5", "'f'", "-3"});

  // Truncated HDF5 file.
  const BodyModel m = read_body_model_npz(generated_fixture("tiny_smpl.npz"));
  write_body_model_hdf5(m, dir.file("ok.h5"));
  std::filesystem::resize_file(dir.file("ok.h5"), std::filesystem::file_size(dir.file("ok.h5")) / 2);
  expect_error([&] { read_body_model_hdf5(dir.file("ok.h5")); }, {"ok.h5"});
  // Writing refuses an invalid model and leaves no file behind.
  BodyModel bad = m;
  bad.faces(0, 0) = 99;
  expect_error([&] { write_body_model_hdf5(bad, dir.file("w.h5")); }, {"w.h5", "f[0, 0]"});
  EXPECT_FALSE(std::filesystem::exists(dir.file("w.h5")));
}

TEST(BodyModelIo, LoadBodyModelPicksReaderByExtension) {
  TempDir dir;
  expect_error([&] { load_body_model(dir.file("model.pkl")); }, {"model.pkl", "smpl_pkl_to_h5.py"});
  expect_error([&] { load_body_model(dir.file("model.obj")); }, {"model.obj", "procedural", ".npz"});
  std::filesystem::copy_file(generated_fixture("tiny_smpl.npz"), dir.file("UPPER.NPZ"));
  EXPECT_EQ(load_body_model(dir.file("UPPER.NPZ")).num_vertices(), 20);
}

// The built-in body goes through the canonical file format unchanged (its
// all-zero pose directions come back as "none", with the same content hash).
TEST(BodyModelIo, ProceduralBodyRoundTripsThroughHdf5) {
  TempDir dir;
  const BodyModel m = load_body_model("procedural");
  ASSERT_NO_THROW(m.validate());
  write_body_model_hdf5(m, dir.file("procedural.h5"));
  const BodyModel back = load_body_model(dir.file("procedural.h5"));
  EXPECT_EQ(back.v_template, m.v_template);
  EXPECT_EQ(back.faces, m.faces);
  EXPECT_EQ(back.shape_meanings, m.shape_meanings);
  EXPECT_EQ(back.has_pose_blend_shapes(), m.has_pose_blend_shapes());
  EXPECT_EQ(body_model_hash(back), body_model_hash(m));
  const BodyPose pose = pose_preset("walk");
  const VecX betas = VecX::LinSpaced(m.num_betas(), -1.0, 1.0);
  EXPECT_LT((pose_body(back, betas, pose).v_posed - pose_body(m, betas, pose).v_posed).cwiseAbs().maxCoeff(), 1e-12);
}

// data_tools/smpl_pkl_to_h5.py on an SMPL-like pickle (chumpy-style objects,
// csc regressor; chumpy not installed) gives the same model as the .npz.
TEST(BodyModelIo, PickleConverterMatchesNpzReader) {
  const std::string py = "/usr/bin/python3";
  if (test::run_command(py + " -c 'import numpy, scipy, h5py'") != 0)
    GTEST_SKIP() << py << " with numpy, scipy and h5py is not available";
  TempDir dir;
  const std::string script = test::source_dir() + "/data_tools/smpl_pkl_to_h5.py";
  const std::string pkl = dir.file("tiny.pkl"), h5 = dir.file("tiny.h5");
  std::string out;
  ASSERT_EQ(test::run_command(py + " " + script + " --make-test-pkl " + generated_fixture("tiny_smpl.npz") + " " + pkl, &out), 0)
      << out;
  ASSERT_EQ(test::run_command(py + " " + script + " " + pkl + " " + h5, &out), 0) << out;
  expect_same_model(read_body_model_npz(generated_fixture("tiny_smpl.npz")), read_body_model_hdf5(h5));
  // A broken pickle is reported, not crashed on.
  std::ofstream(dir.file("junk.pkl")) << "junk";
  EXPECT_NE(test::run_command(py + " " + script + " " + dir.file("junk.pkl") + " " + dir.file("j.h5"), &out), 0);
  EXPECT_NE(out.find("junk.pkl"), std::string::npos) << out;
}

}  // namespace
}  // namespace sflsh
