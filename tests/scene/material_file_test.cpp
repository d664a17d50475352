// The material file's keys, each checked against the field it must set
// (mutation check M50/M51, scripts/results/mutation.md).
#include <gtest/gtest.h>

#include <vector>

#include "sflsh/scene/material_file.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

TEST(MaterialFile, EachKeySetsItsOwnFieldAndYoungSetsAllThreeModuli) {
  std::vector<RegionMaterial> m(2);
  m[0].name = "belly";
  m[1].name = "thigh";
  // Distinct values per key, so a key written to the wrong field shows.
  apply_material_text(
      "regions:\n"
      "  belly: {young_along: 1.25e4, young_through: 2.5e4, young_around: 5.0e4, poisson: 0.375,"
      " fung_c: 3.0e3, density: 1125}\n"
      "  thigh: {young: 7.5e3}\n",
      "m.yaml", m);
  EXPECT_EQ(m[0].young_along, 1.25e4);
  EXPECT_EQ(m[0].young_through, 2.5e4);
  EXPECT_EQ(m[0].young_around, 5.0e4);
  EXPECT_EQ(m[0].poisson, 0.375);
  EXPECT_EQ(m[0].fung_c, 3.0e3);
  EXPECT_EQ(m[0].density, 1125);
  // 'young' is the isotropic shorthand: all three moduli.
  EXPECT_EQ(m[1].young_along, 7.5e3);
  EXPECT_EQ(m[1].young_through, 7.5e3);
  EXPECT_EQ(m[1].young_around, 7.5e3);
}

}  // namespace
}  // namespace sflsh
