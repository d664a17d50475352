// The contact benchmark on a tiny synthetic body (the quick scenes, scaled to
// an 8 × 12 × 8 cm box): with a complete basis (W = identity) and Newton to
// convergence the reduced model is the full-FEM reference, so rel_err ≈ 0 and
// the dent ratio ≈ 1; with 6 hat handles it is not, and the dent is shallower.
#include <gtest/gtest.h>

#include "sflsh/bench/contact_benchmark.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/progress.hpp"
#include <iostream>
#include "sim/synthetic_avatar.hpp"

namespace sflsh {
namespace {

std::shared_ptr<const Avatar> box(int handles) {
  test::SyntheticAvatarOptions o;
  o.nx = o.nz = 4;
  o.ny = 6;
  o.cell = 0.02;
  o.handles = handles;
  o.handle_radius = 0.1;
  o.two_regions = false;  // lumped node masses use one tet's density: equal to the reference only for one region
  return std::make_shared<const Avatar>(test::make_synthetic_avatar(o));
}

// Disabled until the reduced model's rigid contact samples the skin's faces as
// the full-FEM reference now does (full_fem.hpp): with vertex samples against
// face samples the complete basis no longer reproduces the reference.
TEST(ContactBenchmark, DISABLED_CompleteBasisMatchesTheReferenceAndFewHandlesDentLess) {
  ContactBenchSettings s;
  s.quick = true;
  s.newton_iters = 12;
  s.pressed_radius = 0.03;
  s.pressed_depth = 0.01;
  s.impact_radius = 0.03;
  s.impact_depth = 0.01;
  s.impact_speed = 1.0;
  s.scenes = {"pressed", "impact"};  // the probe needs a body with a thigh (run by sflsh bench-contact)
  // The complete (nodal) basis is full FEM only with every tet's own volume change.
  s.mean_dilatation = false;
  Progress::set_quiet(true);
  const auto rows = run_contact_scenes({box(0), box(6)}, s);
  Progress::set_quiet(false);
  ASSERT_EQ(rows.size(), 4u);
  for (const ContactBenchRow& r : rows) {
    SCOPED_TRACE(r.scene + " K=" + std::to_string(r.handles));
    std::cout << "[ contact bench ] " << r.scene << " K=" << r.handles << " rel_err " << r.rel_err << " dent "
              << r.dent_full_mm << " / " << r.dent_reduced_mm << " mm, force " << r.force_full_n << " / "
              << r.force_reduced_n << " N, active " << r.active_samples << ", " << r.us_per_sample_iter
              << " us/sample/iter, step ratio " << r.step_ratio << "\n";
    EXPECT_GT(r.dent_full_mm, 1.0);  // the sphere goes 1 cm deep
    EXPECT_LT(r.dent_full_mm, 10.0);
    EXPECT_GT(r.force_full_n, 0);
    EXPECT_GT(r.active_samples, 0);
    EXPECT_GT(r.us_per_sample_iter, 0);
    EXPECT_GT(r.step_ratio, 0);
    if (r.handles == 6) {
      EXPECT_GT(r.rel_err, 0.05);
      EXPECT_LT(r.dent_ratio, 0.95);
    } else {
      EXPECT_LT(r.rel_err, 1e-4);
      EXPECT_NEAR(r.dent_ratio, 1.0, 1e-4);
      EXPECT_NEAR(r.force_reduced_n, r.force_full_n, 1e-4 * r.force_full_n);
    }
  }
  EXPECT_EQ(rows[0].scene, "pressed");
  EXPECT_EQ(rows[2].scene, "impact");
  EXPECT_THROW(run_contact_scenes({}, s), Error);
}

}  // namespace
}  // namespace sflsh
