// End to end through the sflsh executable on a coarse built-in body:
// precompute -> inspect -> simulate (+ exports), batch precompute, bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/precompute/batch_precompute.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sflsh/scene/simulation_run.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

// Coarse settings on the built-in body: few handles, large tets (~10k), seconds.
const char* kCoarse = " --handles 8 --cell-size 0.08 --facet-size 0.06 --facet-distance 0.004";

class PipelineCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir();
    const std::string cmd = test::sflsh_binary() + " -q precompute" + kCoarse + " --cache-dir " + dir_->file("cache") +
                            " --out " + dir_->file("avatar.h5");
    status_ = test::run_command(cmd, &output_);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string run(const std::string& args, int* code) {
    std::string out;
    *code = test::run_command(test::sflsh_binary() + " -q " + args, &out);
    return out;
  }
  static test::TempDir* dir_;
  static void PrecomputeWritesAValidAvatar();
  static void InspectPrintsTextAndJson();
  static void SimulateWritesResultExportsAndPicture();
  static void BatchPrecomputesOneFilePerRow();
  static void BadInputFailsWithOneClearLineAndNoOutput();
  static void MalformedMaterialFileNamesTheLine();
  static int status_;
  static std::string output_;
};
test::TempDir* PipelineCli::dir_ = nullptr;
int PipelineCli::status_ = -1;
std::string PipelineCli::output_;

}  // namespace

void PipelineCli::PrecomputeWritesAValidAvatar() {
  ASSERT_EQ(status_, 0) << output_;
  EXPECT_NE(output_.find("cubature vs. full integration"), std::string::npos) << output_;
  const Avatar a = read_avatar(dir_->file("avatar.h5"));
  EXPECT_EQ(a.num_handles(), 8);
  EXPECT_GT(a.tet.num_elements(), 100);
  // Partition of unity with the bone complement, bounds.
  const VecX sums = a.W * VecX::Ones(a.W.cols());
  EXPECT_LE(sums.maxCoeff(), 1.0 + 1e-6);
  EXPECT_GE(MatXr(a.W).minCoeff(), -1e-8);
  EXPECT_LE(MatXr(a.W).maxCoeff(), 1.0 + 1e-8);
  // The cached template is there and a second run reuses it.
  int code = 0;
  const std::string out = run(std::string("precompute") + kCoarse + " --betas 1,-1 --cache-dir " + dir_->file("cache") +
                                  " --out " + dir_->file("avatar2.h5"),
                              &code);
  ASSERT_EQ(code, 0) << out;
  EXPECT_NE(out.find("from cache"), std::string::npos) << out;
  const Avatar b = read_avatar(dir_->file("avatar2.h5"));
  EXPECT_EQ(b.tet.elements, a.tet.elements) << "every shape shares one tet topology";
  EXPECT_GT((b.tet.nodes - a.tet.nodes).norm(), 1e-3) << "a different shape moves the nodes";
}

void PipelineCli::InspectPrintsTextAndJson() {
  ASSERT_EQ(status_, 0) << output_;
  int code = 0;
  std::string out = run("inspect " + dir_->file("avatar.h5"), &code);
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("tet mesh"), std::string::npos) << out;
  out = run("inspect --json " + dir_->file("avatar.h5"), &code);
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("\"handles\": 8"), std::string::npos) << out;
}

void PipelineCli::SimulateWritesResultExportsAndPicture() {
  ASSERT_EQ(status_, 0) << output_;
  for (const char* bones : {"kinematic", "dynamic"}) {
    const std::string res = dir_->file(std::string("jump_") + bones + ".h5");
    int code = 0;
    const std::string out = run("simulate --avatar " + dir_->file("avatar.h5") +
                                    " --motion builtin:jump --seconds 0.3 --bones " + bones + " --out " + res +
                                    " --export " + dir_->file("jump.pc2") + " --render " + dir_->file("jump.png"),
                                &code);
    ASSERT_EQ(code, 0) << out;
    const SimulationResult r = read_simulation_result(res);
    EXPECT_EQ(r.step_time.size(), 18u);  // 0.3 s at 1/60
    EXPECT_EQ(r.frame_time.size(), 10u);  // t = 0 plus 9 frames at 30 fps
    EXPECT_EQ(r.frame_positions[0].rows(), r.surface_rest.rows());
    double umax = 0;
    for (const auto& u : r.frame_displacement) umax = std::max(umax, u.rowwise().norm().maxCoeff());
    EXPECT_GT(umax, 1e-5) << "the jump must excite the soft tissue";
    EXPECT_LT(umax, 0.1) << "soft displacement stays plausible";
    io::Hdf5File f(res, io::Hdf5File::Mode::Read);
    for (const char* name : {"/frames/time", "/frames/positions", "/frames/joints", "/frames/reduced", "/frames/step_ms",
                             "/surface/faces"})
      EXPECT_TRUE(f.has(name)) << name;
  }
  EXPECT_TRUE(std::filesystem::exists(dir_->file("jump.pc2")));
  EXPECT_TRUE(std::filesystem::exists(dir_->file("jump_rest.obj")));
  EXPECT_TRUE(std::filesystem::exists(dir_->file("jump.png")));
}

void PipelineCli::BatchPrecomputesOneFilePerRow() {
  ASSERT_EQ(status_, 0) << output_;
  {
    std::ofstream csv(dir_->file("betas.csv"));
    csv << "b0,b1\n0,0\n1,0.5\n-1,-0.5\n";
  }
  int code = 0;
  const std::string out = run(std::string("precompute") + kCoarse + " --cache-dir " + dir_->file("cache") + " --batch " +
                                  dir_->file("betas.csv") + " --out-dir " + dir_->file("batch"),
                              &code);
  ASSERT_EQ(code, 0) << out;
  // Files are named by content key; the manifest maps data rows to them.
  const auto rows = read_batch_manifest(dir_->file("batch/manifest.csv"));
  ASSERT_EQ(rows.size(), 3u);
  for (const auto& r : rows) {
    EXPECT_EQ(r.status, "built") << r.error;
    EXPECT_TRUE(std::filesystem::exists(r.file)) << r.file;
  }
  EXPECT_NEAR(read_avatar(rows[1].file).betas[1], 0.5, 1e-12);
}

void PipelineCli::BadInputFailsWithOneClearLineAndNoOutput() {
  ASSERT_EQ(status_, 0) << output_;
  struct Case {
    std::string args, expect;
  } cases[] = {
      {"simulate --avatar " + dir_->file("nope.h5") + " --out " + dir_->file("x.h5"), "nope.h5: file not found"},
      {"simulate --avatar " + dir_->file("avatar.h5") + " --dt 1/0 --out " + dir_->file("x.h5"), "--dt"},
      {"simulate --avatar " + dir_->file("avatar.h5") + " --motion builtin:moonwalk --out " + dir_->file("x.h5"),
       "moonwalk"},
      {"simulate --avatar " + dir_->file("avatar.h5") + " --material " + dir_->file("missing.yaml") + " --out " +
           dir_->file("x.h5"),
       "missing.yaml"},
      {"inspect " + dir_->file("betas_missing.csv"), "not found"},
      {"precompute --model procedural:10 --out " + dir_->file("x.h5"), "procedural:N"},
      {"precompute --batch " + dir_->file("none.csv") + " --out-dir " + dir_->file("b2"), "none.csv"},
  };
  for (const auto& c : cases) {
    int code = 0;
    const std::string out = run(c.args, &code);
    EXPECT_NE(code, 0) << c.args;
    EXPECT_NE(out.find(c.expect), std::string::npos) << c.args << "\n" << out;
    EXPECT_NE(out.find("error"), std::string::npos) << out;
  }
  EXPECT_FALSE(std::filesystem::exists(dir_->file("x.h5")));
}

void PipelineCli::MalformedMaterialFileNamesTheLine() {
  ASSERT_EQ(status_, 0) << output_;
  {
    std::ofstream y(dir_->file("m.yaml"));
    y << "all:\n  young: 2.0e4\nregions:\n  no_such_region: {young: 1e4}\n";
  }
  int code = 0;
  const std::string out = run("simulate --avatar " + dir_->file("avatar.h5") + " --seconds 0.05 --material " +
                                  dir_->file("m.yaml") + " --out " + dir_->file("y.h5"),
                              &code);
  EXPECT_NE(code, 0);
  EXPECT_NE(out.find("m.yaml:4"), std::string::npos) << out;
  EXPECT_NE(out.find("no_such_region"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir_->file("y.h5")));
}

// ctest runs every TEST in its own process: one test, so the precompute runs once.
TEST_F(PipelineCli, EndToEnd) {
  {
    SCOPED_TRACE("PrecomputeWritesAValidAvatar");
    PrecomputeWritesAValidAvatar();
  }
  {
    SCOPED_TRACE("InspectPrintsTextAndJson");
    InspectPrintsTextAndJson();
  }
  {
    SCOPED_TRACE("SimulateWritesResultExportsAndPicture");
    SimulateWritesResultExportsAndPicture();
  }
  {
    SCOPED_TRACE("BatchPrecomputesOneFilePerRow");
    BatchPrecomputesOneFilePerRow();
  }
  {
    SCOPED_TRACE("BadInputFailsWithOneClearLineAndNoOutput");
    BadInputFailsWithOneClearLineAndNoOutput();
  }
  {
    SCOPED_TRACE("MalformedMaterialFileNamesTheLine");
    MalformedMaterialFileNamesTheLine();
  }
}
