// Recovery of known parameters with Ceres on a tiny body (seconds), the
// material file round trip, and bad observation input.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "fit_fixture.hpp"
#include "sflsh/fit/material_fit.hpp"
#include "sflsh/fit/observations.hpp"
#include "sflsh/scene/material_file.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

/// Observations simulated with parameters `truth` at every 2nd step.
std::vector<Points> observe(const Avatar& a, const FitParameters& params, const VecX& truth, const BoneSequence& seq,
                            std::vector<int>& steps) {
  steps.clear();
  for (int s = 2; s <= seq.num_steps(); s += 2) steps.push_back(s);
  return simulate_surface(a, params, truth, 0.0, seq, steps, {}, false).surface;
}

TEST(MaterialFit, RecoversYoungAndFungPerRegion) {
  const Avatar a = test::fit_avatar();
  const BoneSequence seq = test::fit_bones(a, 40);
  const FitParameters params(a, "young,fung_c", "all");
  ASSERT_EQ(params.size(), 4);
  VecX truth(4);
  truth << std::log(2.0), std::log(0.5), std::log(0.4), std::log(2.5);  // soft: young, fung_c; firm: young, fung_c
  std::vector<int> steps;
  const std::vector<Points> obs = observe(a, params, truth, seq, steps);
  MaterialFitOptions o;
  o.max_iterations = 30;
  o.function_tolerance = 1e-12;
  const MaterialFitResult r = fit_materials(a, params, seq, steps, obs, o);
  for (int i = 0; i < 4; ++i)
    EXPECT_NEAR(std::exp(r.fitted[i]) / std::exp(truth[i]), 1.0, 1e-3) << r.labels[i] << "\n" << r.brief_report;
  EXPECT_LT(r.rms_after, 1e-3 * r.rms_before);
  EXPECT_LE(r.iterations, 30);
  EXPECT_GT(r.rms_before, 1e-4);  // the defaults are visibly off
  // The fitted materials are the truth's materials.
  const std::vector<RegionMaterial> m = params.materials(a.materials, truth);
  EXPECT_NEAR(r.materials[1].young_along / m[1].young_along, 1.0, 1e-3);
  EXPECT_NEAR(r.materials[0].fung_c / m[0].fung_c, 1.0, 1e-3);
}

TEST(MaterialFit, NumericJacobiansReachTheSameFit) {
  const Avatar a = test::fit_avatar();
  const BoneSequence seq = test::fit_bones(a, 24);
  const FitParameters params(a, "young", "all");
  VecX truth(2);
  truth << std::log(1.5), std::log(0.7);
  std::vector<int> steps;
  const std::vector<Points> obs = observe(a, params, truth, seq, steps);
  MaterialFitOptions o;
  o.numeric = true;
  o.loss = "huber";
  o.function_tolerance = 1e-12;
  const MaterialFitResult r = fit_materials(a, params, seq, steps, obs, o);
  EXPECT_NEAR(r.fitted[0], truth[0], 1e-3);
  EXPECT_NEAR(r.fitted[1], truth[1], 1e-3);
  EXPECT_EQ(r.simulations - r.jacobian_simulations * 2 * params.size() > 0, true);
}

TEST(MaterialFit, UnidentifiedParameterIsReported) {
  // A Fung constant far above any stress the motion makes: saturation never
  // acts, so the skin does not depend on it (its column of J is ~0).
  Avatar a = test::fit_avatar();
  for (RegionMaterial& m : a.materials) m.fung_c = 1e9;
  const BoneSequence seq = test::fit_bones(a, 12);
  const FitParameters params(a, "young,fung_c", "soft");
  std::vector<int> steps;
  VecX truth(2);
  truth << 0.3, 0.0;
  const std::vector<Points> obs = observe(a, params, truth, seq, steps);
  MaterialFitOptions o;
  o.max_iterations = 10;
  const MaterialFitResult r = fit_materials(a, params, seq, steps, obs, o);
  bool warned = false;
  for (const std::string& w : r.warnings)
    warned = warned || (w.find("does not identify fung_c:soft") != std::string::npos && w.find("young") == std::string::npos);
  EXPECT_TRUE(warned) << r.describe();
  EXPECT_NEAR(r.fitted[0], 0.3, 1e-4) << r.describe();  // Young's modulus is still found
}

TEST(MaterialFile, RoundTripOfDistinctValues) {
  test::TempDir dir;
  std::vector<RegionMaterial> m(2);
  m[0].name = "belly";
  m[0].young_along = 12345.678901234567;
  m[0].young_through = 4321.5;
  m[0].young_around = 7777.125;
  m[0].poisson = 0.4321;
  m[0].fung_c = 987.654321;
  m[0].density = 1033.3;
  m[1].name = "thigh";
  m[1].young_along = 3.1e4 / 3;
  m[1].young_through = 2.2e4;
  m[1].young_around = 1.7e4;
  m[1].poisson = 0.31;
  m[1].fung_c = 1.0 / 3 * 1e4;
  m[1].density = 1071;
  const std::string path = dir.file("fitted.yaml");
  write_material_file(path, m, {"fitted by a test"});
  std::vector<RegionMaterial> back(2);
  back[0].name = "belly";
  back[1].name = "thigh";
  apply_material_file(path, back);
  for (int r = 0; r < 2; ++r) {
    EXPECT_EQ(back[r].young_along, m[r].young_along);
    EXPECT_EQ(back[r].young_through, m[r].young_through);
    EXPECT_EQ(back[r].young_around, m[r].young_around);
    EXPECT_EQ(back[r].poisson, m[r].poisson);
    EXPECT_EQ(back[r].fung_c, m[r].fung_c);
    EXPECT_EQ(back[r].density, m[r].density);
  }
  EXPECT_FALSE(std::filesystem::exists(path + ".partial"));
}

TEST(Observations, BadInputIsOneClearError) {
  test::TempDir dir;
  const Points P = Points::Zero(5, 3);
  const std::string ok = dir.file("ok.h5"), back = dir.file("back.h5"), nan = dir.file("nan.h5");
  test::write_observation_file(ok, {0.0, 1.0 / 30}, {P, P});
  test::write_observation_file(back, {0.0, 0.1, 0.1}, {P, P, P});
  Points Q = P;
  Q(3, 1) = std::nan("");
  test::write_observation_file(nan, {0.0, 0.1}, {P, Q});
  const Observations o = read_observations(ok);
  EXPECT_EQ(o.positions.size(), 2u);
  test::expect_error([&] { check_observation_vertices(o, 6, "a.h5"); }, {"5 vertices", "a.h5", "6 surface vertices"});
  test::expect_error([&] { read_observations(back); }, {"back.h5", "not increasing", "frame 2"});
  test::expect_error([&] { read_observations(nan); }, {"nan.h5", "frame 1", "vertex 3", "non-finite"});
  EXPECT_EQ(observation_steps(o, 1.0 / 60), (std::vector<int>{0, 2}));
  test::expect_error([&] { observation_steps(o, 1.0 / 45); }, {"frame 1", "whole number"});
  const Avatar a = test::fit_avatar();
  test::expect_error([&] { FitParameters(a, "young,stiffness", "all"); }, {"unknown parameter 'stiffness'"});
  test::expect_error([&] { FitParameters(a, "young", "belly"); }, {"unknown region 'belly'", "soft, firm"});
}

}  // namespace
}  // namespace sflsh
