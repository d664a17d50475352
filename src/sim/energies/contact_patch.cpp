#include "sflsh/sim/energies/contact_patch.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>

#include <Eigen/Eigenvalues>

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"
#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/energies/inertia.hpp"
#include "sflsh/sim/linearized_stiffness.hpp"
#include "sim/energies/contact_patch_cache.hpp"

namespace sflsh {

using contact_patch_detail::add_offset_rotation_gradient;
using contact_patch_detail::local_layout;
using contact_patch_detail::patch_cache;
using contact_patch_detail::PatchCache;
using contact_patch_detail::PatchHistory;

ContactPatchTerm::ContactPatchTerm(std::string object, const Avatar& a, geometry::SdfPtr field,
                                   const Isometry& shape_in_frame, bool dynamic_object, const ContactPatchOptions& o,
                                   std::optional<PatchAnchors> anchors)
    : object_(std::move(object)),
      avatar_(&a),
      field_(std::move(field)),
      shape_in_frame_(shape_in_frame),
      dynamic_(dynamic_object),
      options_(o),
      anchors_(std::move(anchors)) {
  const std::string what = "contact with '" + object_ + "'";
  require(field_ != nullptr || anchors_, what, ": no field and no anchors");
  if (anchors_) {
    require(!anchors_->set.empty(), what, ": the anchor set has no name");
    const AnchorOptions& ao = anchors_->options;
    require(ao.hardness > 0 && std::isfinite(ao.hardness), what, ": anchor hardness ", ao.hardness,
            " N/m, expected > 0");
    require(ao.damping >= 0 && std::isfinite(ao.damping), what, ": anchor damping ", ao.damping,
            " N·s/m, expected >= 0");
  }
  check_contact_sampling(o.pressure_stiffness, o.spacing, what);
  require(std::isfinite(o.patch_radius) && o.patch_radius > 0, what, ": patch radius ", o.patch_radius,
          " m, expected a finite number > 0");
  require(std::isfinite(o.margin) && o.margin >= 0, what, ": margin ", o.margin, " m, expected >= 0");
  require(o.max_inner_iterations >= 1 && o.inner_tolerance >= 0 && o.release_displacement >= 0, what,
          ": inner iterations must be >= 1 and the tolerances >= 0");
  require(std::isfinite(o.release_time) && o.release_time > 0, what, ": release_time ", o.release_time,
          " s, expected a finite number > 0");
  require(std::isfinite(o.friction) && o.friction >= 0, what, ": friction ", o.friction, ", expected >= 0");
  require(std::isfinite(o.static_slip_speed) && o.static_slip_speed > 0, what, ": static slip speed ",
          o.static_slip_speed, " m/s, expected > 0");
  require(o.max_patch_nodes >= 1, what, ": max_patch_nodes ", o.max_patch_nodes, ", expected >= 1");
  require(std::isfinite(o.patch_radius_per_contact_radius) && o.patch_radius_per_contact_radius >= 0, what,
          ": patch_radius_per_contact_radius ", o.patch_radius_per_contact_radius, ", expected a finite number >= 0");
  vertices_ = PosedPoints::at_surface(a);
  if (o.max_handles > 0) vertices_ = vertices_.with_truncated_rows(o.max_handles);
  const int N = a.tet.num_nodes(), T = a.tet.num_elements();
  node_tets_.assign(N, {});
  for (int t = 0; t < T; ++t)
    for (int c = 0; c < 4; ++c) node_tets_[a.tet.elements(t, c)].push_back(t);
  // The subspace at the nodes: each node as a point of one of its tets.
  Cubature at_nodes;
  at_nodes.elements.resize(N);
  at_nodes.barycentric = MatXr::Zero(N, 4);
  at_nodes.weights = VecX::Ones(N);
  for (int n = 0; n < N; ++n) {
    require(!node_tets_[n].empty(), what, ": tet node ", n, " belongs to no tet");
    const int t = node_tets_[n][0];
    at_nodes.elements[n] = t;
    for (int c = 0; c < 4; ++c)
      if (a.tet.elements(t, c) == n) at_nodes.barycentric(n, c) = 1.0;
  }
  nodes_ = PosedPoints::at_cubature(a, at_nodes);
  for (int n = 0; n < N; ++n)
    if (a.node_role.size() == 0 || a.node_role[n] == int(NodeRole::Simulated))
      simulated_by_x_.emplace_back(a.tet.nodes(n, 0), n);
  std::sort(simulated_by_x_.begin(), simulated_by_x_.end());
  grads_ = fem::tet_gradients(a.tet);
  tet_volume_ = fem::tet_volumes(a.tet);
  node_mass_ = VecX::Zero(N);
  materials_.reserve(T);
  for (int t = 0; t < T; ++t) {
    const RegionMaterial& m = tet_material(a, t);
    materials_.emplace_back(m, tet_frame(a, t));
    for (int c = 0; c < 4; ++c) node_mass_[a.tet.elements(t, c)] += m.density * tet_volume_[t] / 4.0;
  }
  // The inertia cubature's samples by their main node (largest barycentric weight).
  inertia_points_ = PosedPoints::at_cubature(a, a.inertia);
  inertia_mass_ = cubature_masses(a, a.inertia);
  sample_node_.resize(size_t(a.inertia.size()));
  for (int s = 0; s < a.inertia.size(); ++s) {
    int k = 0;
    a.inertia.barycentric.row(s).maxCoeff(&k);
    sample_node_[size_t(s)] = a.tet.elements(a.inertia.elements[s], k);
  }
  // The subspace's quadratic share of each tet (subspace_quadratic_hessian).
  if (o.subspace_mean_dilatation) dilatation_cell_ = dilatation_cells(a);
  // Broad phase: vertices by dominant bone and 10 cm cell (unposed), each
  // cluster with a bounding radius and 5 cm of slack for skinning blends and
  // soft displacement (as sdf_contact.hpp's clusters).
  std::map<std::tuple<int, long, long, long>, std::vector<int>> cells;
  for (int v = 0; v < vertices_.size(); ++v) {
    const Vec3 x = vertices_.unposed().row(v).transpose();
    cells[{std::max(0, vertices_.dominant_bone(v)), std::lround(std::floor(x.x() / 0.1)),
           std::lround(std::floor(x.y() / 0.1)), std::lround(std::floor(x.z() / 0.1))}]
        .push_back(v);
  }
  for (auto& [key, members] : cells) {
    VertexCluster cl;
    cl.bone = std::get<0>(key);
    for (int v : members) cl.center += vertices_.unposed().row(v).transpose();
    cl.center /= double(members.size());
    for (int v : members) cl.radius = std::max(cl.radius, (vertices_.unposed().row(v).transpose() - cl.center).norm());
    cl.radius += 0.05;
    cl.vertices = std::move(members);
    clusters_.push_back(std::move(cl));
  }
  vertex_faces_.assign(a.surface_rest.rows(), {});
  for (int f = 0; f < a.surface_faces.rows(); ++f)
    for (int i = 0; i < 3; ++i) vertex_faces_[a.surface_faces(f, i)].push_back(f);
}

int ContactPatchTerm::object_offset(const StepContext& ctx) const {
  if (!dynamic_) return -1;
  require(ctx.bound.size() == 2 && ctx.bound[1].q != nullptr, name(), ": the object's body is not bound");
  return ctx.bound[1].layout.base;
}

std::unique_ptr<TermCache> ContactPatchTerm::make_cache() const {
  auto c = std::make_unique<PatchCache>();
  c->num_nodes = avatar_->tet.num_nodes();
  return c;
}

std::vector<int> ContactPatchTerm::patch_nodes(const StepContext& ctx) const { return patch_cache(ctx, name()).nodes; }

/// Patch nodes: Simulated nodes within patch_radius (unposed) of a seed (a
/// skin vertex near the object; seed_phi its φ), nearest the deepest seeds
/// first when there are too many, and every node still displaced.
void ContactPatchTerm::select_patch_nodes(TermCache& cache, const std::vector<int>& seeds,
                                          const std::vector<double>& seed_phi) const {
  PatchCache& c = static_cast<PatchCache&>(cache);
  const Avatar& a = *avatar_;
  c.nodes.clear();
  c.node_slot.clear();
  auto add_node = [&](int n) {
    if (c.node_slot.emplace(n, int(c.nodes.size())).second) c.nodes.push_back(n);
  };
  c.radius = options_.patch_radius;
  if (options_.patch) {
    // The contact's radius a = 2 σ₂ (options): the middle principal spread
    // of the seeds that touch at time t (φ < 0).
    std::vector<int> touching;
    for (size_t i = 0; i < seeds.size(); ++i)
      if (seed_phi[i] < 0) touching.push_back(seeds[i]);
    if (options_.patch_radius_per_contact_radius > 0 && touching.size() >= 3) {
      Vec3 mean = Vec3::Zero();
      for (int v : touching) mean += a.surface_rest.row(v).transpose();
      mean /= double(touching.size());
      Mat3 cov = Mat3::Zero();
      for (int v : touching) {
        const Vec3 d = a.surface_rest.row(v).transpose() - mean;
        cov += d * d.transpose();
      }
      cov /= double(touching.size());
      const Vec3 ev = Eigen::SelfAdjointEigenSolver<Mat3>(cov, Eigen::EigenvaluesOnly).eigenvalues();  // increasing
      c.radius = std::max(c.radius, options_.patch_radius_per_contact_radius * 2.0 * std::sqrt(std::max(ev[1], 0.0)));
    }
    const double r2 = c.radius * c.radius;
    if (!seeds.empty()) {
      // Bounding box of the seeds first: most nodes are far.
      Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
      for (int v : seeds) {
        lo = lo.cwiseMin(Vec3(a.surface_rest.row(v).transpose()));
        hi = hi.cwiseMax(Vec3(a.surface_rest.row(v).transpose()));
      }
      lo.array() -= c.radius;
      hi.array() += c.radius;
      // Each node within the radius, ranked by its distance to a seed
      // plus that vertex's φ: the deepest contact's nodes first when the patch
      // is over max_patch_nodes (a broad press).
      std::vector<std::pair<double, int>> ranked;
      const auto first = std::lower_bound(simulated_by_x_.begin(), simulated_by_x_.end(), std::make_pair(lo.x(), -1));
      for (auto it = first; it != simulated_by_x_.end() && it->first <= hi.x(); ++it) {
        const int n = it->second;
        const Vec3 y = a.tet.nodes.row(n).transpose();
        if ((y.array() < lo.array()).any() || (y.array() > hi.array()).any()) continue;
        double rank = std::numeric_limits<double>::infinity();
        for (size_t i = 0; i < seeds.size(); ++i) {
          const double d2 = (y - a.surface_rest.row(seeds[i]).transpose()).squaredNorm();
          if (d2 <= r2) rank = std::min(rank, std::sqrt(d2) + seed_phi[i]);
        }
        if (std::isfinite(rank)) ranked.emplace_back(rank, n);
      }
      if (int(ranked.size()) > options_.max_patch_nodes) {
        std::nth_element(ranked.begin(), ranked.begin() + options_.max_patch_nodes, ranked.end());
        ranked.resize(size_t(options_.max_patch_nodes));
      }
      for (const auto& [rank, n] : ranked) add_node(n);
    }
    for (const auto& [n, h] : c.history) add_node(n);
  }
}

/// The patch tets (with a patch node), each one's nodes as indices into the
/// distinct nodes of the patch tets, their patch slots and the material's
/// small-strain Hessian; the patch nodes sorted.
void ContactPatchTerm::prepare_patch_tets(TermCache& cache) const {
  PatchCache& c = static_cast<PatchCache&>(cache);
  const Avatar& a = *avatar_;
  std::sort(c.nodes.begin(), c.nodes.end());
  c.node_slot.clear();
  for (int i = 0; i < int(c.nodes.size()); ++i) c.node_slot[c.nodes[i]] = i;
  if (c.nodes == c.prepared_nodes) return;  // the tets, slots and pairs below follow from the nodes alone
  c.prepared_nodes = c.nodes;
  std::vector<char> tet_mark(a.tet.num_elements(), 0);
  c.tets.clear();
  for (int n : c.nodes)
    for (int t : node_tets_[n])
      if (!tet_mark[t]) tet_mark[t] = 1, c.tets.push_back(t);
  std::sort(c.tets.begin(), c.tets.end());
  c.tet_nodes.clear();
  c.tet_local.assign(c.tets.size(), {});
  c.tet_slot.assign(c.tets.size(), {});
  c.tet_H2.resize(c.tets.size());
  c.tet_Hq.resize(c.tets.size());
  c.tet_K0.resize(c.tets.size());
  std::unordered_map<int, int> tet_node_index;
  for (size_t i = 0; i < c.tets.size(); ++i) {
    const int t = c.tets[i];
    for (int k = 0; k < 4; ++k) {
      const int n = a.tet.elements(t, k);
      const auto [it, added] = tet_node_index.emplace(n, int(c.tet_nodes.size()));
      if (added) c.tet_nodes.push_back(n);
      c.tet_local[i][size_t(k)] = it->second;
      const auto s = c.node_slot.find(n);
      c.tet_slot[i][size_t(k)] = s == c.node_slot.end() ? -1 : s->second;
    }
    c.tet_H2[i] = linearized_hessian(materials_[t]);
    c.tet_Hq[i] = subspace_quadratic_hessian(t, c.tet_H2[i]);
    c.tet_K0[i] = contact_patch_detail::element_blocks(grads_[t], tet_volume_[t], c.tet_Hq[i]);
  }
  std::vector<std::vector<int>> slots(c.tet_nodes.size());
  for (size_t i = 0; i < c.tets.size(); ++i)
    for (int k = 0; k < 4; ++k)
      for (int l = 0; l < 4; ++l)
        if (c.tet_slot[i][size_t(l)] >= 0) slots[size_t(c.tet_local[i][size_t(k)])].push_back(c.tet_slot[i][size_t(l)]);
  c.cross_first.assign(1, 0);
  c.cross_slot.clear();
  for (std::vector<int>& s : slots) {
    std::sort(s.begin(), s.end());
    s.erase(std::unique(s.begin(), s.end()), s.end());
    c.cross_slot.insert(c.cross_slot.end(), s.begin(), s.end());
    c.cross_first.push_back(int(c.cross_slot.size()));
  }
  // The pairs' indices, and the subspace share's stiffness summed per pair
  // and over the patch DoFs (K0_pp).
  c.tet_cross.assign(c.tets.size(), {});
  c.node_cross.assign(c.cross_slot.size(), Mat3::Zero());
  c.K0pp.setZero(3 * long(c.nodes.size()), 3 * long(c.nodes.size()));
  for (size_t i = 0; i < c.tets.size(); ++i)
    for (int k = 0; k < 4; ++k) {
      const int n = c.tet_local[i][size_t(k)], sk = c.tet_slot[i][size_t(k)];
      const auto first = c.cross_slot.begin() + c.cross_first[size_t(n)], last = c.cross_slot.begin() + c.cross_first[size_t(n) + 1];
      for (int l = 0; l < 4; ++l) {
        const int slot = c.tet_slot[i][size_t(l)];
        const int e = slot < 0 ? -1 : int(std::lower_bound(first, last, slot) - c.cross_slot.begin());
        c.tet_cross[i][size_t(4 * k + l)] = e;
        if (e < 0) continue;
        const Mat3& K0 = c.tet_K0[i][size_t(k)][size_t(l)];
        c.node_cross[size_t(e)] += K0;
        if (sk >= 0) c.K0pp.block<3, 3>(3 * sk, 3 * slot) += K0;
      }
    }
}

// Σ_t (1 − α) κ_t V_t (Wᵀ b_t)(Wᵀ b_t)ᵀ over the patch tets (b_t the tet's
// volume-change gradient, κ_t = vᵀH₂v/9): columns over the handles the
// tets' Simulated nodes touch, then one rank update.
void ContactPatchTerm::prepare_bulk_hessian(TermCache& cache) const {
  PatchCache& c = static_cast<PatchCache&>(cache);
  if (dilatation_cell_.size() == 0 || c.tets.empty()) {
    c.bulk_handles.clear();
    c.bulk_hessian.resize(0, 0);
    c.bulk_tets.clear();
    return;
  }
  if (c.tets == c.bulk_tets) return;
  const Avatar& a = *avatar_;
  std::vector<int> index(size_t(a.num_handles()), -1);  // handle → compressed index
  std::vector<std::pair<int, Vec3>> entries;
  std::vector<int> first{0};
  c.bulk_handles.clear();
  Vec9 v = Vec9::Zero();
  v[0] = v[4] = v[8] = 1.0;
  for (size_t ti = 0; ti < c.tets.size(); ++ti) {
    const int t = c.tets[ti];
    if (dilatation_cell_[t] < 0) continue;
    const double kappa = v.dot(c.tet_H2[ti] * v) / 9.0;
    const double scale = std::sqrt((1.0 - kPerTetVolumeShare) * kappa * tet_volume_[t]);
    for (int k = 0; k < 4; ++k) {
      const int n = a.tet.elements(t, k);
      if (a.node_role.size() && a.node_role[n] != int(NodeRole::Simulated)) continue;
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, n); it; ++it) {
        int& h = index[size_t(it.col())];
        if (h < 0) h = int(c.bulk_handles.size()), c.bulk_handles.push_back(int(it.col()));
        entries.emplace_back(h, scale * it.value() * grads_[t].row(k).transpose());
      }
    }
    first.push_back(int(entries.size()));
  }
  MatX C = MatX::Zero(3 * long(c.bulk_handles.size()), long(first.size()) - 1);
  for (size_t e = 0; e + 1 < first.size(); ++e)
    for (int i = first[e]; i < first[e + 1]; ++i) C.block<3, 1>(3 * entries[size_t(i)].first, long(e)) += entries[size_t(i)].second;
  c.bulk_hessian = MatX::Zero(C.rows(), C.rows());
  c.bulk_hessian.selfadjointView<Eigen::Lower>().rankUpdate(C);
  c.bulk_hessian.triangularView<Eigen::StrictlyUpper>() = c.bulk_hessian.transpose();
  c.bulk_tets = c.tets;
}

void ContactPatchTerm::begin_step(const StepContext& ctx) const {
  PatchCache& c = patch_cache(ctx, name());
  // The displacement fixed at the end of the last step becomes the one at t.
  // Nodes whose displacement has released leave (kept aside: a tet may still need them).
  std::unordered_map<int, PatchHistory> left;
  for (auto it = c.history.begin(); it != c.history.end();) {
    PatchHistory& h = it->second;
    h.d_prev = h.d_t;
    h.d_t = h.d_next;
    h.du_prev = h.du;
    h.du = h.du_next;
    h.du_back = h.du_back_next;
    h.du_back_next.setZero();
    const double rel = options_.release_displacement;
    if (h.du.norm() <= rel && h.d_t.norm() <= rel && h.d_prev.norm() <= rel) {
      left.emplace(it->first, h);
      it = c.history.erase(it);
    } else {
      ++it;
    }
  }
  std::vector<int> near;
  std::vector<double> near_phi;  // φ of each near vertex at t
  if (field_) find_near_vertices(ctx, c, near, near_phi);
  collect_candidate_faces(c, near);
  if (anchors_) collect_anchors(ctx, c, near, near_phi);
  // No skin near the object and no anchor: the patch is released (header comment).
  c.releasing = near.empty();
  select_patch_nodes(c, near, near_phi);
  prepare_patch_tets(c);
  const BoundBody& b = ctx.bound.empty() ? BoundBody{0, 0, ctx.avatar, ctx.layout, nullptr, &ctx.q_prev, &ctx.q_prev2}
                                         : ctx.bound[0];
  const Configuration& qt = *b.q_prev;
  const double decay = std::exp(-ctx.h / options_.release_time);  // of a released patch's δu
  keep_start_admissible(c, qt.z, left, decay);
  prepare_bulk_hessian(c);
  // Predictions and the warm start.
  const bool has_prev = b.q_prev2 && b.q_prev2->bones.size() == qt.bones.size();
  const size_t P = c.nodes.size();
  c.x_star.assign(P, Vec3::Zero());
  c.d_pred.assign(P, Vec3::Zero());
  c.du = VecX::Zero(3 * P);
  c.du_predicted = VecX::Zero(3 * P);
  c.inner_iterations = c.minimizations = 0;
  c.solved = c.linearized = false;
  c.has_trial = false;
  c.settled = P > 0;
  for (size_t i = 0; i < P; ++i) {
    const int n = c.nodes[i];
    const Vec3 xt = nodes_.world_point(n, qt);
    c.x_star[i] = has_prev ? Vec3(2 * xt - nodes_.world_point(n, *b.q_prev2)) : xt;
    const auto h = c.history.find(n);
    if (h == c.history.end()) {
      c.settled = false;
      continue;
    }
    c.d_pred[i] = 2 * h->second.d_t - h->second.d_prev;
    c.du.segment<3>(3 * i) = h->second.du;
    c.du_predicted.segment<3>(3 * i) = 2 * h->second.du - h->second.du_prev + h->second.du_back;
  }
  prepare_friction(ctx, c, qt);
  if (c.releasing) c.du *= decay;
  c.samples_in_patch.clear();
  c.sample_x_star.clear();
  for (int s = 0; s < int(sample_node_.size()); ++s)
    if (c.node_slot.count(sample_node_[s])) {
      const Vec3 xt = inertia_points_.world_point(s, qt);
      c.samples_in_patch.push_back(s);
      c.sample_x_star.push_back(has_prev ? Vec3(2 * xt - inertia_points_.world_point(s, *b.q_prev2)) : xt);
    }
  collect_q_rows(ctx, c, qt);
}

// The rows the evaluation writes in the q blocks: the DoFs of the points it
// poses (the patch nodes, the inertia samples there, the candidate faces' and
// the anchors' vertices: their Jacobians' columns), the handles of the patch
// tets' Simulated nodes (the cross blocks through W) and of the bulk share,
// and a dynamic object's six. Which DoFs a point depends on does not depend
// on q, so one collection serves the step.
void ContactPatchTerm::collect_q_rows(const StepContext& ctx, TermCache& cache, const Configuration& q) const {
  PatchCache& c = static_cast<PatchCache&>(cache);
  const Avatar& a = *avatar_;
  const DofLayout& L = local_layout(ctx);
  // The object's rows (object_offset, without its configuration: begin_step binds t's).
  const int ob = dynamic_ && ctx.bound.size() == 2 ? ctx.bound[1].layout.base : -1;
  const int nq = std::max(L.end(), ob + 6), z0 = L.z_offset();
  std::vector<char> mark(size_t(nq), 0);
  Eigen::Matrix<double, 3, Eigen::Dynamic> J;
  std::vector<int> cols;
  auto add_points = [&](const PosedPoints& points, const std::vector<int>& ids) {
    for (int p : ids) {
      points.local_jacobian(p, q, L, J, cols);
      for (int r : cols) mark[size_t(r)] = 1;
    }
  };
  auto add_handle = [&](int h) {
    for (int k = 0; k < 3; ++k) mark[size_t(z0 + 3 * h + k)] = 1;
  };
  add_points(nodes_, c.nodes);
  add_points(inertia_points_, c.samples_in_patch);
  add_points(vertices_, c.vertices);
  add_points(vertices_, c.anchor_vertices);
  for (int n : c.tet_nodes)
    if (a.node_role.size() == 0 || a.node_role[n] == int(NodeRole::Simulated))
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, n); it; ++it) add_handle(int(it.col()));
  for (int h : c.bulk_handles) add_handle(h);
  if (ob >= 0)
    for (int k = 0; k < 6; ++k) mark[size_t(ob + k)] = 1;
  // A system of another size: every row may hold an old value (the blocks are
  // zeroed whole when they are resized, but one of this size may be kept).
  bool changed = c.q_row_written.size() != size_t(nq);
  if (changed) c.q_row_written.assign(size_t(nq), c.q_row_written.empty() ? 0 : 1);
  c.q_rows.clear();
  for (int r = 0; r < nq; ++r) {
    if (!mark[size_t(r)]) continue;
    c.q_rows.push_back(r);
    if (!c.q_row_written[size_t(r)]) c.q_row_written[size_t(r)] = 1, changed = true;
  }
  if (!changed) return;
  c.q_rows_written.clear();
  for (int r = 0; r < nq; ++r)
    if (c.q_row_written[size_t(r)]) c.q_rows_written.push_back(r);
}

bool ContactPatchTerm::active(const StepContext& ctx) const {
  const PatchCache& c = patch_cache(ctx, name());
  return !c.faces.empty() || !c.nodes.empty() || !c.anchor_vertices.empty();
}

}  // namespace sflsh
