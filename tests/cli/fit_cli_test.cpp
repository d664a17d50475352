// `sflsh fit` end to end on a tiny synthetic avatar: simulate observations with
// known materials, fit them back, and reject bad input with one line, a
// non-zero exit and no output file.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/fit/observations.hpp"
#include "sflsh/scene/material_file.hpp"
#include "fit/fit_fixture.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

int run(const std::string& args, std::string* out) {
  return test::run_command(test::sflsh_binary() + " -q " + args, out);
}

/// Writes `a` to `avatar` and, to `truth`, its materials with each region's three Young's moduli scaled by
/// `young[r]`; returns those materials.
std::vector<RegionMaterial> write_box_and_truth(const Avatar& a, const std::string& avatar, const std::string& truth,
                                                const std::vector<double>& young) {
  write_avatar(a, avatar);
  std::vector<RegionMaterial> t = a.materials;
  for (size_t r = 0; r < young.size(); ++r)
    t[r].scale_young(young[r]);
  write_material_file(truth, t);
  return t;
}

TEST(FitCli, FitsSimulatedObservationsAndRejectsBadInput) {
  test::TempDir dir;
  const Avatar a = test::fit_avatar();
  const std::string avatar = dir.file("box.h5"), truth = dir.file("truth.yaml"), obs = dir.file("obs.h5");
  const std::vector<RegionMaterial> t = write_box_and_truth(a, avatar, truth, {2.0, 0.5});
  std::string out;
  ASSERT_EQ(run("simulate --avatar " + avatar + " --motion builtin:shake --seconds 0.5 --bones kinematic "
                    "--newton-nonlinearity-tol 0 --material " +
                    truth + " --out " + obs, &out),
            0)
      << out;
  const std::string fitted = dir.file("fitted.yaml"), svg = dir.file("fitted_error.svg");
  ASSERT_EQ(run("fit --avatar " + avatar + " --observed " + obs + " --params young --out " + fitted, &out), 0) << out;
  EXPECT_NE(out.find("Ceres Solver Report"), std::string::npos) << out;
  EXPECT_NE(out.find("iter      cost"), std::string::npos) << out;
  ASSERT_TRUE(std::filesystem::exists(svg));
  std::vector<RegionMaterial> back = a.materials;
  apply_material_file(fitted, back);
  for (int r = 0; r < 2; ++r) EXPECT_NEAR(back[r].young_along / t[r].young_along, 1.0, 1e-3) << out;

  // Bad input: one line naming the problem, exit code 1, no output.
  const Points P = a.surface_rest;
  Points nan = P;
  nan(2, 0) = std::nan("");
  test::write_observation_file(dir.file("few.h5"), {0.0, 1.0 / 30}, {P.topRows(5), P.topRows(5)});
  test::write_observation_file(dir.file("back.h5"), {0.0, 1.0 / 30, 1.0 / 60}, {P, P, P});
  test::write_observation_file(dir.file("nan.h5"), {0.0, 1.0 / 30}, {P, nan});
  const std::string common = " --avatar " + avatar + " --out " + dir.file("bad.yaml");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"fit --observed " + dir.file("few.h5") + common, "5 vertices per frame"},
      {"fit --observed " + dir.file("back.h5") + common, "frame times not increasing"},
      {"fit --observed " + dir.file("nan.h5") + common, "vertex 2 has a non-finite position"},
      {"fit --observed " + obs + common + " --regions soft,belly", "unknown region 'belly'"},
      {"fit --observed " + obs + common + " --params young,stiffness", "unknown parameter 'stiffness'"},
      {"fit --observed " + dir.file("none.h5") + common, "not found"},
  };
  for (const auto& [args, fragment] : cases) {
    const int code = run(args, &out);
    EXPECT_EQ(code, 1) << args << "\n" << out;
    EXPECT_NE(out.find(fragment), std::string::npos) << args << "\n" << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << args << "\n" << out;
    EXPECT_FALSE(std::filesystem::exists(dir.file("bad.yaml"))) << args;
    EXPECT_FALSE(std::filesystem::exists(dir.file("bad_error.svg"))) << args;
  }
}

TEST(FitCli, ARunWithDynamicBonesIsFittedWithItsOwnBones) {
  // simulate's default (dynamic bones) with the soft region's moduli doubled:
  // the bones the run took are not the motion's. With the bones the result
  // file holds (/steps/bones), the fit recovers the factor; the same skin
  // without them (prescribing the motion's bones) is off by much more.
  test::TempDir dir;
  const Avatar a = test::fit_avatar();
  const std::string avatar = dir.file("box.h5"), truth = dir.file("truth.yaml"), obs = dir.file("obs.h5");
  write_box_and_truth(a, avatar, truth, {2.0, 1.0});
  std::string out;
  ASSERT_EQ(run("simulate --avatar " + avatar + " --motion builtin:shake --seconds 0.5 --material " + truth +
                    " --out " + obs,
                &out),
            0)
      << out;
  const Observations o = read_observations(obs);
  ASSERT_EQ(o.bones, "dynamic");
  ASSERT_EQ(o.step_bones.size(), 30u);
  const std::string plain = dir.file("plain.h5");
  test::write_observation_file(plain, o.time, o.positions, "builtin:shake");
  auto fitted_factor = [&](const std::string& observed, const std::string& name) {
    const std::string fitted = dir.file(name + ".yaml");
    EXPECT_EQ(run("fit --avatar " + avatar + " --observed " + observed + " --params young --regions soft --out " +
                      fitted,
                  &out),
              0)
        << out;
    std::vector<RegionMaterial> back = a.materials;
    apply_material_file(fitted, back);
    return back[0].young_along / a.materials[0].young_along;
  };
  const double own = fitted_factor(obs, "own");
  EXPECT_NE(out.find("bones: the observed run's own"), std::string::npos) << out;
  const double motion = fitted_factor(plain, "motion");
  EXPECT_EQ(out.find("bones: the observed run's own"), std::string::npos) << out;
  std::cout << "fitted factor (truth 2): own bones " << own << ", the motion's " << motion << "\n";
  EXPECT_NEAR(own, 2.0, 0.04);
  EXPECT_GT(std::abs(motion - 2.0), 3 * std::abs(own - 2.0));
  // The run's bones are per step of its dt: another time step is refused in one line, with no output.
  const std::string bad = dir.file("bad.yaml");
  EXPECT_EQ(run("fit --avatar " + avatar + " --observed " + obs + " --params young --dt 1/120 --out " + bad, &out), 1);
  EXPECT_NE(out.find("its run's bones are per step of 0.0166"), std::string::npos) << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  EXPECT_FALSE(std::filesystem::exists(bad));
}

TEST(FitCli, DatasetMapAndItsMaterialsForANewShape) {
  // Three "shapes" of the tiny box (same mesh, betas -1, 0.5, 1.5) whose
  // Young's factors follow exp(P0 + beta P1); fit the map, evaluate it at beta 2.
  test::TempDir dir;
  const double P0[2] = {0.3, -0.2}, P1[2] = {0.2, -0.15};
  std::string yaml = "subjects:\n", out;
  auto shape = [&](double beta, const std::string& name) {
    Avatar a = test::fit_avatar();
    a.betas = VecX::Constant(1, beta);
    write_avatar(a, dir.file(name + ".h5"));
    return a;
  };
  for (double beta : {-1.0, 0.5, 1.5}) {
    const std::string name = "box" + std::to_string(int(10 * beta));
    const Avatar a = shape(beta, name);
    std::vector<RegionMaterial> t = a.materials;
    for (int r = 0; r < 2; ++r) {
      const double f = std::exp(P0[r] + beta * P1[r]);
      t[r].young_along *= f, t[r].young_through *= f, t[r].young_around *= f;
    }
    write_material_file(dir.file(name + "_truth.yaml"), t);
    ASSERT_EQ(run("simulate --avatar " + dir.file(name + ".h5") + " --motion builtin:shake --seconds 0.4 --bones kinematic "
                  "--newton-nonlinearity-tol 0 --material " + dir.file(name + "_truth.yaml") + " --out " + dir.file(name + "_obs.h5"), &out), 0) << out;
    yaml += "  - {avatar: " + name + ".h5, observed: " + name + "_obs.h5}\n";
  }
  std::ofstream(dir.file("fits.yaml")) << yaml;
  ASSERT_EQ(run("fit --dataset " + dir.file("fits.yaml") + " --params young --regularization 1e-12 --leave-one-out --out " +
                dir.file("map.yaml"), &out), 0) << out;
  EXPECT_NE(out.find("leave-one-out"), std::string::npos) << out;
  const Avatar b2 = shape(2.0, "new");
  ASSERT_EQ(run("fit --map " + dir.file("map.yaml") + " --avatar " + dir.file("new.h5") + " --out " + dir.file("new.yaml"), &out), 0) << out;
  std::vector<RegionMaterial> m = b2.materials;
  apply_material_file(dir.file("new.yaml"), m);
  for (int r = 0; r < 2; ++r)
    EXPECT_NEAR(m[r].young_along / b2.materials[r].young_along, std::exp(P0[r] + 2.0 * P1[r]), 5e-3) << out;
  // A map's parameter for a region the avatar lacks is one clear error.
  std::ofstream(dir.file("bad_map.yaml")) << "parameters:\n  - {name: \"young:belly\", p0: 0, pk: [0]}\n";
  EXPECT_EQ(run("fit --map " + dir.file("bad_map.yaml") + " --avatar " + dir.file("new.h5") + " --out " + dir.file("x.yaml"), &out), 1);
  EXPECT_NE(out.find("region 'belly'"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("x.yaml")));
}

}  // namespace
}  // namespace sflsh
