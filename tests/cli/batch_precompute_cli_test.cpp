// `sflsh precompute --batch` end to end on the coarse built-in body: resume
// after a crash gives the files of an uninterrupted run bit for bit, bad rows
// are reported by row while the rest are built, shards cover every row once,
// and the Dask driver (data_tools/batch_precompute_dask.py) on a LocalCluster.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <numeric>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/basis/basis_coverage.hpp"
#include "sflsh/basis/handle_placement.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/mesh/tet_topology_hash.hpp"
#include "sflsh/precompute/batch_precompute.hpp"
#include "test_support.hpp"

using namespace sflsh;
namespace fs = std::filesystem;

namespace {

// Few handles, large tets: a shape takes a few seconds.
const char* kCoarse = " --handles 6 --cell-size 0.08 --facet-size 0.06 --facet-distance 0.004";

class BatchCli : public ::testing::Test {
 protected:
  /// One template stage for every test (the suite's cache folder).
  static void SetUpTestSuite() {
    dir_ = new test::TempDir();
    status_ = test::run_command(
        test::sflsh_binary() + " -q precompute --template-only" + kCoarse + " --cache-dir " + dir_->file("cache"),
        &output_);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  void SetUp() override { ASSERT_EQ(status_, 0) << output_; }
  static int run(const std::string& args, std::string* out) {
    return test::run_command(test::sflsh_binary() + " -q precompute" + kCoarse + " --cache-dir " + dir_->file("cache") +
                                 " " + args,
                             out);
  }
  static std::string csv(const std::string& name, const std::string& text) {
    std::ofstream(dir_->file(name)) << text;
    return dir_->file(name);
  }
  static std::map<int, BatchRecord> manifest(const std::string& path) {
    std::map<int, BatchRecord> m;
    for (auto& r : read_batch_manifest(path)) EXPECT_TRUE(m.emplace(r.row, r).second) << "row " << r.row << " twice";
    return m;
  }
  static std::string bytes(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  }
  static test::TempDir* dir_;
  static int status_;
  static std::string output_;
};
test::TempDir* BatchCli::dir_ = nullptr;
int BatchCli::status_ = -1;
std::string BatchCli::output_;

}  // namespace

TEST_F(BatchCli, ResumedRunSkipsFinishedRowsAndMatchesAnUninterruptedRunBitForBit) {
  // Row 3 repeats row 1 (same key: built once).
  const std::string shapes = csv("resume.csv", "name,b0,b1\nslim,-1,0.5\nmid,0,0\nwide,1.5,-0.5\nmid again,0,0\n");
  std::string out;
  ASSERT_EQ(run("--batch " + shapes + " --out-dir " + dir_->file("a") + " --jobs 2", &out), 0) << out;
  auto a = manifest(dir_->file("a/manifest.csv"));
  ASSERT_EQ(a.size(), 4u);
  for (int row : {0, 1, 2}) {
    EXPECT_EQ(a[row].status, "built") << row << ": " << a[row].error;
    EXPECT_EQ(fs::path(a[row].file).filename().string(), "avatar-" + a[row].key + ".h5");
    EXPECT_GT(a[row].seconds, 0);
    EXPECT_GT(a[row].peak_rss_mib, 10) << "a worker's peak memory";
  }
  EXPECT_EQ(a[0].name, "slim");
  EXPECT_EQ(a[3].name, "mid again");
  EXPECT_EQ(a[3].status, "duplicate");
  EXPECT_EQ(a[3].file, a[1].file);
  const Avatar wide = read_avatar(a[2].file);
  ASSERT_GE(wide.betas.size(), 2);
  EXPECT_EQ(wide.betas[0], 1.5);
  EXPECT_EQ(wide.betas[1], -0.5);
  EXPECT_EQ(wide.betas.tail(wide.betas.size() - 2).cwiseAbs().maxCoeff(), 0.0) << "padded with zeros";
  EXPECT_FALSE(fs::exists(dir_->file("a/logs/row-000000.log"))) << "logs of successful rows are removed";

  // A crashed run: row 1 finished (built alone, as a job-array task would),
  // row 0 left a half-written temporary file, and row 2's final name holds a
  // file that is not an avatar (an interrupted copy, say). Row 1 is solved on
  // 3 weight threads here and on 1 in run a's workers: the bytes must not differ.
  ASSERT_EQ(run("--batch " + shapes + " --out-dir " + dir_->file("b") + " --task-index 1 --threads 3", &out), 0) << out;
  EXPECT_EQ(manifest(dir_->file("b/manifest-task-1.csv"))[1].status, "built");
  const std::string f0 = dir_->file("b/" + fs::path(a[0].file).filename().string());
  const std::string f2 = dir_->file("b/" + fs::path(a[2].file).filename().string());
  std::ofstream(f0 + ".partial") << "half an HDF5 file";
  std::ofstream(f2) << "not an avatar";
  ASSERT_EQ(run("--batch " + shapes + " --out-dir " + dir_->file("b") + " --jobs 2", &out), 0) << out;
  auto b = manifest(dir_->file("b/manifest.csv"));
  ASSERT_EQ(b.size(), 4u);
  EXPECT_EQ(b[0].status, "built");
  EXPECT_EQ(b[1].status, "exists") << "finished before the crash: not computed again";
  EXPECT_EQ(b[2].status, "built") << "a file that is not the row's avatar is rebuilt";
  EXPECT_EQ(b[3].status, "duplicate");
  for (int row : {0, 1, 2}) {
    EXPECT_EQ(b[row].key, a[row].key);
    const std::string fa = bytes(a[row].file), fb = bytes(b[row].file);
    EXPECT_GT(fa.size(), 1000u);
    EXPECT_TRUE(fa == fb) << "row " << row << ": the resumed run's file differs from the uninterrupted run's";
  }
  EXPECT_NE(run("--batch " + shapes + " --out-dir " + dir_->file("c") + " --threads -1", &out), 0);
  EXPECT_NE(out.find("--threads must be in [1, 1024]"), std::string::npos) << out;
  // Nothing left to do: a third run builds nothing and succeeds.
  ASSERT_EQ(run("--batch " + shapes + " --out-dir " + dir_->file("b"), &out), 0) << out;
  EXPECT_NE(out.find("4 rows: 3 exists, 1 duplicate"), std::string::npos) << out;
}

TEST_F(BatchCli, FailingRowsAreReportedByRowWhileTheOthersAreBuilt) {
  const std::string shapes = csv("bad.csv",
                                 "name,b0,b1\n"
                                 "ok,0.5,0\n"
                                 "nan row,nan,0\n"
                                 "short,1\n"
                                 "text,abc,0\n"
                                 "ok2,-0.5,0.25\n");
  for (const char* jobs : {"1", "2"}) {
    SCOPED_TRACE(std::string("--jobs ") + jobs);
    const std::string out_dir = dir_->file(std::string("bad") + jobs);
    std::string out;
    EXPECT_NE(run("--batch " + shapes + " --out-dir " + out_dir + " --jobs " + jobs, &out), 0) << out;
    for (const std::string& e :
         {"row 1 (" + shapes + " line 3) failed: column 'b0' is nan (β must be finite)",
          "row 2 (" + shapes + " line 4) failed: has 2 fields but the header has 3",
          "row 3 (" + shapes + " line 5) failed: column 'b0' 'abc' is not a number",
          std::string("5 rows: 2 built, 3 failed"), std::string("failed rows:"),
          std::string("error: batch: 3 of 5 rows failed")})
      EXPECT_NE(out.find(e), std::string::npos) << e << "\n" << out;
    auto m = manifest(out_dir + "/manifest.csv");
    ASSERT_EQ(m.size(), 5u);
    EXPECT_EQ(m[0].status, "built");
    EXPECT_EQ(m[4].status, "built");
    EXPECT_EQ(m[1].status, "failed");
    EXPECT_EQ(m[1].name, "nan row");
    EXPECT_EQ(read_avatar(m[4].file).betas[1], 0.25);
  }
}

TEST_F(BatchCli, ShardsCoverEveryRowExactlyOnceAndBadSlicesFail) {
  std::string text = "b0\n";
  for (int i = 0; i < 7; ++i) text += std::to_string(0.1 * i) + "\n";
  const std::string shapes = csv("shards.csv", text);
  std::map<int, int> seen;
  for (int i = 0; i < 3; ++i) {
    std::string out;
    const std::string shard = std::to_string(i) + "/3";
    ASSERT_EQ(run("--batch " + shapes + " --out-dir " + dir_->file("s") + " --dry-run --shard " + shard, &out), 0)
        << out;
    for (const auto& [row, r] : manifest(dir_->file("s/manifest-shard-" + std::to_string(i) + "-of-3.csv"))) {
      ++seen[row];
      EXPECT_EQ(row % 3, i);
      EXPECT_EQ(r.status, "pending");
    }
  }
  ASSERT_EQ(seen.size(), 7u);
  for (const auto& [row, n] : seen) EXPECT_EQ(n, 1) << "row " << row;
  EXPECT_FALSE(fs::exists(dir_->file("s/avatar-" + manifest(dir_->file("s/manifest-shard-0-of-3.csv"))[0].key + ".h5")))
      << "--dry-run builds nothing";
  struct Case {
    std::string args, expect;
  } cases[] = {
      {"--shard 3/3", "--shard '3/3': expected i/n"},
      {"--task-index 7", "--task-index 7 but the file has 7 data rows (task indices 0 to 6)"},
      {"--task-index 1 --shard 0/2", "--task-index and --shard exclude each other"},
      {"--jobs 2 --no-cache", "--no-cache with --jobs 2"},
  };
  for (const auto& c : cases) {
    std::string out;
    EXPECT_NE(run("--batch " + shapes + " --out-dir " + dir_->file("s") + " " + c.args, &out), 0) << c.args;
    EXPECT_NE(out.find(c.expect), std::string::npos) << c.args << "\n" << out;
  }
  std::string out;
  EXPECT_NE(test::run_command(test::sflsh_binary() + " precompute --shard 0/2 --out x.h5", &out), 0);
  EXPECT_NE(out.find("--shard needs --batch"), std::string::npos) << out;
}

TEST_F(BatchCli, DaskLocalClusterOfTwoWorkersBuildsEveryRow) {
  std::string probe;
  if (test::run_command("/usr/bin/python3 -c 'import distributed'", &probe) != 0)
    GTEST_SKIP() << "Dask distributed is not importable by /usr/bin/python3 (Debian: apt-get install "
                    "python3-distributed); skipping the Dask batch test";
  const std::string shapes = csv("dask.csv", "name,b0\nthin,-1\nmid,0\nbig,1\n");
  std::string out;
  const std::string cmd = "/usr/bin/python3 " + test::source_dir() + "/data_tools/batch_precompute_dask.py --sflsh " +
                          test::sflsh_binary() + " --workers 2 --batch " + shapes + " --out-dir " + dir_->file("d") +
                          " --csv " + dir_->file("d/result.csv") + " --" + kCoarse + " --cache-dir " +
                          dir_->file("cache");
  ASSERT_EQ(test::run_command(cmd, &out), 0) << out;
  EXPECT_NE(out.find("3 rows: 3 built"), std::string::npos) << out;
  std::ifstream f(dir_->file("d/result.csv"));
  std::string line;
  std::getline(f, line);
  EXPECT_EQ(line, "row,line,name,key,file,status,seconds,shape_seconds,peak_rss_mib,worker,error");
  int rows = 0;
  const char* names[] = {"thin", "mid", "big"};
  while (std::getline(f, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    EXPECT_EQ(line.rfind(std::to_string(rows) + "," + std::to_string(rows + 2) + "," + names[rows] + ",", 0), 0u)
        << line;
    EXPECT_NE(line.find(",built,"), std::string::npos) << line;
    EXPECT_NE(line.find("tcp://"), std::string::npos) << "the worker that ran it: " << line;
    ++rows;
  }
  EXPECT_EQ(rows, 3);
  // The same content keys as a local batch: the files are where sflsh puts them.
  ASSERT_EQ(run("--batch " + shapes + " --out-dir " + dir_->file("d") + " --dry-run", &out), 0) << out;
  auto m = manifest(dir_->file("d/manifest.csv"));
  for (int row = 0; row < 3; ++row) {
    EXPECT_EQ(m[row].status, "exists") << row;
    EXPECT_EQ(read_avatar(m[row].file).betas[0], row - 1.0);
  }
}

/// `--handles-min-per-region`: every region that a minimum of 2 leaves at 2
/// handles gets at least 3 with the flag at 3, from the same K (taken from the
/// large regions), and the batch content key tells the settings apart (also
/// the default, 4, from 2: the earlier default, whose keys did not
/// spell the minimum out).
TEST_F(BatchCli, HandlesMinPerRegionRaisesTheSmallRegionsCounts) {
  const std::string coarse = " --cell-size 0.08 --facet-size 0.06 --facet-distance 0.004 --cache-dir " +
                             dir_->file("cache") + " --handles 40";
  auto counts = [&](const std::string& flag, const std::string& name) {
    std::string out;
    EXPECT_EQ(test::run_command(test::sflsh_binary() + " -q precompute" + coarse + flag + " --out " + dir_->file(name),
                                &out),
              0)
        << out;
    const Avatar a = read_avatar(dir_->file(name));
    const int R = int(a.materials.size());
    const VecXi node_region = basis::node_regions_from_tets(a.tet, a.tet_region, R);
    std::vector<int> n(size_t(R), 0);
    for (int node : basis::nearest_nodes(a.tet.nodes, a.handles)) ++n[size_t(node_region[node])];
    return n;
  };
  const std::vector<int> two = counts(" --handles-min-per-region 2", "min2.h5"), three = counts(" --handles-min-per-region 3", "min3.h5");
  int at_two = 0;
  for (size_t r = 0; r < two.size(); ++r) {
    if (two[r] == 2) ++at_two;
    if (two[r] >= 2) EXPECT_GE(three[r], 3) << "region " << r;
  }
  EXPECT_GT(at_two, 0) << "no region at the default minimum: the test would not see the flag";
  EXPECT_EQ(std::accumulate(two.begin(), two.end(), 0), 40);
  EXPECT_EQ(std::accumulate(three.begin(), three.end(), 0), 40);
  PrecomputeOptions o2, o3, o4;
  o2.placement.min_per_region = 2;
  o3.placement.min_per_region = 3;
  EXPECT_EQ(o4.placement.min_per_region, 4);
  const BodyModel model = load_body_model("procedural");
  const VecX b = VecX::Zero(10);
  EXPECT_NE(avatar_content_key(model, b, o2), avatar_content_key(model, b, o3));
  EXPECT_NE(avatar_content_key(model, b, o2), avatar_content_key(model, b, o4));
}

// One tet topology per batch folder (seed §4). Every output's element array hash is in the
// manifest and in the file's /meta/topology_hash; a manifest row whose hash is not its file's
// is refused with one line naming the manifest line, the row and the file; a folder holding an
// avatar with other tets (an older file: no /meta/topology_hash, two tets swapped) is refused
// with one line naming both files, before anything is built.
TEST_F(BatchCli, AWrongManifestHashAndAFolderWithTwoTopologiesAreRefused) {
  const std::string shapes = csv("topo.csv", "b0,b1\n0.5,0\n");
  const std::string out_dir = dir_->file("topo");
  std::string out;
  ASSERT_EQ(run("--batch " + shapes + " --out-dir " + out_dir + " --jobs 1", &out), 0) << out;
  const std::string path = out_dir + "/manifest.csv";
  auto m = manifest(path);
  ASSERT_EQ(m[0].status, "built");
  const std::string file = m[0].file, hash = m[0].topology;
  ASSERT_EQ(hash.size(), 16u);
  EXPECT_EQ(hash, tet_topology_hash(read_avatar(file).tet.elements));
  const std::string text = bytes(path);

  // The manifest's row 0 records another hash.
  std::string bad = text;
  ASSERT_NE(bad.find("," + hash + ","), std::string::npos);
  bad.replace(bad.find("," + hash + ","), hash.size() + 2, ",0123456789abcdef,");
  std::ofstream(path) << bad;
  EXPECT_NE(run("--batch " + shapes + " --out-dir " + out_dir, &out), 0);
  EXPECT_NE(out.find(path + ":2: row 0: " + file + " has tet topology " + hash +
                     " but the manifest records 0123456789abcdef"),
            std::string::npos)
      << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << "one line:\n" << out;
  EXPECT_EQ(bytes(path), bad) << "the refused run rewrote the manifest";
  std::ofstream(path) << text;

  // A second avatar with other tets in the folder.
  const std::string other = out_dir + "/avatar-0000000000000000.h5";
  fs::copy_file(file, other);
  ASSERT_EQ(test::run_command("/usr/bin/python3 -c \"import h5py, sys\n"
                              "with h5py.File(sys.argv[1], 'r+') as f:\n"
                              "    e = f['/tet/elements'][...]\n"
                              "    e[[0, 1]] = e[[1, 0]]\n"
                              "    f['/tet/elements'][...] = e\n"
                              "    del f['/meta/topology_hash']\" " +
                                  other,
                              &out),
            0)
      << out;
  const std::string more = csv("topo2.csv", "b0,b1\n0.5,0\n-0.5,0\n");
  EXPECT_NE(run("--batch " + more + " --out-dir " + out_dir, &out), 0);
  EXPECT_NE(out.find("batch: " + other + " and " + file + " have different tet topologies"), std::string::npos) << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << "one line:\n" << out;
  EXPECT_EQ(bytes(path), text) << "nothing written";
  EXPECT_EQ(manifest(path).size(), 1u);
  int avatars = 0;
  for (const auto& e : fs::directory_iterator(out_dir)) avatars += e.path().extension() == ".h5";
  EXPECT_EQ(avatars, 2) << "the second row was not built";
}
