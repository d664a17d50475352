// Quality of the shaped tet mesh over the shape space (slow; run explicitly, or through
// scripts/shape_quality_sweep.py, which writes scripts/results/shape_quality.md):
//
//   SFLSH_SWEEP_MODEL=procedural|model.h5  SFLSH_SWEEP_CORNERS=32|all|0  SFLSH_SWEEP_RANDOM=100 \
//   SFLSH_SWEEP_DIRECTIONS=0|1  SFLSH_SWEEP_BETAS=extra.csv  nice build/test_precompute \
//       --gtest_also_run_disabled_tests --gtest_filter='ShapeQualitySweep.*'
//
// Shapes: beta = 0; corners of [-3, 3]^10 (the first 10 betas): every sign pattern of the first
// 4 with the others at +-3 alternating, both phases (32 corners; "all" = all 1024, "0" = none);
// with SFLSH_SWEEP_DIRECTIONS=1 the template stage's design shapes (volume/topology_design.hpp:
// each direction alone at -3 and +3, all -3, all +3, the two alternating corners); uniform random draws in the box
// (seed 2026); and the rows of an optional CSV (`name,b0,b1,...`, e.g. the MakeHuman targets
// from data_tools/makehuman_to_smpl.py --target-betas). Each goes through the shape stage's
// geometry (shape_volume, default thickness map); every one must keep its minimum dihedral angle
// >= 8 deg with no inverted tet, on the template's tets (the same element array for every shape).
// Template stage from the precompute cache. One machine-readable line per shape:
// SWEEP|name|min dihedral deg|inverted|tets below 8 deg|tets|seconds|skin self-intersects (yes/no,
// tested only for shapes below the bar, else -)|same tets as the template (yes/no), or for a
// shape that failed SWEEP|name|failed|-|-|-|seconds|skin self-intersects|error. First a line
// SWEEP-TEMPLATE|tets|nodes|topology hash|template stage seconds (0 if cached)|design report.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/precompute/precompute.hpp"
#include "sflsh/volume/body_regions.hpp"
#include "sflsh/mesh/tet_topology_hash.hpp"
#include "sflsh/volume/shape_volume.hpp"
#include "sflsh/volume/topology_design.hpp"

namespace sflsh {
namespace {

int env_int(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::atoi(v) : fallback;
}

TEST(ShapeQualitySweep, DISABLED_CornersRandomDrawsAndListedShapes) {
  const char* model_env = std::getenv("SFLSH_SWEEP_MODEL");
  const BodyModel model = load_body_model(model_env && *model_env ? model_env : "procedural");
  PrecomputeOptions po;
  po.cache_dir = default_cache_dir();
  PrecomputeReport pr;
  const TemplateVolume tv = cached_template_volume(model, po, &pr);
  std::string design = tv.report.describe();  // the template report (empty when loaded from the cache)
  for (char& c : design)
    if (c == '|' || c == '\n') c = ' ';
  std::printf("SWEEP-TEMPLATE|%d|%d|%s|%.1f|%s\n", tv.tet.num_elements(), tv.tet.num_nodes(),
              tet_topology_hash(tv.tet.elements).c_str(), pr.template_from_cache ? 0.0 : pr.template_s,
              pr.template_from_cache ? "(loaded from the cache)" : design.c_str());
  const int B = model.num_betas(), D = std::min(B, 10);
  const double range = 3.0;

  std::vector<std::pair<std::string, VecX>> shapes;
  shapes.emplace_back("zero", VecX::Zero(B));
  // Corners: every sign pattern of the first 4 components, the other components at +-3
  // alternating (starting with + and with -): 32 corners, including the ones that stack the
  // extremes of the leading directions. SFLSH_SWEEP_CORNERS=all takes all 2^D corners.
  const char* corner_env = std::getenv("SFLSH_SWEEP_CORNERS");
  const bool all_corners = corner_env && std::string(corner_env) == "all";
  const bool no_corners = corner_env && std::string(corner_env) == "0";
  const int lead = std::min(D, 4);
  int corners = 0;
  if (!no_corners) {
    const int count = all_corners ? (1 << D) : (1 << lead) * (D > lead ? 2 : 1);
    for (int id = 0; id < count; ++id) {
      VecX b = VecX::Zero(B);
      std::string name = "corner ";
      for (int d = 0; d < D; ++d) {
        const bool plus = all_corners || d < lead ? (id >> d & 1) : ((d - lead + (id >> lead)) % 2 == 0);
        b[d] = plus ? range : -range;
        name += plus ? '+' : '-';
      }
      shapes.emplace_back(name, b);
      ++corners;
    }
  }
  // The template stage's design shapes but zero (SFLSH_SWEEP_DIRECTIONS=1).
  if (env_int("SFLSH_SWEEP_DIRECTIONS", 0)) {
    TopologyDesignOptions design_options;
    design_options.range = range;
    for (const auto& shape : topology_design_shapes(B, design_options))
      if (shape.first != "zero") shapes.push_back(shape);
  }
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> U(-range, range);
  for (int i = 0, n = env_int("SFLSH_SWEEP_RANDOM", 100); i < n; ++i) {
    VecX b = VecX::Zero(B);
    for (int d = 0; d < D; ++d) b[d] = U(rng);
    shapes.emplace_back("random " + std::to_string(i), b);
  }
  if (const char* csv = std::getenv("SFLSH_SWEEP_BETAS"); csv && *csv) {
    std::ifstream in(csv);
    ASSERT_TRUE(in.good()) << csv;
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
      std::istringstream ls(line);
      std::string name, tok;
      std::getline(ls, name, ',');
      std::vector<double> v;
      while (std::getline(ls, tok, ',')) v.push_back(std::stod(tok));
      shapes.emplace_back(name, Eigen::Map<VecX>(v.data(), v.size()).head(std::min<int>(v.size(), B)));
    }
  }

  std::printf("SWEEP-TOTAL|%zu\n", shapes.size());  // for the driver's progress line
  std::fflush(stdout);
  double worst = 180, worst_before = 180, total_s = 0;
  std::string worst_name;
  int failed = 0, max_moved = 0;
  for (const auto& [name, betas] : shapes) {
    Timer t;
    try {
      const ShapedVolume s = shape_volume(tv, model, betas, ThicknessMap::defaults());
      const TetQualityReport& q = s.report.quality;
      const double sec = t.seconds();
      total_s += sec;
      const int si = s.report.skin_self_intersects;
      const bool same_tets = s.avatar.tet.elements == tv.tet.elements;
      std::printf("SWEEP|%s|%.3f|%d|%d|%d|%.2f|%s|%s\n", name.c_str(), q.min_dihedral_deg, q.num_inverted,
                  q.num_below_threshold, s.avatar.tet.num_elements(), sec, si < 0 ? "-" : si ? "yes" : "no",
                  same_tets ? "yes" : "no");
      EXPECT_TRUE(same_tets) << name << ": the shape stage changed the tets";
      std::fflush(stdout);
      std::printf("%-24s min dihedral %6.3f deg (before the interior optimization %6.3f), %d below 8, %d inverted, "
                  "%d nodes moved, %d tets below target on fixed nodes only, %d skin nodes slid (max %.2f mm), %.2f s\n",
                  name.c_str(), q.min_dihedral_deg, s.report.smoothing.min_dihedral_before, q.num_below_threshold,
                  q.num_inverted, s.report.smoothing.nodes_moved, s.report.smoothing.below_target_all_fixed,
                  s.report.skin_smoothing.nodes_moved, s.report.skin_smoothing.max_displacement * 1e3, sec);
      if (q.num_below_threshold > 0) {  // where the remaining bad tets are
        std::map<std::string, int> where;
        std::vector<char> outer(tv.tet.num_nodes(), 0);
        for (int i = 0; i < tv.outer_nodes.size(); ++i) outer[tv.outer_nodes[i]] = 1;
        const Tets& T = s.avatar.tet.elements;
        std::map<std::array<int, 3>, int> face_uses;
        auto face = [&](int t, int skip) {
          std::array<int, 3> f;
          for (int i = 0, j = 0; i < 4; ++i)
            if (i != skip) f[size_t(j++)] = T(t, i);
          std::sort(f.begin(), f.end());
          return f;
        };
        std::vector<int> node_tets(size_t(s.avatar.tet.num_nodes()), 0);
        for (int t = 0; t < T.rows(); ++t)
          for (int k = 0; k < 4; ++k) ++face_uses[face(t, k)], ++node_tets[size_t(T(t, k))];
        for (int t = 0; t < s.avatar.tet.num_elements(); ++t) {
          if (tet_quality(s.avatar.tet, t).min_dihedral_deg >= 8.0) continue;
          int boundary = 0;
          for (int k = 0; k < 4; ++k) boundary += face_uses[face(t, k)] == 1;
          int skin = 0, simulated = 0;
          for (int i = 0; i < 4; ++i) {
            skin += outer[s.avatar.tet.elements(t, i)];
            simulated += s.avatar.node_role[s.avatar.tet.elements(t, i)] == int(NodeRole::Simulated);
          }
          std::string apex;  // an ear's apex: the node its three boundary faces share
          if (boundary == 3)
            for (int k = 0; k < 4; ++k)
              if (face_uses[face(t, k)] != 1)
                apex = " (apex node in " + std::to_string(node_tets[size_t(T(t, k))]) + " tets)";
          ++where[body_region_names()[s.avatar.tet_region[t]] + (simulated ? " simulated" : " dirichlet-only") +
                  ", " + std::to_string(skin) + " skin nodes, " + std::to_string(boundary) + " boundary faces" + apex];
        }
        for (const auto& [k, n] : where) std::printf("    below 8 deg: %d tets in %s\n", n, k.c_str());
      }
      std::fflush(stdout);
      if (q.min_dihedral_deg < worst) worst = q.min_dihedral_deg, worst_name = name;
      worst_before = std::min(worst_before, s.report.smoothing.min_dihedral_before);
      max_moved = std::max(max_moved, s.report.smoothing.nodes_moved);
      const bool ok = q.min_dihedral_deg >= 8.0 && q.num_inverted == 0;
      failed += !ok;
      EXPECT_TRUE(ok) << name << ": min dihedral " << q.min_dihedral_deg << ", " << q.num_inverted << " inverted";
    } catch (const Error& e) {
      std::string why = e.what();  // one line for the table
      for (char& c : why)
        if (c == '|' || c == '\n') c = ' ';
      const bool si = why.find("skin self-intersects") != std::string::npos;
      std::printf("SWEEP|%s|failed|-|-|-|%.2f|%s|%s\n", name.c_str(), t.seconds(), si ? "yes" : "-",
                  why.substr(0, 240).c_str());
      std::fflush(stdout);
      ++failed;
      ADD_FAILURE() << name << ": " << e.what();
    }
  }
  std::printf("%s: %zu shapes (%d corners of [-3,3]^%d), worst min dihedral %.3f deg (%s; %.3f before the interior "
              "optimization), %d failed, at most %d nodes moved, %.1f s per shape\n",
              model.source.c_str(), shapes.size(), corners, D, worst, worst_name.c_str(), worst_before, failed,
              max_moved, total_s / std::max<size_t>(1, shapes.size()));
}

}  // namespace
}  // namespace sflsh
