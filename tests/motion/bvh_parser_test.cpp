#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <regex>

#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/motion/bvh.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

using Quat = Eigen::Quaterniond;

std::string fixture(const std::string& name) { return test::source_dir() + "/tests/data/motion/" + name; }

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

Quat rot(char axis, double deg) {
  const Vec3 a = axis == 'X' ? Vec3::UnitX() : axis == 'Y' ? Vec3::UnitY() : Vec3::UnitZ();
  return Quat(Eigen::AngleAxisd(deg * M_PI / 180, a));
}

TEST(BvhParser, ReadsTinyFixtureLfAndCrlfAlike) {
  const BvhMotion lf = read_bvh(fixture("tiny.bvh"));
  const BvhMotion crlf = read_bvh(fixture("tiny_crlf.bvh"));
  ASSERT_EQ(lf.joints.size(), 4u);
  EXPECT_EQ(lf.joints[0].name, "Hips");
  EXPECT_EQ(lf.joints[2].name, "LeftUpLeg");
  EXPECT_EQ(lf.joints[3].parent, 2);
  EXPECT_EQ(lf.joints[2].parent, 0);
  EXPECT_TRUE(lf.joints[1].has_end_site);
  EXPECT_DOUBLE_EQ(lf.joints[3].end_site.y(), -40);
  EXPECT_EQ(lf.num_channels, 15);
  EXPECT_EQ(lf.num_frames, 3);
  EXPECT_DOUBLE_EQ(lf.frame_time, 0.04);
  EXPECT_EQ(lf.joints[2].first_channel, 9);
  EXPECT_EQ(lf.values, crlf.values);
  EXPECT_EQ(crlf.joints.size(), 4u);
  EXPECT_DOUBLE_EQ(lf.value(1, 1), 91);
  EXPECT_DOUBLE_EQ(lf.value(2, 2), -4);
}

TEST(BvhParser, ChannelOrderIsApplied) {
  const BvhMotion m = read_bvh(fixture("tiny.bvh"));
  // Spine: "Xrotation Yrotation Zrotation" with 10 20 30 -> Rx Ry Rz.
  const Quat spine = rot('X', 10) * rot('Y', 20) * rot('Z', 30);
  EXPECT_NEAR(m.local_rotation(1, 1).angularDistance(spine), 0, 1e-12);
  // LeftUpLeg: "Zrotation Xrotation Yrotation" with 10 20 30 -> Rz(10) Rx(20) Ry(30).
  const Quat leg = rot('Z', 10) * rot('X', 20) * rot('Y', 30);
  EXPECT_NEAR(m.local_rotation(2, 1).angularDistance(leg), 0, 1e-12);
  // The two orders really differ for the same numbers.
  EXPECT_GT(spine.angularDistance(rot('Z', 10) * rot('X', 20) * rot('Y', 30)), 0.05);
  // Root: Zrotation 90 first; position channels add to the offset.
  EXPECT_NEAR(m.local_rotation(0, 1).angularDistance(rot('Z', 90)), 0, 1e-12);
  EXPECT_NEAR((m.local_translation(0, 1) - Vec3(1.5, 91, -2)).norm(), 0, 1e-12);
  EXPECT_NEAR((m.local_translation(2, 1) - Vec3(8, -5, 0)).norm(), 0, 1e-12);
}

// Position channels add to a non-zero OFFSET, on the root and on a joint with
// its own position channels (some exporters write 6 channels per joint).
// tiny.bvh's root offset is 0, which cannot tell "offset + value" from "value"
// (mutant M23 in scripts/results/mutation.md).
TEST(BvhParser, PositionChannelsAddToANonZeroOffset) {
  const std::string text =
      "HIERARCHY\nROOT Hips\n{\n OFFSET 1 2 3\n CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation "
      "Yrotation\n JOINT Spine\n {\n  OFFSET 0 10 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation "
      "Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 5 0\n  }\n }\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n"
      "10 20 30 0 0 0 0.5 -0.25 2 0 0 0\n";
  const BvhMotion m = parse_bvh(text, "offsets.bvh");
  EXPECT_NEAR((m.local_translation(0, 0) - Vec3(11, 22, 33)).norm(), 0, 1e-12);
  EXPECT_NEAR((m.local_translation(1, 0) - Vec3(0.5, 9.75, 2)).norm(), 0, 1e-12);
}

// Each malformed variant of the tiny file must throw naming the file, the
// line and what was expected.
struct BadCase {
  const char* what;
  std::string from, to;  // textual edit of tiny.bvh
  int line;
  const char* expect;
};

TEST(BvhParser, MalformedInputNamesFileLineAndExpectation) {
  const std::string good = slurp(fixture("tiny.bvh"));
  const std::vector<BadCase> cases = {
      {"channel count", "CHANNELS 3 Xrotation Yrotation Zrotation", "CHANNELS 4 Xrotation Yrotation Zrotation", 10,
       "expected 4 channel names"},
      {"count too big", "CHANNELS 3 Xrotation Yrotation Zrotation", "CHANNELS 9 Xrotation Yrotation Zrotation", 9,
       "expected 0 to 6"},
      {"unknown rotation channel", "CHANNELS 3 Zrotation Yrotation Xrotation", "CHANNELS 3 Zrotation Wrotation Xrotation",
       22, "found 'Wrotation'"},
      {"repeated axis (bad order)", "CHANNELS 3 Zrotation Xrotation Yrotation", "CHANNELS 3 Zrotation Xrotation Zrotation",
       18, "appears twice"},
      {"non-numeric value", "1.5 91 -2 90", "1.5 91 -2 abc", 34, "expected a finite number, found 'abc'"},
      {"nan value", "1.5 91 -2 90", "1.5 91 -2 nan", 34, "expected a finite number"},
      {"short frame", "3 92 -4 0 0 0 0 0 0 0 0 0 0 0 0", "3 92 -4 0 0 0 0 0 0 0 0 0 0 0", 35, "has 14 values, expected 15"},
      {"long frame", "3 92 -4 0 0 0 0 0 0 0 0 0 0 0 0", "3 92 -4 0 0 0 0 0 0 0 0 0 0 0 0 7", 35, "more than the 15"},
      {"truncated motion", "Frames: 3", "Frames: 4", 36, "ends after 3 of 4 frames"},
      {"too few frames declared", "Frames: 3", "Frames: 2", 35, "after the last of the 2"},
      {"missing open brace", "JOINT Spine\n\t{", "JOINT Spine\n\t", 8, "expected '{' after JOINT Spine"},
      {"missing close brace", "\t}\n\tJOINT LeftUpLeg", "\tJOINT LeftUpLeg", 29,
       "'MOTION' while joint 'Hips' opened at line 2 has no closing '}'"},
      {"extra close brace", "}\nMOTION", "}\n}\nMOTION", 30, "unexpected '}'"},
      {"bad offset", "OFFSET 8.0 -5.0 0.0", "OFFSET 8.0 -5.0", 18, "expected an OFFSET coordinate"},
      {"bad frame time", "Frame Time: 0.04", "Frame Time: fast", 32, "expected 'Frame Time' in seconds"},
      {"zero frame time", "Frame Time: 0.04", "Frame Time: 0", 32, "must be positive"},
      {"bad frames", "Frames: 3", "Frames: three", 31, "expected a frame count"},
      {"no hierarchy", "HIERARCHY", "HIERARCH", 1, "expected 'HIERARCHY'"},
  };
  test::TempDir dir;
  for (const auto& c : cases) {
    std::string text = good;
    const size_t at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.what;
    text.replace(at, c.from.size(), c.to);
    for (const std::string eol : {"\n", "\r\n"}) {
      std::string t = eol == "\n" ? text : std::regex_replace(text, std::regex("\n"), "\r\n");
      const std::string path = dir.file("bad.bvh");
      std::ofstream(path, std::ios::binary) << t;
      try {
        read_bvh(path);
        ADD_FAILURE() << c.what << ": no error";
      } catch (const Error& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.rfind(path + ":" + std::to_string(c.line) + ":", 0), 0u) << c.what << ": " << m;
        EXPECT_NE(m.find(c.expect), std::string::npos) << c.what << ": " << m;
      }
    }
  }
  // Empty and truncated-in-hierarchy texts.
  EXPECT_THROW(parse_bvh("", "empty"), Error);
  EXPECT_THROW(parse_bvh(good.substr(0, 200), "cut"), Error);
  EXPECT_THROW(read_bvh(dir.file("missing.bvh")), Error);
}

TEST(BvhParser, HostileInputsFailCleanly) {
  const std::string head = "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n}\nMOTION\n";
  // A frame count the file cannot hold is rejected before allocating for it.
  try {
    parse_bvh(head + "Frames: 99999999\nFrame Time: 0.1\n1\n", "huge");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("huge:8:"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_bvh(head + "Frames: -3\nFrame Time: 0.1\n", "neg"), Error);
  // Labels glued to their values, '+' signs and exponents are fine.
  const BvhMotion m = parse_bvh(head + "Frames:2\nFrame Time:0.5\n+1e1\n-2.5E-1\n", "glued");
  EXPECT_DOUBLE_EQ(m.value(0, 0), 10);
  EXPECT_DOUBLE_EQ(m.value(1, 0), -0.25);
  // Deep nesting is handled without recursion.
  std::string deep = "HIERARCHY\nROOT J\n{\nOFFSET 0 0 0\nCHANNELS 1 Zrotation\n";
  for (int i = 0; i < 20000; ++i) deep += "JOINT J\n{\nOFFSET 0 1 0\n";
  for (int i = 0; i < 20000; ++i) deep += "}\n";
  EXPECT_EQ(parse_bvh(deep + "}\nMOTION\nFrames: 1\nFrame Time: 1\n0\n", "deep").joints.size(), 20001u);
  // Binary junk.
  EXPECT_THROW(parse_bvh(std::string("\x00\xff\x93NUMPY", 8), "junk"), Error);
  EXPECT_THROW(parse_bvh(head + "Frames: 1\nFrame Time: 0.1 extra\n0\n", "extra"), Error);
}

TEST(BvhParser, TenThousandFramesParseTime) {
  // 32 joints x 3 channels = 96 (like CMU): timing printed, not asserted.
  std::string text = "HIERARCHY\nROOT J0\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n";
  for (int j = 1; j < 31; ++j) text += " JOINT J" + std::to_string(j) + "\n {\n OFFSET 0 1 0\n CHANNELS 3 Zrotation Yrotation Xrotation\n";
  text += " End Site\n {\n OFFSET 0 1 0\n }\n";
  for (int j = 1; j < 31; ++j) text += " }\n";
  text += "}\nMOTION\nFrames: 10000\nFrame Time: .0083333\n";
  std::string line;
  for (int c = 0; c < 96; ++c) line += (c % 7 ? "-12.3456 " : "0.1234 ");
  line += "\r\n";
  for (int f = 0; f < 10000; ++f) text += line;
  test::TempDir dir;
  const std::string path = dir.file("big.bvh");
  std::ofstream(path, std::ios::binary) << text;
  Timer timer;
  const BvhMotion m = read_bvh(path);
  const double ms = timer.ms();
  EXPECT_EQ(m.num_frames, 10000);
  EXPECT_EQ(m.num_channels, 96);
  EXPECT_DOUBLE_EQ(m.value(9999, 95), -12.3456);
  std::printf("[ figure ] BVH parse: 10000 frames x 96 channels (%.1f MB) in %.1f ms\n", text.size() / 1e6, ms);
}

}  // namespace
}  // namespace sflsh
