// RegionMaterial::scale_young: the one place that scales a region's stiffness
// (the fit's parameters, the shape map, the sensitivities use it).
#include <gtest/gtest.h>

#include "sflsh/asset/avatar.hpp"

namespace sflsh {
namespace {

TEST(RegionMaterial, ScaleYoungMultipliesTheThreeModuliAndNothingElse) {
  RegionMaterial m{"thigh", 3.5e4, 1.25e4, 2.75e4, 0.43, 2.5e3, 1050.0};
  m.scale_young(2.0);
  EXPECT_EQ(m.young_along, 7.0e4);
  EXPECT_EQ(m.young_through, 2.5e4);
  EXPECT_EQ(m.young_around, 5.5e4);
  EXPECT_EQ(m.poisson, 0.43);
  EXPECT_EQ(m.fung_c, 2.5e3);
  EXPECT_EQ(m.density, 1050.0);
  EXPECT_EQ(m.name, "thigh");
}

}  // namespace
}  // namespace sflsh
