// Parameters as a function of shape: a joint fit over subjects recovers a
// known linear map p(β) = P0 + β P1, leave-one-out errors, map file round trip.
#include <gtest/gtest.h>

#include <cmath>

#include "fit_fixture.hpp"
#include "sflsh/fit/shape_map.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

TEST(ShapeMap, JointFitRecoversALinearMapAndLeaveOneOutPredicts) {
  const Avatar base = test::fit_avatar();
  const FitParameters params(base, "young", "all");
  VecX P0(2), P1(2);
  P0 << std::log(1.5), std::log(0.8);
  P1 << 0.2, -0.3;
  std::vector<FitSubject> subjects;
  for (double beta : {-1.0, 0.5, 1.5}) {
    auto a = std::make_shared<Avatar>(base);
    a->betas = VecX::Constant(1, beta);
    FitSubject s;
    s.name = "beta " + std::to_string(beta);
    s.avatar = a;
    s.bones = test::fit_bones(*a, 24);
    for (int k = 2; k <= 24; k += 2) s.steps.push_back(k);
    s.observed = simulate_surface(*a, params, P0 + beta * P1, 0.0, s.bones, s.steps, {}, false).surface;
    subjects.push_back(std::move(s));
  }
  MaterialFitOptions o;
  o.function_tolerance = 1e-12;
  const ShapeMapResult r = fit_shape_map(subjects, params, o, 1e-12, true);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(r.map.p0[i], P0[i], 1e-3) << r.describe(subjects);
    EXPECT_NEAR(r.map.pk(i, 0), P1[i], 1e-3) << r.describe(subjects);
  }
  ASSERT_EQ(r.rms_leave_one_out.size(), 3u);
  for (int s = 0; s < 3; ++s) {
    EXPECT_GT(r.rms_before[s], 1e-4);
    EXPECT_LT(r.rms_after[s], 1e-3 * r.rms_before[s]);
    EXPECT_LT(r.rms_leave_one_out[s], 1e-2 * r.rms_before[s]) << r.describe(subjects);
  }

  // The map file round trip, and the materials it gives a new shape.
  test::TempDir dir;
  write_shape_map(dir.file("map.yaml"), r.map, {"test"});
  const ShapeMap back = read_shape_map(dir.file("map.yaml"));
  EXPECT_EQ(back.labels, r.map.labels);
  EXPECT_EQ(back.p0, r.map.p0);
  EXPECT_EQ(back.pk, r.map.pk);
  const std::vector<RegionMaterial> m = shape_map_materials(back, base, VecX::Constant(1, 2.0), 0.0);
  EXPECT_NEAR(m[0].young_along / base.materials[0].young_along, std::exp(P0[0] + 2 * P1[0]), 2e-3);
  EXPECT_NEAR(m[1].young_around / base.materials[1].young_around, std::exp(P0[1] + 2 * P1[1]), 2e-3);
  test::expect_error([&] { back.evaluate(VecX::Constant(2, 1.0)); }, {"betas[1]", "1 shape terms"});
}

}  // namespace
}  // namespace sflsh
