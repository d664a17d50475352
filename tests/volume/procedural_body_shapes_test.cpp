// Figures on the real default body (slow: the template stage takes about a
// minute). Run with --gtest_also_run_disabled_tests; set
// SFLSH_TEMPLATE_CACHE=/some/file.h5 to reuse a template between runs.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>

#include "sflsh/body/procedural_body.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/volume/shape_volume.hpp"
#include "sflsh/volume/template_volume.hpp"

namespace sflsh {
namespace {

TEST(ProceduralBody, DISABLED_ShapesOverBetaRange) {
  const BodyModel m = make_procedural_body();
  const char* cache = std::getenv("SFLSH_TEMPLATE_CACHE");
  TemplateVolume tv;
  if (cache && std::ifstream(cache).good()) {
    tv = load_template_volume(cache);
  } else {
    Timer t;
    tv = build_template_volume(m, TemplateOptions{});
    std::printf("template stage %.1f s\n%s\n", t.seconds(), tv.report.describe().c_str());
    if (cache) save_template_volume(tv, cache);
  }
  const TetQualityReport q0 = tet_quality_report(tv.tet);
  std::printf("template: %d tets, %d nodes, min dihedral %.2f deg\n", q0.num_tets, q0.num_nodes, q0.min_dihedral_deg);
  std::vector<VecX> betas;
  const int B = m.num_betas();
  for (int b = 0; b < std::min(B, 2); ++b)
    for (double v : {-2.0, 2.0}) {
      VecX x = VecX::Zero(B);
      x[b] = v;
      betas.push_back(x);
    }
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-2, 2);
  for (int i = 0; i < 4; ++i) {
    VecX x(B);
    for (int b = 0; b < B; ++b) x[b] = U(rng);
    betas.push_back(x);
  }
  for (const VecX& beta : betas) {
    for (int th = 0; th < 2; ++th) {
      Timer t;
      ShapedVolume s;
      try {
        s = shape_volume(tv, m, beta, th ? ThicknessMap::defaults() : ThicknessMap::uniform());
      } catch (const Error& e) {
        ADD_FAILURE() << e.what();
        continue;
      }
      const auto& sq = s.report.quality;
      std::printf("beta [%s] %s: min dihedral %.2f deg, min volume %.3g m^3, %d below 8 deg, %.2f s\n",
                  [&] { std::string r; for (int b = 0; b < B; ++b) r += (b ? " " : "") + std::to_string(beta[b]).substr(0, 5); return r; }().c_str(),
                  th ? "default thickness" : "uniform", sq.min_dihedral_deg, sq.min_volume, sq.num_below_threshold, t.seconds());
      EXPECT_EQ(sq.num_inverted, 0);
    }
  }
}

}  // namespace
}  // namespace sflsh
