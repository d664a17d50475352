// The contact benchmark on a tiny synthetic body (the quick scenes, scaled to
// an 8 × 12 × 8 cm box): with a complete basis (W = identity), the same face
// quadrature of the contact and Newton to convergence the reduced model is the
// full-FEM reference, so rel_err ≈ 0 and the dent ratio ≈ 1; with 6 hat
// handles it is not, and the dent is shallower; the contact patch brings it back.
#include <gtest/gtest.h>

#include "sflsh/bench/contact_benchmark.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/progress.hpp"
#include <cmath>
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

TEST(ContactBenchmark, CompleteBasisMatchesTheReferenceAndThePatchDentsLikeIt) {
  ContactBenchSettings s;
  s.quick = true;
  s.newton_iters = 12;
  s.pressed_radius = 0.03;
  s.pressed_depth = 0.01;
  s.impact_radius = 0.03;
  s.impact_depth = 0.01;
  s.impact_speed = 1.0;
  s.spacing = 0.004;
  s.scenes = {"pressed", "impact"};  // the probes need a body with a thigh and a calf (run by sflsh bench-contact)
  // The complete (nodal) basis is full FEM only with every tet's own volume change.
  s.mean_dilatation = false;
  Progress::set_quiet(true);
  // The complete basis without a patch (a patch would duplicate its DoFs), and
  // 6 hat handles with and without one.
  ContactBenchSettings no_patch = s;
  no_patch.patch = false;
  const auto complete = run_contact_scenes({box(0)}, no_patch);
  const auto subspace = run_contact_scenes({box(6)}, no_patch);
  const auto patched = run_contact_scenes({box(6)}, s);
  Progress::set_quiet(false);
  ASSERT_EQ(complete.size(), 2u);
  ASSERT_EQ(subspace.size(), 2u);
  ASSERT_EQ(patched.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    for (const ContactBenchRow* r : {&complete[i], &subspace[i], &patched[i]}) {
      std::cout << "[ contact bench ] " << r->scene << " K=" << r->handles << (r == &patched[i] ? " patch" : "")
                << " rel_err " << r->rel_err << " dent " << r->dent_full_mm << " / " << r->dent_reduced_mm
                << " mm, force " << r->force_full_n << " / " << r->force_reduced_n << " N, active "
                << r->active_samples << ", patch nodes " << r->max_patch_nodes << "\n";
      EXPECT_GT(r->dent_full_mm, 1.0);  // the sphere goes 1 cm deep
      EXPECT_LT(r->dent_full_mm, 12.0);
      EXPECT_GT(r->force_full_n, 0);
      EXPECT_GT(r->active_samples, 0);
      EXPECT_GT(r->step_ratio, 0);
    }
    SCOPED_TRACE(complete[i].scene);
    // Same discretization, same contact quadrature: the reference itself.
    EXPECT_LT(complete[i].rel_err, 1e-4);
    EXPECT_NEAR(complete[i].dent_ratio, 1.0, 1e-4);
    EXPECT_NEAR(complete[i].force_reduced_n, complete[i].force_full_n, 1e-4 * complete[i].force_full_n);
    // Six handles alone dent less; the patch under the sphere dents like the reference.
    EXPECT_GT(subspace[i].rel_err, 0.05);
    EXPECT_LT(subspace[i].dent_ratio, 0.95);
    EXPECT_GT(patched[i].max_patch_nodes, 0);
    EXPECT_LT(std::abs(patched[i].dent_ratio - 1.0), std::abs(subspace[i].dent_ratio - 1.0));
    EXPECT_LT(patched[i].rel_err, subspace[i].rel_err);
    const auto force_error = [](const ContactBenchRow& r) { return std::abs(r.force_reduced_n / r.force_full_n - 1); };
    EXPECT_LT(force_error(patched[i]), 0.25 * force_error(subspace[i]));
  }
  EXPECT_EQ(complete[0].scene, "pressed");
  EXPECT_EQ(complete[1].scene, "impact");
  EXPECT_THROW(run_contact_scenes({}, s), Error);
}

}  // namespace
}  // namespace sflsh
