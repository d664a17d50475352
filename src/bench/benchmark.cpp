// The benchmark's variants: the reduced simulator at each handle count, time
// step, Newton setting, cubature and basis, the Bullet peer and skinning alone,
// each a row measured against one full-FEM reference; plus the floors of
// candidate bases that are not simulated.
#include "bench/benchmark_internal.hpp"

namespace sflsh {
namespace {

using namespace bench_internal;

/// The options with their defaults filled in: seconds, the handle counts
/// (sorted, with the default count among them).
BenchOptions with_defaults(const BenchOptions& in) {
  BenchOptions o = in;
  if (o.seconds <= 0) o.seconds = o.quick ? 0.5 : 2.0;
  if (o.handle_counts.empty()) o.handle_counts = o.quick ? std::vector<int>{16} : std::vector<int>{16, 32, 64, 128};
  if (std::find(o.handle_counts.begin(), o.handle_counts.end(), o.default_handles) == o.handle_counts.end())
    o.handle_counts.push_back(o.default_handles);
  std::sort(o.handle_counts.begin(), o.handle_counts.end());
  return o;
}

/// The motion on the shape's skeleton (as the avatar's).
MotionClip bench_motion(const BodyModel& model, const BenchOptions& o) {
  MotionOptions mo;
  mo.rest_joints = regress_joints(model, shape_vertices(model, o.betas));
  mo.builtin_seconds = o.seconds + 0.5;
  return load_motion(o.motion, mo);
}

/// One benchmark: the avatars, the reference trace, and the rows of the
/// variants measured against it, in the order they are run.
class BenchmarkRun {
 public:
  explicit BenchmarkRun(const BenchOptions& in)
      : o_(with_defaults(in)),
        model_(load_body_model(o_.model)),
        // The motion first, on the shape's skeleton (as the avatar's), so that a bad
        // motion file fails before minutes of precompute.
        motion_(bench_motion(model_, o_)),
        tv_(cached_template_volume(model_, o_.precompute)) {
    for (int K : o_.handle_counts) {
      PrecomputeOptions po = o_.precompute;
      po.handles = K;
      log_info("bench: shape stage with K = " + std::to_string(K) + " handles");
      avatars_.push_back(std::make_shared<Avatar>(precompute_shape(tv_, model_, o_.betas, po)));
      if (K == o_.default_handles) default_avatar_ = avatars_.back();
    }
    region_ = simulated_region(base());
    labels_ = vertex_regions(base(), region_);
    num_regions_ = int(base().materials.size());
    in_region_ = labels_.unaryExpr([](int r) { return r >= 0 ? 0 : -1; });
    h_ = o_.default_dt;
    K_ = o_.default_handles;
    ref_ = run_reference(default_avatar_, motion_, o_.seconds, h_);
  }

  std::vector<BenchRow> run() {
    add_reference_row();
    add_step_variants();
    add_basis_variants();
    const std::shared_ptr<const Avatar> exact = add_exact_cubature_variants();
    add_lumped_inertia_variants(exact);
    add_inertia_cubature_variant();
    add_peer_rows();
    add_affine_floors();
    add_mode_floor_rows();
    add(run_skinning(base(), motion_, o_.seconds, h_), nullptr, "skinning", "skinning only (u = 0)", 0, h_, 0, false);
    return rows_;
  }

 private:
  const Avatar& base() const { return *default_avatar_; }

  /// The floor of avatar a's basis (computed once per avatar; the map keeps each
  /// avatar alive so that its address is never reused by another).
  const std::vector<Points>* floor_of(const std::shared_ptr<const Avatar>& a) {
    if (!a) return nullptr;
    auto it = floors_.find(a);
    if (it == floors_.end()) it = floors_.emplace(a, floor_trace(*a, ref_)).first;
    return &it->second;
  }

  /// rel_err and floor per region, and the overall floor.
  void split(const Trace& tr, const std::shared_ptr<const Avatar>& a, BenchRow& r) {
    const std::vector<Points>* fl = floor_of(a);
    r.floor_rel_err = fl ? region_rel_errors(*fl, ref_.u, in_region_, 1)[0] : kNaN;
    const std::vector<double> e = region_rel_errors(tr.u, ref_.u, labels_, num_regions_);
    const std::vector<double> ef = fl ? region_rel_errors(*fl, ref_.u, labels_, num_regions_) : std::vector<double>();
    for (int g = 0; g < num_regions_; ++g)
      if (std::isfinite(e[size_t(g)]))
        r.regions.push_back({base().materials[size_t(g)].name, e[size_t(g)], fl ? ef[size_t(g)] : kNaN});
  }

  void add_reference_row() {
    BenchRow rr{"reference", "full FEM, Newton to convergence", 0, h_, -1, false};
    rr.ms_inertia = rr.ms_elastic = rr.ms_solve = rr.dynamic_ms_median = rr.peak_mib = kNaN;
    compare(ref_, ref_, region_, rr);
    split(ref_, nullptr, rr);
    rows_.push_back(rr);
    ref_ms_ = rr.ms_median;
  }

  void add(const Trace& tr, const std::shared_ptr<const Avatar>& a, const std::string& method, const std::string& label,
           int K, double dt, int iters, bool is_default) {
    BenchRow r{method, label, K, dt, iters, is_default};
    r.ms_inertia = r.ms_elastic = r.ms_solve = r.dynamic_ms_median = r.peak_mib = kNaN;
    compare(tr, ref_, region_, r);
    split(tr, a, r);
    r.speedup = r.ms_median > 0 ? ref_ms_ / r.ms_median : 0;
    rows_.push_back(r);
  }

  /// --only: does the variant described by `what` run?
  bool wanted(const std::string& what) const {
    if (o_.only.empty()) return true;
    for (const std::string& s : o_.only)
      if (what.find(s) != std::string::npos) return true;
    return false;
  }

  /// A row of the reduced simulator on avatar a (skipped unless wanted or the default).
  void reduced(std::shared_ptr<const Avatar> a, int K, double dt, int iters, const std::string& what, bool is_default,
               bool mean_dilatation = SimulatorOptions().mean_dilatation,
               std::optional<double> nonlinearity_tolerance = std::nullopt) {
    const std::string label = "K=" + std::to_string(K) + (what.empty() ? "" : ", " + what);
    if (!is_default && !wanted(label)) return;
    const Trace tr = run_reduced(a, motion_, o_.seconds, dt, iters, "reduced " + label, false, mean_dilatation,
                                 nonlinearity_tolerance, o_.linear_solver, o_.cpu_time);
    add(tr, a, "reduced", label, K, dt, iters, is_default);
    BenchRow& r = rows_.back();
    const double steps = double(tr.ms.size());
    r.ms_inertia = tr.ms_inertia / steps;
    r.ms_elastic = tr.ms_elastic / steps;
    r.ms_solve = tr.ms_solve / steps;
    r.peak_mib = tr.peak_mib;
    r.dynamic_ms_median =
        percentile(run_reduced(a, motion_, o_.seconds, dt, iters, "reduced " + label, true, mean_dilatation,
                               nonlinearity_tolerance, o_.linear_solver, o_.cpu_time)
                       .ms,
                   0.5);
  }

  /// An avatar of the default shape and K with its precompute options changed by `change`.
  template <class Change>
  std::shared_ptr<const Avatar> shape_with(Change change) {
    PrecomputeOptions po = o_.precompute;
    po.handles = K_;
    change(po);
    return std::make_shared<Avatar>(precompute_shape(tv_, model_, o_.betas, po));
  }

  /// Handle counts, mean dilatation, time steps and Newton iterations.
  void add_step_variants() {
    const int K = K_;
    const double h = h_;
    // Handle counts at the default time step and cubature, one Newton step
    // (plus the automatic second where a step is far off its quadratic model).
    for (size_t i = 0; i < avatars_.size(); ++i)
      reduced(avatars_[i], o_.handle_counts[i], h, 1,
              o_.handle_counts[i] != K ? "" : K == PrecomputeOptions().handles ? "default" : "default settings otherwise",
              o_.handle_counts[i] == K);
    // Mean dilatation per handle cell (against the subspace's volumetric
    // locking) against every tet's own volume change, as before.
    const bool md = SimulatorOptions().mean_dilatation;
    reduced(default_avatar_, K, h, 1, md ? "volume per tet (no mean dilatation, before)" : "mean dilatation", false, !md);
    // Time steps and Newton iterations around the default.
    for (double dt : o_.quick ? std::vector<double>{1.0 / 30.0} : std::vector<double>{1.0 / 30.0, 1.0 / 120.0})
      reduced(default_avatar_, K, dt, 1, "dt=1/" + std::to_string(int(std::lround(1.0 / dt))), false);
    // Fixed iteration counts (no nonlinearity check), against the default's
    // one step plus one more where it is > 5 % off its quadratic model.
    for (int iters : {1, 2, 3})
      reduced(default_avatar_, K, h, iters,
              iters == 1 ? "one Newton step, no nonlinearity check (before)" : std::to_string(iters) + " Newton iterations",
              false, md, 0.0);
    reduced(default_avatar_, K, h, o_.converged_newton_iters, "Newton converged", false, md, 0.0);
  }

  /// Cubature variants: the stratified samples without the stiffness fit, more
  /// or fewer candidates.
  void cubature_variant(int per_cell, bool fit, const std::string& what) {
    if (!wanted(what)) return;
    log_info("bench: shape stage for " + what);
    const auto a = shape_with([&](PrecomputeOptions& po) {
      po.elastic_samples_per_cell = per_cell;
      po.fit_elastic_cubature = fit;
    });
    reduced(a, K_, h_, 1, what + " (" + std::to_string(a->elastic.size()) + " samples)", false);
  }

  /// The other bone condition, handle placements and cubatures.
  void add_basis_variants() {
    const int K = K_;
    const double h = h_;
    // The earlier basis (bones Dirichlet 0 in every QP), for its floor
    // and its simulation next to the default's.
    if (wanted("bones Dirichlet 0") || wanted("bones depth-blended")) {
      const bool dirichlet = o_.precompute.bbw.bone_condition != basis::BoneCondition::Dirichlet;
      log_info("bench: shape stage with bones " + std::string(dirichlet ? "Dirichlet" : "depth-blended"));
      const auto a = shape_with([&](PrecomputeOptions& po) {
        po.bbw.bone_condition = dirichlet ? basis::BoneCondition::Dirichlet : basis::BoneCondition::DepthBlend;
      });
      reduced(a, K, h, 1, dirichlet ? "bones Dirichlet 0 (the earlier basis)" : "bones depth-blended", false);
    }
    // Handle allocation ("handle placement"): more handles for the
    // small regions (calf, arms, neck, chest) at the same K, taken from the
    // large ones by the same apportionment.
    for (int m : {2, 4, 6}) {
      const std::string what =
          "at least " + std::to_string(m) + " handles per region" + (m == 2 ? " (the earlier minimum)" : "");
      if (m == o_.precompute.placement.min_per_region || !wanted(what)) continue;
      log_info("bench: shape stage with " + what);
      reduced(shape_with([&](PrecomputeOptions& po) { po.placement.min_per_region = m; }), K, h, 1, what, false);
    }
    const PrecomputeOptions defaults = o_.precompute;
    cubature_variant(defaults.elastic_samples_per_cell, !defaults.fit_elastic_cubature,
                     std::string(defaults.fit_elastic_cubature ? "no" : "with") + " stiffness fit");
    if (!o_.quick) {
      cubature_variant(1, true, "1 sample/cell, fitted");
      cubature_variant(6, true, "6 samples/cell, fitted");
    }
  }

  /// Exact integration (one sample per tet) for the elastic energy alone and for
  /// elasticity and inertia: the error of the basis itself. Returns the avatar
  /// with the elastic energy on all tets.
  std::shared_ptr<const Avatar> add_exact_cubature_variants() {
    auto exact = std::make_shared<Avatar>(base());
    if (wanted("elastic on all tets")) exact->elastic = basis::full_cubature(exact->tet, exact->node_role, true);
    reduced(exact, K_, h_, 1, "elastic on all tets", false);
    if (!o_.quick && wanted("elastic + inertia on all tets")) {
      auto exact_both = std::make_shared<Avatar>(*exact);
      exact_both->inertia = basis::full_cubature(exact->tet);
      reduced(exact_both, K_, h_, 1, "elastic + inertia on all tets", false);
    }
    return exact;
  }

  /// The reference's own mass model (lumped at the nodes) projected onto the
  /// basis: is the inertia model what separates rel_err from the floor? With
  /// elasticity on all tets too (`exact`), the row is the Galerkin projection of the
  /// reference onto span(W ⊗ I3) up to the posing nonlinearity.
  void add_lumped_inertia_variants(const std::shared_ptr<const Avatar>& exact) {
    const Avatar& b = base();
    VecX tet_density(b.tet.num_elements());
    for (int t = 0; t < b.tet.num_elements(); ++t) tet_density[t] = tet_material(b, t).density;
    if (wanted("lumped")) {
      auto lumped = std::make_shared<Avatar>(b);
      lumped->inertia = basis::nodal_cubature(b.tet, tet_density, b.node_role);
      reduced(lumped, K_, h_, 1, "inertia lumped at the nodes", false);
      auto lumped_exact = std::make_shared<Avatar>(*exact);
      lumped_exact->inertia = lumped->inertia;
      reduced(lumped_exact, K_, h_, 1, "elastic on all tets + lumped nodal inertia", false);
    }
  }

  /// The other inertia cubature: the data-oblivious samples at the handles
  /// (before the mass fit), or the mass-fitted one if the default is that.
  void add_inertia_cubature_variant() {
    const int per_cell = o_.precompute.inertia_samples_per_cell > 0 ? 0 : 2;
    const std::string what = per_cell > 0 ? "inertia mass-fitted" : "inertia at the handles (data-oblivious, before)";
    // With both accuracy changes (mean dilatation, mass-fitted inertia) as the defaults: the setting before them.
    const std::string before = "previous default (inertia at the handles, volume per tet)";
    const bool both_default = per_cell == 0 && SimulatorOptions().mean_dilatation;
    if (!(wanted(what) || (both_default && wanted(before)))) return;
    log_info("bench: shape stage for " + what);
    const auto a = shape_with([&](PrecomputeOptions& po) { po.inertia_samples_per_cell = per_cell; });
    const std::string label = what + " (" + std::to_string(a->inertia.size()) + " samples)";
    reduced(a, K_, h_, 1, label, false);
    // The combination measured: mean dilatation with the fitted inertia.
    if (per_cell > 0 && !SimulatorOptions().mean_dilatation) reduced(a, K_, h_, 1, label + " + mean dilatation", false, true);
    if (both_default) reduced(a, K_, h_, 1, before, false, false);
  }

  void add_peer_rows() {
    for (bool reskin : o_.peer && wanted("Bullet") ? std::vector<bool>{false, true} : std::vector<bool>{}) {
      int iters = 0;
      long diverged = 0;
      const Trace tr = run_peer(default_avatar_, motion_, o_.seconds, h_, reskin, &iters, &diverged);
      std::string label = std::string("Bullet 3 Neo-Hookean FEM") + (reskin ? ", rest re-skinned" : "");
      if (diverged)
        label += " (diverged at step " + std::to_string(diverged) + "; error over the " + std::to_string(tr.u.size()) +
                 " frames before)";
      add(tr, nullptr, "peer", label, 0, h_, iters, false);
    }
  }

  /// Floors of a candidate basis without simulating it ("report the floor for the
  /// alternatives"): a row with the floor and its regions, the simulated figures NaN.
  void add_floor_only(const std::vector<Points>& fl, const std::string& label, int handles) {
    const double nan = kNaN;
    BenchRow r{"floor", label, handles, h_, 0, false};
    r.ms_median = r.ms_p95 = r.speedup = r.err_mean_mm = r.err_max_mm = r.rel_err = r.peak_ratio = nan;
    r.ms_inertia = r.ms_elastic = r.ms_solve = r.dynamic_ms_median = r.peak_mib = nan;
    r.floor_rel_err = region_rel_errors(fl, ref_.u, in_region_, 1)[0];
    const std::vector<double> ef = region_rel_errors(fl, ref_.u, labels_, num_regions_);
    for (int g = 0; g < num_regions_; ++g)
      if (std::isfinite(ef[size_t(g)])) r.regions.push_back({base().materials[size_t(g)].name, nan, ef[size_t(g)]});
    rows_.push_back(r);
  }

  /// Affine handles: 12 DoFs per handle instead of 3, on each K's handles.
  void add_affine_floors() {
    if (!wanted("affine handles")) return;
    for (size_t i = 0; i < avatars_.size(); ++i) {
      const Avatar& a = *avatars_[i];
      const auto Wa = affine_handle_weights(a.W, a.tet.nodes, a.handles);
      add_floor_only(floor_trace(a, ref_, &Wa),
                     "affine handles, K=" + std::to_string(a.num_handles()) + " (" +
                         std::to_string(12 * a.num_handles()) + " DoFs; floor only)",
                     a.num_handles());
    }
  }

  /// The floor trace of a general vector basis B (3N by D) on the default avatar's mesh.
  std::vector<Points> vector_floor_trace(const MatX& B) const {
    const VectorSubspaceProjector proj(B, simulated_lumped_mass(base()));
    std::vector<Points> out;
    for (const Points& u : ref_.nodal) out.push_back(surface_from_nodes(base(), proj.project(u)));
    return out;
  }

  /// Mode bases (soft_tissue_modes.hpp) as a 3N by D vector basis `modes` whose first d
  /// columns are the lowest d / dofs_per_mode modes: alone, as many DoFs as each K's
  /// handles, and added to the default K's handles (3K/4, 3K/2 and 3K more DoFs).
  void add_mode_floors(const std::string& what, const MatX& modes, int dofs_per_mode) {
    const int K = K_;
    for (const auto& a : avatars_) {
      const int d = 3 * a->num_handles();
      add_floor_only(vector_floor_trace(modes.leftCols(d)),
                     what + " only, " + std::to_string(d / dofs_per_mode) + " (" + std::to_string(d) +
                         " DoFs; floor only)",
                     a->num_handles());
    }
    const MatX bbw = vector_basis(base().W);
    for (int d : added_dofs()) {
      d -= d % dofs_per_mode;  // whole modes
      MatX B(bbw.rows(), bbw.cols() + d);
      B << bbw, modes.leftCols(d);
      add_floor_only(vector_floor_trace(B),
                     "K=" + std::to_string(K) + " handles + " + std::to_string(d / dofs_per_mode) + " " + what +
                         " (" + std::to_string(3 * K + d) + " DoFs; floor only)",
                     K);
    }
  }

  std::vector<int> added_dofs() const { return {3 * K_ / 4, 3 * K_ / 2, 3 * K_}; }

  void add_mode_floor_rows() {
    int most_dofs = added_dofs().back();
    for (const auto& a : avatars_) most_dofs = std::max(most_dofs, 3 * a->num_handles());
    // The lowest vibration modes of the soft tissue with the bones held: one DoF each.
    if (wanted("vibration modes")) {
      log_info("bench: the " + std::to_string(most_dofs) + " lowest vibration modes of the soft tissue (bones held)");
      add_mode_floors("vibration modes", soft_tissue_modes(base(), most_dofs).phi, 1);
    }
    // Scalar skinning eigenmodes: weights like the handles' W, 3 DoFs each (column 3k + c of
    // vector_basis is mode k along axis c, so its first 3m columns are the lowest m modes).
    if (wanted("skinning eigenmodes")) {
      log_info("bench: the " + std::to_string(most_dofs / 3) + " lowest skinning eigenmodes (scalar, bones held)");
      const MatX phi = skinning_eigenmodes(base(), most_dofs / 3).phi;
      add_mode_floors("skinning eigenmodes", vector_basis(phi.sparseView()), 3);
    }
  }

  BenchOptions o_;
  BodyModel model_;
  MotionClip motion_;
  TemplateVolume tv_;
  std::vector<std::shared_ptr<const Avatar>> avatars_;
  std::shared_ptr<const Avatar> default_avatar_;
  std::vector<int> region_;  // skin vertices with simulated nodes
  VecXi labels_;             // region label per skin vertex
  int num_regions_ = 0;
  VecXi in_region_;  // 0 on region_, -1 elsewhere
  double h_ = 0;
  int K_ = 0;
  Trace ref_;
  std::vector<BenchRow> rows_;
  std::map<std::shared_ptr<const Avatar>, std::vector<Points>> floors_;
  double ref_ms_ = 0;
};

}  // namespace

std::vector<BenchRow> run_benchmark(const BenchOptions& in) { return BenchmarkRun(in).run(); }

}  // namespace sflsh
