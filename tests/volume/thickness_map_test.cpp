#include <gtest/gtest.h>

#include <fstream>

#include "sflsh/core/error.hpp"
#include "sflsh/volume/body_regions.hpp"
#include "sflsh/volume/thickness_map.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

std::string write(const test::TempDir& dir, const std::string& text) {
  const std::string path = dir.file("thickness.txt");
  std::ofstream(path) << text;
  return path;
}

std::string error_of(const std::string& path) {
  try {
    read_thickness_map(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(ThicknessMap, ReadsPairsCommentsAndKeepsDefaults) {
  test::TempDir dir;
  const ThicknessMap m = read_thickness_map(write(dir, "# soft belly\nbelly 1.5\n\n  thigh   0.8  # lean\n"));
  EXPECT_DOUBLE_EQ(m.scale_of("belly"), 1.5);
  EXPECT_DOUBLE_EQ(m.scale_of("thigh"), 0.8);
  EXPECT_DOUBLE_EQ(m.scale_of("buttocks"), ThicknessMap::defaults().scale_of("buttocks"));
  EXPECT_DOUBLE_EQ(m.scale_of("forearm"), 1.0);
}

TEST(ThicknessMap, BadFilesGiveClearErrors) {
  test::TempDir dir;
  std::string e = error_of(write(dir, "belly 1.2\nbely 1.3\n"));
  EXPECT_NE(e.find("thickness.txt:2"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown body region 'bely'"), std::string::npos) << e;
  e = error_of(write(dir, "belly abc\n"));
  EXPECT_NE(e.find(":1: scale 'abc' of region belly is not a number"), std::string::npos) << e;
  e = error_of(write(dir, "belly 1.2x\n"));
  EXPECT_NE(e.find("not a number"), std::string::npos) << e;
  e = error_of(write(dir, "\n\nbelly -1\n"));
  EXPECT_NE(e.find(":3: scale -1 of region belly must be in (0, 3]"), std::string::npos) << e;
  e = error_of(write(dir, "belly nan\n"));
  EXPECT_NE(e.find("must be in (0, 3]"), std::string::npos) << e;
  e = error_of(write(dir, "belly\n"));
  EXPECT_NE(e.find(":1: expected 'region scale'"), std::string::npos) << e;
  e = error_of(write(dir, "belly 1 2\n"));
  EXPECT_NE(e.find("unexpected '2'"), std::string::npos) << e;
  e = error_of(dir.file("missing.txt"));
  EXPECT_NE(e.find("missing.txt: file not found"), std::string::npos) << e;
}

TEST(BodyRegions, NamesMaterialsAndRules) {
  const auto& names = body_region_names();
  const auto mats = default_region_materials();
  ASSERT_EQ(names.size(), mats.size());
  for (size_t i = 0; i < names.size(); ++i) {
    EXPECT_EQ(mats[i].name, names[i]);
    EXPECT_GE(mats[i].young_through, 1e3);
    EXPECT_LE(mats[i].young_along, 2e5);
    EXPECT_DOUBLE_EQ(mats[i].density, 1000.0);
  }
  EXPECT_EQ(names[body_region_of(3, 0.9, 0)], "belly");
  EXPECT_EQ(names[body_region_of(0, -0.9, 0)], "buttocks");
  EXPECT_EQ(names[body_region_of(1, 0.0, -0.3)], "thigh");
  EXPECT_EQ(names[body_region_of(9, 0.8, 0)], "chest");
  EXPECT_EQ(names[body_region_of(18, 0.0, 0)], "forearm");
  EXPECT_TRUE(is_skinned_joint(15));
  EXPECT_FALSE(is_skinned_joint(12));
  EXPECT_THROW(body_region_index("elbow"), Error);
}

}  // namespace
}  // namespace sflsh
