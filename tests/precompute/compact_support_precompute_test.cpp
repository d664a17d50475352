// Compact-support weights on the real pipeline (built-in body, coarse mesh):
// the radius bounds every handle's support and shrinks the handles each
// cubature sample sees, and a handle count below the simulated regions is
// refused before any weight is solved.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "sflsh/basis/sample_handles.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/precompute/precompute.hpp"

using namespace sflsh;

namespace {

PrecomputeOptions coarse(int K) {
  PrecomputeOptions o;  // same mesh criteria as soft_coverage_test.cpp
  o.template_stage.mesh.cell_size = 0.08;
  o.template_stage.mesh.facet_size = 0.06;
  o.template_stage.mesh.facet_distance = 0.004;
  o.handles = K;
  o.bbw.show_progress = false;
  o.fit_elastic_cubature = false;
  return o;
}

TEST(CompactSupportPrecompute, RadiusBoundsTheSupportsAndTheHandlesPerSample) {
  const BodyModel model = load_body_model("procedural");
  PrecomputeOptions o = coarse(48);
  PrecomputeReport rep_full, rep;
  const TemplateVolume tv = cached_template_volume(model, o, &rep_full);
  const Avatar full = precompute_shape(tv, model, VecX(), o, &rep_full);
  o.bbw.support_radius = 0.12;
  const Avatar compact = precompute_shape(tv, model, VecX(), o, &rep);
  std::printf("handles per elastic sample: unrestricted mean %.2f max %d; radius 0.12 m mean %.2f max %d\n",
              rep_full.elastic_handles.mean, rep_full.elastic_handles.max, rep.elastic_handles.mean,
              rep.elastic_handles.max);
  // Every weight lies within 0.12 m of its handle (a path along the edges is
  // never shorter than the straight line).
  for (int i = 0; i < compact.W.outerSize(); ++i)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(compact.W, i); it; ++it) {
      ASSERT_GE(it.value(), 0.0);
      ASSERT_LE(it.value(), 1.0);
      const double d = (compact.tet.nodes.row(i) - compact.handles.row(it.col())).norm();
      ASSERT_LE(d, 0.12 + 1e-9) << "node " << i << " handle " << it.col();
    }
  EXPECT_LT(compact.W.nonZeros(), full.W.nonZeros());
  EXPECT_LT(rep.elastic_handles.mean, rep_full.elastic_handles.mean);
  EXPECT_EQ(rep.elastic_handles.mean,
            basis::handles_per_sample(compact.tet, compact.W, compact.node_role, compact.elastic).mean);
  EXPECT_EQ(rep.bbw_report.support_radius, 0.12);

  // Fewer handles than simulated regions (9 on the built-in body): refused;
  // as many as there are is accepted.
  PrecomputeOptions enough = coarse(9);
  enough.bbw.support_radius = 0.12;
  EXPECT_NO_THROW(precompute_shape(tv, model, VecX(), enough));
  PrecomputeOptions few = coarse(8);
  few.placement.min_per_region = 0;
  few.bbw.support_radius = 0.12;
  try {
    precompute_shape(tv, model, VecX(), few);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    // torso, belly, chest, buttocks, thigh, calf, upper arm, forearm, neck.
    EXPECT_NE(std::string(e.what()).find("below the 9 simulated regions"), std::string::npos) << e.what();
  }
  few.bbw.support_radius = -1.0;
  EXPECT_THROW(precompute_shape(tv, model, VecX(), few), Error);
}

}  // namespace
