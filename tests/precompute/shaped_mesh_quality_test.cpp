// Shaped-mesh quality on a few extreme shapes (fast; the full sweep over the shape space is
// scripts/shape_quality_sweep.py): the shape stage's geometry (shape_volume, default thickness
// map) on a coarse mesh must keep every tet's smallest dihedral angle >= 8 deg with none
// inverted, on the template's tets (one connectivity for every shape, seed §4: the element
// array, the regions and the node count of every shape are the template's).
// Procedural body: beta = 0, the all -3 and all +3 corners of [-3, 3]^10 and two mixed ones.
// MakeHuman body (skips when ../shared/data/makehuman is absent): the two targets whose folds
// the pipeline could not undo before (male maximum weight: skin caps turned inside out under
// the arm and at the crotch; male minimum muscle: node paths folded in the legs) and the
// minimum height (calves shortened by decimetres).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "../test_support.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/meshing/surface_checks.hpp"
#include "sflsh/precompute/precompute.hpp"
#include "sflsh/volume/shape_volume.hpp"

using namespace sflsh;

namespace {

PrecomputeOptions coarse() {
  PrecomputeOptions o;  // the coarse mesh of the other precompute tests
  o.template_stage.mesh.cell_size = 0.08;
  o.template_stage.mesh.facet_size = 0.06;
  o.template_stage.mesh.facet_distance = 0.004;
  o.bbw.show_progress = false;
  return o;
}

/// The MakeHuman base human converted (data_tools/makehuman_to_smpl.py) into `dir`.
BodyModel makehuman_model(const std::string& folder, const test::TempDir& dir) {
  std::string log;
  const int rc = test::run_command("/usr/bin/python3 " + test::source_dir() + "/data_tools/makehuman_to_smpl.py " +
                                       folder + " " + dir.file("mh.h5"),
                                   &log);
  require(rc == 0, "makehuman_to_smpl.py failed: ", log);
  return load_body_model(dir.file("mh.h5"));
}

// Every avatar node carries its template node's fields, every node is in a tet, and the tets,
// regions and skin nodes are the template's.
void expect_template_topology_and_fields(const TemplateVolume& tv, const ShapedVolume& s, const std::string& name) {
  const Avatar& a = s.avatar;
  ASSERT_EQ(a.tet.num_nodes(), tv.tet.num_nodes()) << name;
  EXPECT_TRUE(a.tet.elements == tv.tet.elements) << name << ": the shape changed the connectivity";
  EXPECT_TRUE(a.tet_region == tv.tet_region) << name;
  EXPECT_TRUE(a.surface_nodes == tv.outer_nodes) << name;
  EXPECT_TRUE(a.node_weights == tv.node_weights) << name;
  EXPECT_TRUE(a.node_role == tv.node_role) << name;
  std::vector<int> uses(a.tet.num_nodes(), 0);
  for (int t = 0; t < a.tet.num_elements(); ++t)
    for (int c = 0; c < 4; ++c) ++uses[a.tet.elements(t, c)];
  EXPECT_EQ(std::count(uses.begin(), uses.end(), 0), 0) << name;
  EXPECT_EQ(s.node_depth.size(), a.tet.num_nodes()) << name;
}

void expect_quality(const TemplateVolume& tv, const BodyModel& model, const std::string& name, const VecX& betas) {
  const ShapedVolume s = shape_volume(tv, model, betas, ThicknessMap::defaults());
  const TetQualityReport& q = s.report.quality;
  std::printf("%s: min dihedral %.3f deg, %d inverted, %d tets, %.1f s\n", name.c_str(), q.min_dihedral_deg,
              q.num_inverted, s.avatar.tet.num_elements(), s.report.seconds);
  EXPECT_GE(q.min_dihedral_deg, 8.0) << name;
  EXPECT_EQ(q.num_inverted, 0) << name;
  expect_template_topology_and_fields(tv, s, name);
}

TEST(ShapedMeshQuality, ProceduralBodyExtremeCorners) {
  const BodyModel model = load_body_model("procedural");
  const TemplateVolume tv = cached_template_volume(model, coarse());
  std::printf("%s\n", tv.report.topology.describe().c_str());
  const int B = model.num_betas(), D = std::min(B, 10);
  VecX lo = VecX::Zero(B), hi = VecX::Zero(B), alt = VecX::Zero(B), alt2 = VecX::Zero(B);
  for (int d = 0; d < D; ++d) {
    lo[d] = -3, hi[d] = 3;
    alt[d] = d % 2 ? -3 : 3, alt2[d] = d % 2 ? 3 : -3;
  }
  expect_quality(tv, model, "zero", VecX::Zero(B));
  expect_quality(tv, model, "all -3", lo);
  expect_quality(tv, model, "all +3", hi);
  expect_quality(tv, model, "+-+-...", alt);
  expect_quality(tv, model, "-+-+...", alt2);
}

TEST(ShapedMeshQuality, MakeHumanHardestTargets) {
  const std::string folder = test::shared_data("makehuman");
  if (folder.empty()) GTEST_SKIP() << "../shared/data/makehuman is absent (the MakeHuman base human); skipping";
  test::TempDir dir;
  const BodyModel model = makehuman_model(folder, dir);
  const TemplateVolume tv = cached_template_volume(model, coarse());
  const int B = model.num_betas();
  // Rows of makehuman_to_smpl.py --target-betas (beta = +-3 in the directions that make the target).
  auto betas = [&](std::vector<double> v) {
    VecX b = VecX::Zero(B);
    for (int i = 0; i < std::min<int>(B, v.size()); ++i) b[i] = v[i];
    return b;
  };
  expect_quality(tv, model, "male max weight", betas({3, 0, 0, -3, 0, 3, 0, -3, 0, 0}));
  expect_quality(tv, model, "male min muscle", betas({0, -3, 0, 0, 3, 0, 3, 0, -3, 0}));
  expect_quality(tv, model, "min height", betas({0, 0, -3, 0, 0, 0, 0, 0, 0, 3}));

  // A corner past every target: 0.94 m tall at max weight and muscle. The model's own skin
  // self-intersects there (CGAL on the shaped surface, independently of the shape stage), so
  // no mesh bounded by it can be valid; the shape stage must say so rather than only "inverted".
  const VecX corner = betas({3, 3, -3, 3, 3, -3, 3, -3, 3, -3});
  ASSERT_TRUE(check_surface(shape_vertices(model, corner), model.faces, true).self_intersects);
  try {
    const ShapedVolume s = shape_volume(tv, model, corner, ThicknessMap::defaults());
    ASSERT_TRUE(s.report.quality.num_inverted == 0 && s.report.quality.min_dihedral_deg < 8.0)
        << "this corner was expected below the bar on the coarse mesh (min dihedral "
        << s.report.quality.min_dihedral_deg << ")";
    EXPECT_EQ(s.report.skin_self_intersects, 1);
    EXPECT_NE(s.report.describe().find("the shaped skin self-intersects"), std::string::npos);
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("the shaped skin self-intersects at these betas"), std::string::npos)
        << e.what();
  }
}

// Two stacked MakeHuman corners with a valid skin that needed, on the full-size mesh, a flattened
// skin ear removed (with its apex node) and two tets on a needle skin triangle flipped (its skin
// edge) while those repairs were made per shape. On the template's one connectivity,
// --++-+-+-+ meets the bar and keeps the template's tets and every node its template fields.
// -+---+-+-+ does not meet it on one topology: its needle skin triangle (torso) needs a skin edge
// flip that no design shape asks for (it is not one of them); measured 6.149 deg in one template
// build and 1 inverted tet in another (the full-size MakeHuman mesh varies between builds: CGAL's
// sliver perturbation stops at its time limit). The fixed point (one topology) is kept; this
// corner is printed, not held to the bar.
TEST(ShapedMeshQuality, MakeHumanCornersThatNeededAnEarRemovedOrASkinEdgeFlipped) {
  const std::string folder = test::shared_data("makehuman");
  if (folder.empty()) GTEST_SKIP() << "../shared/data/makehuman is absent (the MakeHuman base human); skipping";
  test::TempDir dir;
  const BodyModel model = makehuman_model(folder, dir);
  PrecomputeOptions full;
  full.bbw.show_progress = false;
  const TemplateVolume tv = cached_template_volume(model, full);
  std::printf("%s\n", tv.report.topology.describe().c_str());
  auto corner = [&](const std::string& signs) {
    VecX b = VecX::Zero(model.num_betas());
    for (int i = 0; i < int(signs.size()) && i < b.size(); ++i) b[i] = signs[size_t(i)] == '+' ? 3 : -3;
    return b;
  };
  const ShapedVolume s = shape_volume(tv, model, corner("--++-+-+-+"), ThicknessMap::defaults());
  std::printf("--++-+-+-+: %s\n", s.report.describe().c_str());
  EXPECT_GE(s.report.quality.min_dihedral_deg, 8.0);
  EXPECT_EQ(s.report.quality.num_inverted, 0);
  expect_template_topology_and_fields(tv, s, "--++-+-+-+");
  try {
    const ShapedVolume below = shape_volume(tv, model, corner("-+---+-+-+"), ThicknessMap::defaults());
    std::printf("-+---+-+-+ (below the bar on one topology): %s\n", below.report.describe().c_str());
    expect_template_topology_and_fields(tv, below, "-+---+-+-+");
  } catch (const Error& e) {
    std::printf("-+---+-+-+ (below the bar on one topology): %s\n", e.what());
    EXPECT_NE(std::string(e.what()).find("tets inverted for this shape"), std::string::npos) << e.what();
  }
}

}  // namespace
