#include "sflsh/teleop/pose_file.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "test_support.hpp"

namespace sflsh::teleop {
namespace {

constexpr PoseFileFormat kCsv = PoseFileFormat::kCsv;
constexpr PoseFileFormat kJson = PoseFileFormat::kJsonLines;

std::vector<PoseSample> csv(const std::string& text) { return parse_pose_text(text, kCsv, "grip.csv"); }
std::vector<PoseSample> jsonl(const std::string& text) { return parse_pose_text(text, kJson, "grip.jsonl"); }

TEST(PoseFile, ReadsCsvWithColumnsInAnyOrderAndSkipsComments) {
  const auto s = csv(
      "# a recorded pinch\n"
      "closure,time,x,y,z,qw,qx,qy,qz\n"
      "0.5, 0, 0.1, 0.2, 0.3, 1, 0, 0, 0\n"
      "\n"
      "0.25,0.01,0.1,0.2,0.35,0,1,0,0\n");
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].closure, 0.5);
  EXPECT_EQ(s[0].position, Vec3(0.1, 0.2, 0.3));
  EXPECT_EQ(s[1].time, 0.01);
  EXPECT_EQ(s[1].position.z(), 0.35);
  EXPECT_EQ(s[1].orientation.x(), 1.0);
  EXPECT_EQ(s[1].closure, 0.25);
}

TEST(PoseFile, ReadsJsonLines) {
  const auto s = jsonl(
      "{\"t\": 0.5, \"p\": [1, -2, 3.5], \"q\": [0.5, 0.5, -0.5, 0.5], \"closure\": 0.75}\n"
      "{\"closure\":0,\"q\":[1,0,0,0],\"p\":[0,0,0],\"t\":15e-1}\n");
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].time, 0.5);
  EXPECT_EQ(s[0].position, Vec3(1, -2, 3.5));
  EXPECT_EQ(s[0].orientation.w(), 0.5);
  EXPECT_EQ(s[0].orientation.y(), -0.5);
  EXPECT_EQ(s[0].closure, 0.75);
  EXPECT_EQ(s[1].time, 1.5);
}

TEST(PoseFile, SmallQuaternionDeviationIsNormalized) {
  const auto s = csv("time,x,y,z,qw,qx,qy,qz,closure\n0,0,0,0,1.0005,0,0,0,0\n");
  EXPECT_DOUBLE_EQ(s[0].orientation.w(), 1.0);
}

TEST(PoseFile, CsvErrorsNameFileLineAndField) {
  const std::string h = "time,x,y,z,qw,qx,qy,qz,closure\n";
  test::expect_error([] { csv("time,x,y,z,qw,qx,qy,closure\n0,0,0,0,1,0,0,0\n"); },
                     {"grip.csv line 1", "lacks the column 'qz'"});
  test::expect_error([] { csv("time,x,y,z,qw,qx,qy,qz,closure,speed\n"); }, {"grip.csv line 1", "unknown column 'speed'"});
  test::expect_error([&] { csv(h + "0,0,nan,0,1,0,0,0,0\n"); }, {"grip.csv line 2, field 'y'", "finite", "nan"});
  test::expect_error([&] { csv(h + "0,0,0,0,1,0,0,abc,0\n"); }, {"grip.csv line 2, field 'qz'", "expected a number, got 'abc'"});
  test::expect_error([&] { csv(h + "0,0,0,0,1,0,0,0\n"); }, {"grip.csv line 2", "8 values, expected 9"});
  test::expect_error([&] { csv(h + "0,0,0,0,1,0,0,0,0\n0,0,0,0,1,0,0,0,0\n"); },
                     {"grip.csv line 3, field 'time'", "strictly increasing"});
  test::expect_error([&] { csv(h + "0,0,0,0,1,0,0,0,0\n# gap\n-1,0,0,0,1,0,0,0,0\n"); },
                     {"grip.csv line 4, field 'time'", "-1"});
  test::expect_error([&] { csv(h + "0,0,0,0,0.9,0,0,0,0\n"); }, {"grip.csv line 2, field 'q'", "norm 0.9"});
  test::expect_error([&] { csv(h + "0,0,0,0,1,0,0,0,4\n"); }, {"grip.csv line 2, field 'closure'", "[0, pi]"});
  test::expect_error([&] { csv(h); }, {"grip.csv", "no pose samples"});
  test::expect_error([] { csv(""); }, {"grip.csv", "no header"});
}

TEST(PoseFile, JsonLinesErrorsNameFileLineAndField) {
  test::expect_error([] { jsonl("{\"t\":0,\"p\":[0,0,0],\"q\":[1,0,0,0]}\n"); }, {"grip.jsonl line 1, field 'closure'", "missing"});
  test::expect_error([] { jsonl("{\"t\":0,\"p\":[0,0],\"q\":[1,0,0,0],\"closure\":0}\n"); },
                     {"grip.jsonl line 1, field 'p'", "2 numbers, expected 3"});
  test::expect_error([] { jsonl("{\"t\":0,\"p\":[0,0,0],\"q\":[1,0,0,0,0],\"closure\":0}\n"); },
                     {"field 'q'", "more than 4"});
  test::expect_error([] { jsonl("{\"t\":0,\"p\":[0,0,0],\"q\":[1,0,0,0],\"closure\":0,\"v\":1}\n"); },
                     {"field 'v'", "unknown key"});
  test::expect_error([] { jsonl("\n{\"t\":NaN,\"p\":[0,0,0],\"q\":[1,0,0,0],\"closure\":0}\n"); },
                     {"grip.jsonl line 2, field 't'", "finite"});
  test::expect_error([] { jsonl("{\"t\":0,\"p\":[0,0,0],\"q\":[0,0,0,0],\"closure\":0}\n"); },
                     {"field 'q'", "quaternion norm 0"});
  test::expect_error([] { jsonl("{\"t\":1,\"p\":[0,0,0],\"q\":[1,0,0,0],\"closure\":0}\n"
                               "{\"t\":0.5,\"p\":[0,0,0],\"q\":[1,0,0,0],\"closure\":0}\n"); },
                     {"grip.jsonl line 2, field 't'", "strictly increasing"});
  test::expect_error([] { jsonl("{\"t\":0,\"p\":[0,0,0],\"q\":[1,0,0,0],\"closure\":0} extra\n"); },
                     {"grip.jsonl line 1", "unexpected text"});
  test::expect_error([] { jsonl("[1,2]\n"); }, {"grip.jsonl line 1", "expected '{'"});
}

TEST(PoseFile, FileErrorsNameThePath) {
  test::TempDir dir;
  test::expect_error([&] { read_pose_file(dir.file("missing.csv")); }, {"missing.csv", "cannot open"});
  test::expect_error([&] { read_pose_file(dir.file("poses.txt")); }, {"poses.txt", ".csv, .jsonl"});
  const std::string path = dir.file("bad.jsonl");
  std::ofstream(path) << "{\"t\":0,\"p\":[0,0,0],\"q\":[1,0,0,0],\"closure\":-1}\n";
  test::expect_error([&] { read_pose_file(path); }, {path + " line 1, field 'closure'"});
}

TEST(PoseFile, WriteReadRoundTripIsBitExactInBothFormats) {
  test::TempDir dir;
  std::vector<PoseSample> in;
  for (int i = 0; i < 5; ++i) {
    PoseSample s;
    s.time = 0.1 * i + 1.0 / 3.0;
    s.position = Vec3(std::sqrt(2.0) * i, -1.0 / 7.0, 1e-9 * i);
    s.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3 * i + 0.1, Vec3(1, 2, 3).normalized()));
    s.closure = 0.1 * i;
    in.push_back(s);
  }
  for (const char* name : {"rec.csv", "rec.jsonl"}) {
    write_pose_file(dir.file(name), in);
    const auto out = read_pose_file(dir.file(name));
    ASSERT_EQ(out.size(), in.size()) << name;
    for (std::size_t i = 0; i < in.size(); ++i) {
      EXPECT_EQ(out[i].time, in[i].time) << name;
      EXPECT_EQ(out[i].position, in[i].position) << name;
      EXPECT_EQ(out[i].closure, in[i].closure) << name;
      EXPECT_EQ(out[i].orientation.coeffs(), in[i].orientation.coeffs()) << name;
    }
  }
}

}  // namespace
}  // namespace sflsh::teleop
