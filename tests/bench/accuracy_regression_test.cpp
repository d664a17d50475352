// Accuracy regression: the reduced simulation against the full-FEM reference
// on the same coarse built-in body (the batch CLI tests' mesh: cell 0.08 m,
// facet 0.06 m, distance 4 mm), K = 24 handles, 1 s of the built-in `jump`,
// bones prescribed, through the bench's own code (run_benchmark: the reference
// Newton to convergence, the skin's soft displacement compared at 30 frames
// per second, rel_err per body region). Each region's rel_err and the overall
// one are pinned to the values measured when this test was written, with room
// for rounding and platform differences (× 1.15 + 0.01): a change that makes
// the reduced model less accurate than that fails here instead of only moving
// a figure in scripts/results/bench*.md.
//
// The head, hand and foot barely move in the reference (their floors exceed
// 1): their rel_err is a ratio of two small numbers, and on another CPU (the
// coarse mesh is built by CGAL on the machine) the foot's went from 1.02 to
// 1.77 while the simulated regions moved by up to 6 %. They are checked
// finite, not pinned; the trunk and limb regions carry the figure. Skinning
// only (u = 0, rel_err 1 everywhere) must exceed the pins of the regions below
// 0.86: the pins can fail.
//
// Measured (2026-11-28, Release, 2 cores, on the template whose topology serves every
// shape: its repairs are designed over 25 shapes) with
//   build/test_bench --gtest_filter='AccuracyRegression.*'
// which prints every region's rel_err (the "[ accuracy ]" lines).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "sflsh/bench/benchmark.hpp"

using namespace sflsh;

namespace {

constexpr double kRelativeRoom = 1.15, kAbsoluteRoom = 0.01;

BenchOptions coarse_jump() {
  BenchOptions o;
  o.quick = true;
  o.peer = false;
  o.motion = "builtin:jump";
  o.seconds = 1.0;
  o.default_handles = 24;
  o.handle_counts = {24};
  o.only = {"(no variant: the reference, the default K and skinning only)"};
  o.precompute.template_stage.mesh.cell_size = 0.08;
  o.precompute.template_stage.mesh.facet_size = 0.06;
  o.precompute.template_stage.mesh.facet_distance = 0.004;
  o.precompute.bbw.show_progress = false;
  return o;
}

const BenchRow* find_row(const std::vector<BenchRow>& rows, const std::string& method) {
  for (const BenchRow& r : rows)
    if (r.method == method) return &r;
  return nullptr;
}

}  // namespace

TEST(AccuracyRegression, ReducedJumpOnACoarseBodyStaysWithinItsPinnedErrorPerRegion) {
  // rel_err measured (see the header); "overall" is the row's rel_err over every simulated skin vertex.
  const std::map<std::string, double> measured = {
      {"overall", 0.3274}, {"torso", 0.3390}, {"belly", 0.2828},     {"chest", 0.2850},
      {"buttocks", 0.3401}, {"thigh", 0.3198}, {"calf", 0.6129},     {"upper_arm", 0.7599},
      {"forearm", 0.8206}, {"neck", 0.7982},
  };
  // Measured 1.6328, 0.9470, 1.0159: reported, checked finite (header).
  const std::vector<std::string> unpinned = {"head", "hand", "foot"};
  // The names whose rel_err in `row` (overall and per region) exceeds its pin.
  auto over_the_pins = [&](const BenchRow& row) {
    std::map<std::string, double> got = {{"overall", row.rel_err}};
    for (const RegionError& g : row.regions) got[g.name] = g.rel_err;
    std::vector<std::string> over;
    for (const auto& [name, value] : measured)
      if (!got.count(name) || !(got[name] <= kRelativeRoom * value + kAbsoluteRoom)) over.push_back(name);
    return over;
  };
  const std::vector<BenchRow> rows = run_benchmark(coarse_jump());
  const BenchRow* reduced = find_row(rows, "reduced");
  const BenchRow* skinning = find_row(rows, "skinning");
  ASSERT_NE(reduced, nullptr);
  ASSERT_NE(skinning, nullptr);
  ASSERT_EQ(rows.size(), 3u) << "the reference, K = 24 and skinning only";
  EXPECT_EQ(reduced->handles, 24);
  // Skinning only (u = 0) is off by exactly the reference's own size: ‖0 − u_ref‖ / ‖u_ref‖ = 1.
  // It checks the comparison itself (a reference that did not move would give NaN or 0 here).
  EXPECT_NEAR(skinning->rel_err, 1.0, 1e-12);
  EXPECT_GT(find_row(rows, "reference")->peak_ratio, 0.0);

  std::printf("[ accuracy ] overall rel_err %.4f (floor %.4f)\n", reduced->rel_err, reduced->floor_rel_err);
  for (const RegionError& g : reduced->regions)
    std::printf("[ accuracy ] %-10s rel_err %.4f (floor %.4f)\n", g.name.c_str(), g.rel_err, g.floor_rel_err);
  for (const std::string& name : over_the_pins(*reduced)) {
    double got = name == "overall" ? reduced->rel_err : NAN;
    for (const RegionError& g : reduced->regions)
      if (g.name == name) got = g.rel_err;
    ADD_FAILURE() << name << ": rel_err " << got << " (NaN: no reference motion) above the pin "
                  << kRelativeRoom * measured.at(name) + kAbsoluteRoom << " (measured " << measured.at(name) << ")";
  }
  EXPECT_EQ(reduced->regions.size() + 1, measured.size() + unpinned.size()) << "regions with reference motion changed";
  for (const RegionError& g : reduced->regions)
    if (std::find(unpinned.begin(), unpinned.end(), g.name) != unpinned.end())
      EXPECT_TRUE(std::isfinite(g.rel_err)) << g.name << ": rel_err " << g.rel_err;
  const std::vector<std::string> skinning_over = over_the_pins(*skinning);
  for (const char* name :
       {"overall", "torso", "belly", "chest", "buttocks", "thigh", "calf", "upper_arm", "forearm", "neck"})
    EXPECT_NE(std::find(skinning_over.begin(), skinning_over.end(), name), skinning_over.end())
        << "skinning only passes the pin of " << name;
}
