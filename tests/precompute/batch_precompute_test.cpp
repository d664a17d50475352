// Batch precompute without building avatars: the shapes CSV (valid and bad
// rows), content keys, shards, the plan, the manifest and the progress line.
#include "sflsh/precompute/batch_precompute.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "sflsh/body/body_model_io.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

std::string write_file(const test::TempDir& dir, const std::string& name, const std::string& text) {
  std::ofstream(dir.file(name)) << text;
  return dir.file(name);
}

const BodyModel& model() {
  static const BodyModel m = load_body_model("procedural");
  return m;
}

}  // namespace

TEST(BatchShapes, ReadsBetasNamesAndReportsBadRowsByRowAndLine) {
  test::TempDir dir;
  const std::string path = write_file(dir, "s.csv",
                                      "b0,Name,b1\n"
                                      "0.5,alice,-1\n"
                                      "\n"
                                      "# a comment\n"
                                      "nan,bob,0\n"
                                      "1,carol\n"
                                      "abc,dave,0\n"
                                      "2,\"eve, jr\",1e-3\r\n"
                                      "inf,frank,0\n");
  const auto rows = read_batch_shapes(path, 4);
  ASSERT_EQ(rows.size(), 6u);
  // Row 0: β padded with zeros to the model's 4 shape directions.
  EXPECT_EQ(rows[0].row, 0);
  EXPECT_EQ(rows[0].line, 2);
  EXPECT_EQ(rows[0].name, "alice");
  EXPECT_TRUE(rows[0].error.empty()) << rows[0].error;
  ASSERT_EQ(rows[0].betas.size(), 4);
  EXPECT_EQ(rows[0].betas[0], 0.5);
  EXPECT_EQ(rows[0].betas[1], -1.0);
  EXPECT_EQ(rows[0].betas[2], 0.0);
  EXPECT_EQ(rows[0].betas[3], 0.0);
  // Blank and comment lines are not rows but count as lines.
  EXPECT_EQ(rows[1].row, 1);
  EXPECT_EQ(rows[1].line, 5);
  EXPECT_EQ(rows[1].name, "bob");
  EXPECT_NE(rows[1].error.find("column 'b0' is nan"), std::string::npos) << rows[1].error;
  EXPECT_EQ(rows[1].betas.size(), 0);
  EXPECT_NE(rows[2].error.find("has 2 fields but the header has 3"), std::string::npos) << rows[2].error;
  EXPECT_NE(rows[3].error.find("column 'b0' 'abc' is not a number"), std::string::npos) << rows[3].error;
  EXPECT_EQ(rows[4].name, "eve, jr");
  EXPECT_TRUE(rows[4].error.empty()) << rows[4].error;
  EXPECT_EQ(rows[4].betas[1], 1e-3);
  EXPECT_EQ(rows[4].line, 8);
  EXPECT_NE(rows[5].error.find("is inf (β must be finite)"), std::string::npos) << rows[5].error;
}

TEST(BatchShapes, WithoutHeaderEveryFieldIsABetaAndTooManyFail) {
  test::TempDir dir;
  const auto rows = read_batch_shapes(write_file(dir, "s.csv", "1,2\n1,2,3,4,5\n,1\n"), 4);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_TRUE(rows[0].error.empty());
  EXPECT_EQ(rows[0].line, 1);
  EXPECT_EQ(rows[0].betas[1], 2.0);
  EXPECT_EQ(rows[1].error, "has 5 β values but the model has 4 shape directions");
  EXPECT_EQ(rows[2].error, "β 0 is empty (expected a number)");
}

TEST(BatchShapes, FileLevelProblemsThrowNamingTheFile) {
  test::TempDir dir;
  test::expect_error([&] { read_batch_shapes(dir.file("none.csv"), 4); }, {"none.csv", "cannot open"});
  test::expect_error([&] { read_batch_shapes(write_file(dir, "h.csv", "b0,b1\n\n"), 4); }, {"h.csv", "no data rows"});
  test::expect_error([&] { read_batch_shapes(write_file(dir, "n.csv", "name,b0,NAME\nx,1,y\n"), 4); },
                     {"n.csv:1", "two 'name' columns"});
}

TEST(BatchKey, ChangesWithEveryInputThatChangesTheAvatar) {
  const BodyModel& m = model();
  const PrecomputeOptions base;
  VecX b = VecX::Zero(m.num_betas());
  b[0] = 0.5;
  const std::string k = avatar_content_key(m, b, base);
  EXPECT_EQ(k.size(), 16u);
  EXPECT_EQ(avatar_content_key(m, b, base), k) << "deterministic";
  PrecomputeOptions cache = base;
  cache.cache_dir = "/elsewhere";
  cache.bbw.show_progress = false;
  EXPECT_EQ(avatar_content_key(m, b, cache), k) << "where the cache is and progress output do not change the avatar";

  std::set<std::string> keys{k};
  auto differs = [&](const VecX& betas, const PrecomputeOptions& o, const char* what) {
    EXPECT_TRUE(keys.insert(avatar_content_key(m, betas, o)).second) << what;
  };
  VecX b2 = b;
  b2[0] = std::nextafter(0.5, 1.0);  // one ulp
  differs(b2, base, "beta by one ulp");
  PrecomputeOptions o = base;
  o.handles = 65;
  differs(b, o, "handles");
  o = base;
  o.thickness = ThicknessMap::uniform();
  differs(b, o, "thickness map");
  o = base;
  o.handle_positions = Points::Zero(2, 3);
  differs(b, o, "handle positions");
  o = base;
  o.template_stage.mesh.cell_size *= 2;
  differs(b, o, "template mesh");
  o = base;
  o.elastic_samples_per_cell = 4;
  differs(b, o, "cubature samples");
  o = base;
  o.fit_elastic_cubature = false;
  differs(b, o, "cubature fit");
  o = base;
  o.inertia_samples_per_cell = base.inertia_samples_per_cell == 5 ? 4 : 5;
  differs(b, o, "inertia cubature");
  o = base;
  o.bbw.drop_tolerance = 1e-5;
  differs(b, o, "bbw");
  o = base;
  o.shape_stage.min_depth = 0.2;
  differs(b, o, "shape stage");
  EXPECT_EQ(batch_avatar_file_name(k), "avatar-" + k + ".h5");
}

TEST(BatchShard, ParsesAndCoversEveryRowExactlyOnce) {
  const BatchShard s = parse_batch_shard("2/5");
  EXPECT_EQ(s.index, 2);
  EXPECT_EQ(s.count, 5);
  for (const char* bad : {"5/5", "-1/3", "1", "a/2", "1/0", "/2", "1/2x", ""})
    test::expect_error([&] { parse_batch_shard(bad); }, {"--shard", "i/n"});
  for (int n = 1; n <= 7; ++n)
    for (int row = 0; row < 50; ++row) {
      int owners = 0;
      for (int i = 0; i < n; ++i) owners += BatchShard{i, n}.contains(row);
      EXPECT_EQ(owners, 1) << "row " << row << " of " << n << " shards";
    }
}

TEST(BatchPlan, MarksInvalidDuplicateDoneAndPendingRows) {
  test::TempDir dir;
  const BodyModel& m = model();
  // Rows 1 and 3 are the same shape ("0.5" is "0.5,0" once padded).
  const std::string csv = write_file(dir, "s.csv", "name,b0,b1\na,0,0\nb,0.5,0\nc,nan,0\nd,0.5,\ne,1,1\n");
  const auto shapes = read_batch_shapes(csv, m.num_betas());
  ASSERT_EQ(shapes.size(), 5u);
  EXPECT_NE(shapes[3].error, "") << "an empty β field is an error, not 0";
  std::ofstream(dir.file("s2.csv")) << "name,b0,b1\na,0,0\nb,0.5,0\nc,nan,0\nd,0.5,0\ne,1,1\n";
  const auto rows = read_batch_shapes(dir.file("s2.csv"), m.num_betas());
  PrecomputeOptions o;
  std::filesystem::create_directories(dir.file("out"));
  // Row 4 is "done": a file with its β and model hash under its key.
  const std::string k4 = avatar_content_key(m, rows[4].betas, o);
  {
    io::Hdf5File f(dir.file("out/" + batch_avatar_file_name(k4)), io::Hdf5File::Mode::Write);
    f.write_nd("/meta/betas", rows[4].betas.data(), {rows[4].betas.size()});
    f.write_string("/meta/model_hash", body_model_hash(m));
    f.commit();
  }
  // Row 0's file exists but holds other β: not done.
  const std::string k0 = avatar_content_key(m, rows[0].betas, o);
  {
    io::Hdf5File f(dir.file("out/" + batch_avatar_file_name(k0)), io::Hdf5File::Mode::Write);
    f.write_nd("/meta/betas", rows[4].betas.data(), {rows[4].betas.size()});
    f.write_string("/meta/model_hash", body_model_hash(m));
    f.commit();
  }
  const auto plan = plan_batch(rows, m, o, dir.file("out"));
  ASSERT_EQ(plan.size(), 5u);
  const char* expect[] = {"pending", "pending", "failed", "duplicate", "exists"};
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(plan[i].row, i);
    EXPECT_EQ(plan[i].status, expect[i]) << "row " << i << ": " << plan[i].error;
  }
  EXPECT_EQ(plan[3].key, plan[1].key);
  EXPECT_EQ(plan[3].file, plan[1].file);
  EXPECT_EQ(plan[3].error, "same shape and options as row 1");
  EXPECT_EQ(plan[2].file, "");
  EXPECT_EQ(plan[4].file, dir.file("out/avatar-" + k4 + ".h5"));
  // Slices: a shard keeps its rows' statuses (row 3 stays a duplicate of a row in another shard).
  const auto s1 = plan_batch(rows, m, o, dir.file("out"), BatchShard{1, 2});
  ASSERT_EQ(s1.size(), 2u);
  EXPECT_EQ(s1[0].row, 1);
  EXPECT_EQ(s1[1].row, 3);
  EXPECT_EQ(s1[1].status, "duplicate");
  const auto t = plan_batch(rows, m, o, dir.file("out"), {}, 4);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].status, "exists");
  test::expect_error([&] { plan_batch(rows, m, o, dir.file("out"), {}, 5); }, {"task index 5", "last data row (4)"});
}

TEST(BatchManifest, RoundTripsFieldsWithCommasAndQuotes) {
  test::TempDir dir;
  std::vector<BatchRecord> in(2);
  in[0] = {3, 5, "eve, \"jr\"", "0123456789abcdef", "/x/avatar-0123456789abcdef.h5", "built", 12.3456, 410.26, "",
           "fedcba9876543210"};
  in[1] = {4, 6, "", "", "", "failed", 0, 0, "column 'b0' 'abc' is not a number, see \"x\""};
  write_batch_manifest(in, dir.file("m.csv"));
  std::ifstream f(dir.file("m.csv"));
  std::string header;
  std::getline(f, header);
  EXPECT_EQ(header, "row,line,name,key,file,status,topology,seconds,peak_rss_mib,error");
  std::string row0;
  std::getline(f, row0);
  EXPECT_EQ(row0, "3,5,\"eve, \"\"jr\"\"\",0123456789abcdef,/x/avatar-0123456789abcdef.h5,built,fedcba9876543210,12.346,"
                  "410.3,");
  const auto out = read_batch_manifest(dir.file("m.csv"));
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].topology, "fedcba9876543210");
  EXPECT_EQ(out[1].topology, "");
  EXPECT_EQ(out[0].manifest_line, 2);
  EXPECT_EQ(out[1].manifest_line, 3);
  EXPECT_EQ(out[0].name, in[0].name);
  EXPECT_EQ(out[0].key, in[0].key);
  EXPECT_EQ(out[0].file, in[0].file);
  EXPECT_EQ(out[0].status, "built");
  EXPECT_DOUBLE_EQ(out[0].seconds, 12.346);  // written with 3 decimals
  EXPECT_DOUBLE_EQ(out[0].peak_rss_mib, 410.3);  // 1 decimal
  EXPECT_EQ(out[1].row, 4);
  EXPECT_EQ(out[1].line, 6);
  EXPECT_EQ(out[1].error, in[1].error);
  test::expect_error([&] { read_batch_manifest(write_file(dir, "bad.csv", "a,b\n")); }, {"bad.csv", "not a batch manifest"});
  // A manifest from before the topology column is still read (no topology recorded).
  const auto old = read_batch_manifest(write_file(dir, "old.csv",
                                                  "row,line,name,key,file,status,seconds,peak_rss_mib,error\n"
                                                  "0,2,a,k,/x/f.h5,built,1.5,20.0,\n"));
  ASSERT_EQ(old.size(), 1u);
  EXPECT_EQ(old[0].status, "built");
  EXPECT_EQ(old[0].topology, "");
  EXPECT_DOUBLE_EQ(old[0].seconds, 1.5);
  test::expect_error([&] { read_batch_manifest(write_file(dir, "short.csv",
                                                          "row,line,name,key,file,status,topology,seconds,peak_rss_mib,"
                                                          "error\n0,2,a,k,/x/f.h5,built,1.5,20.0,\n")); },
                     {"short.csv:2", "expected 10 fields, found 9"});
}

TEST(BatchReport, ProgressRateEtaAndSummaryTable) {
  // 4 of 16 rows in 8 s: 0.5 rows/s = 30 rows/min, 12 rows left -> 24 s.
  EXPECT_EQ(batch_progress_line(4, 16, 1, 8.0), "batch: 4/16 rows done (1 failed), 30.00 rows/min, elapsed 8 s, ETA 24 s");
  // 30 of 40 in 10 s: 3 rows/s, 10 left -> 3 s.
  EXPECT_EQ(batch_progress_line(30, 40, 0, 10.0), "batch: 30/40 rows done, 3.00 rows/s, elapsed 10 s, ETA 3 s");
  // 2 of 10 in 100 s: 1.2 rows/min, 8 left -> 400 s = 6.7 min.
  EXPECT_EQ(batch_progress_line(2, 10, 0, 100.0), "batch: 2/10 rows done, 1.20 rows/min, elapsed 1.7 min, ETA 6.7 min");
  EXPECT_EQ(batch_progress_line(0, 10, 0, 0.0), "batch: 0/10 rows done");
  std::vector<BatchRecord> r(3);
  r[0] = {0, 2, "a", "k0", "f0", "built", 2.0, 300, ""};
  r[1] = {1, 3, "b", "k1", "f1", "built", 4.0, 500, ""};
  r[2] = {2, 4, "bob", "", "", "failed", 0, 0, "column 'b0' is nan (β must be finite)"};
  const std::string s = batch_summary(r, 5.0);
  EXPECT_NE(s.find("3 rows: 2 built, 1 failed; wall 5.0 s; 3.00 s per built shape"), std::string::npos) << s;
  EXPECT_NE(s.find("peak memory 500 MiB"), std::string::npos) << s;
  EXPECT_NE(s.find("failed rows:\n  row   line  name  error\n  2     4     bob   column 'b0' is nan"), std::string::npos)
      << s;
}
