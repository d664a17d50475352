#include "sflsh/sim/energies/contact_patch.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <tuple>

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"
#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/sim/compression_guard.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/energies/inertia.hpp"
#include "sflsh/sim/linearized_stiffness.hpp"

namespace sflsh {

/// Φ and its derivatives at one (q, δu) (header comment): over the patch DoFs p
/// (3 per patch node, cache order) and the term's local layout q.
struct ContactPatchTerm::Evaluation {
  double energy = 0;
  VecX gp;   // ∂Φ/∂δu
  MatX Hpp;  // its PSD approximation
  VecX gq;   // ∂Φ/∂q
  MatX Hqq;  // Φ_qq: contact (Gauss–Newton), the nodes' inertia less the samples', the bulk share
  MatX Hqp;  // cross block (layout rows by patch DoFs)
  MatX K0pp; // the subspace state's element stiffness over the patch DoFs (with the q derivatives)
  Vec3 force = Vec3::Zero();
  int active = 0;
  double depth = 0, area = 0;
};

namespace {

struct PatchHistory {
  Vec3 du = Vec3::Zero();       // unposed displacement at t (warm start)
  Vec3 d_t = Vec3::Zero();      // world offset A δu at t
  Vec3 d_prev = Vec3::Zero();   // at t − h
  Vec3 du_next = Vec3::Zero();  // fixed by report() for t + h
  Vec3 d_next = Vec3::Zero();
};

struct PatchCache : TermCache {
  Isometry field_pose = Isometry::Identity();  // world (step frame) pose of the field at t + h
  std::vector<int> faces;                      // candidate skin faces
  std::vector<SkinFaceSample> samples;         // their samples, grouped by face in `faces` order
  std::vector<int> face_first;                 // samples of faces[i]: [face_first[i], face_first[i+1])
  std::vector<int> vertices;                   // distinct vertices of the candidate faces
  std::unordered_map<int, int> vertex_slot;    // vertex → index into `vertices`
  std::vector<int> nodes;                      // patch nodes
  std::unordered_map<int, int> node_slot;      // node → index into `nodes`
  std::vector<int> tets;                       // tets with a patch node
  std::vector<Vec3> x_star, d_pred;            // per patch node: subspace prediction, offset prediction
  std::vector<int> samples_in_patch;           // inertia cubature samples whose main node is a patch node
  std::vector<Vec3> sample_x_star;             // their predictions
  VecX du;                                     // last minimizer (3 per patch node)
  int inner_iterations = 0, minimizations = 0; // this step's Newton iterations on δu, and minimizations
  // The configuration `du` minimizes Φ at (skipped when asked again), and the
  // linearization of the last Hessian evaluation: δu(z) ≈ du_lin − Φ_pp⁻¹ Φ_pz (z − z_lin).
  bool solved = false;
  Configuration q_solved;
  Isometry object_solved = Isometry::Identity();
  bool linearized = false;
  VecX z_lin, du_lin;
  MatX Hpz;                     // Φ_pz (patch DoFs by z)
  Eigen::LLT<MatX> Hpp_llt;
  std::unordered_map<int, PatchHistory> history;
};

PatchCache& patch_cache(const StepContext& ctx, const std::string& name) {
  require(ctx.cache != nullptr, name, ": no cache (call begin_step through begin_term_step or the integrator)");
  return static_cast<PatchCache&>(*ctx.cache);
}

const DofLayout& local_layout(const StepContext& ctx) { return ctx.bound.empty() ? ctx.layout : ctx.bound[0].layout; }

/// Adds the generalized force of a world force `f` on an offset d = Σ_j w_j R_j o
/// (o unposed) to the bones' rotations: ∂d/∂ω_j = −[w_j R_j o]×, so bone j's
/// ω gains (w_j R_j o) × f (translations do not move an offset).
template <class Row>
void add_offset_rotation_gradient(const Row& w, const std::vector<Isometry>& bones, const Vec3& o, const Vec3& f,
                                  const DofLayout& L, VecX& gq) {
  if (!L.bones_dynamic) return;
  for (int j = 0; j < w.size(); ++j)
    if (w[j] != 0.0) gq.segment<3>(L.bone_offset(j)) += (w[j] * (bones[j].linear() * o)).cross(f);
}

}  // namespace

ContactPatchTerm::ContactPatchTerm(std::string object, const Avatar& a, geometry::SdfPtr field,
                                   const Isometry& shape_in_frame, bool dynamic_object, const ContactPatchOptions& o)
    : object_(std::move(object)),
      avatar_(&a),
      field_(std::move(field)),
      shape_in_frame_(shape_in_frame),
      dynamic_(dynamic_object),
      options_(o) {
  const std::string what = "contact with '" + object_ + "'";
  require(field_ != nullptr, what, ": no field");
  check_contact_sampling(o.pressure_stiffness, o.spacing, what);
  require(std::isfinite(o.patch_radius) && o.patch_radius > 0, what, ": patch radius ", o.patch_radius,
          " m, expected a finite number > 0");
  require(std::isfinite(o.margin) && o.margin >= 0, what, ": margin ", o.margin, " m, expected >= 0");
  require(o.max_inner_iterations >= 1 && o.inner_tolerance >= 0 && o.release_displacement >= 0, what,
          ": inner iterations must be >= 1 and the tolerances >= 0");
  require(o.max_patch_nodes >= 1, what, ": max_patch_nodes ", o.max_patch_nodes, ", expected >= 1");
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
  // What the subspace's elastic term holds of each tet (subspace_density).
  if (o.subspace_mean_dilatation) dilatation_cell_ = dilatation_cells(a);
  cubature_weight_ = VecX::Zero(T);
  for (int k = 0; k < a.elastic.size(); ++k) {
    const int t = a.elastic.elements[k];
    require(t >= 0 && t < T, what, ": elastic cubature sample ", k, " has tet ", t, ", expected in [0, ", T, ")");
    cubature_weight_[t] += a.elastic.weights[k];
  }
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

double ContactPatchTerm::subspace_density(int t, const Mat3& F, const Mat9& H2, Mat3* P, Mat9* H) const {
  const MaterialPoint& m = materials_[t];
  Mat9 Hq = H2;
  if (dilatation_cell_.size() > 0 && dilatation_cell_[t] >= 0) {
    // The tet's own share of the mean-dilatation quadratic (linearized_stiffness.cpp):
    // α H₂ + (1 − α) P H₂ P, P = I − v vᵀ/3 the deviatoric projector (v = vec I);
    // the cell's mean stays in the subspace. P H₂ P = H₂ − u vᵀ − v uᵀ + (vᵀH₂v/9) v vᵀ, u = H₂v/3.
    Vec9 v = Vec9::Zero();
    v[0] = v[4] = v[8] = 1.0;
    const Vec9 u = H2 * v / 3.0;
    const double b = v.dot(u) / 3.0;
    Hq.noalias() -= (1.0 - kPerTetVolumeShare) * (u * v.transpose() + v * u.transpose() - b * v * v.transpose());
  }
  const Mat3 D = F - Mat3::Identity();
  const Vec9 h = Eigen::Map<const Vec9>(D.data());
  const Vec9 Hqh = Hq * h;
  double psi = 0.5 * h.dot(Hqh);
  if (P) *P = Eigen::Map<const Mat3>(Hqh.data());
  if (H) *H = Hq;
  // The cubature's remainder Ψ − Ψ₂ (and the compression guard), weighted as the samples in the tet.
  const double c = cubature_weight_[t] / tet_volume_[t];
  if (c == 0.0) return psi;
  Mat3 Pr;
  Mat9 Hr;
  const Vec9 H2h = H2 * h;
  double r = strain_energy_density(F, m, P ? &Pr : nullptr, H ? &Hr : nullptr, true) - 0.5 * h.dot(H2h);
  if (P) Pr -= Eigen::Map<const Mat3>(H2h.data());
  if (H) Hr -= H2;
  if (options_.subspace_mean_dilatation)
    r += compression_guard(F, (1.0 - kPerTetVolumeShare) * m.kappa, kCompressionGuardOnset, P ? &Pr : nullptr,
                           H ? &Hr : nullptr, true);
  if (P) *P += c * Pr;
  // The Hessian serves the cross block Φ_zp only (evaluate_patch): a sample
  // standing for many tets' volume (c ≫ 1) holds its remainder with that
  // weight, but δu couples to z through this tet's own volume.
  if (H) *H += std::min(c, 1.0) * Hr;
  return psi + c * r;
}

int ContactPatchTerm::object_offset(const StepContext& ctx) const {
  if (!dynamic_) return -1;
  require(ctx.bound.size() == 2 && ctx.bound[1].q != nullptr, name(), ": the object's body is not bound");
  return ctx.bound[1].layout.base;
}

std::unique_ptr<TermCache> ContactPatchTerm::make_cache() const { return std::make_unique<PatchCache>(); }

std::vector<int> ContactPatchTerm::patch_nodes(const StepContext& ctx) const { return patch_cache(ctx, name()).nodes; }

void ContactPatchTerm::begin_step(const StepContext& ctx) const {
  PatchCache& c = patch_cache(ctx, name());
  const Avatar& a = *avatar_;
  // The displacement fixed at the end of the last step becomes the one at t.
  for (auto it = c.history.begin(); it != c.history.end();) {
    PatchHistory& h = it->second;
    h.d_prev = h.d_t;
    h.d_t = h.d_next;
    h.du = h.du_next;
    const double rel = options_.release_displacement;
    if (h.du.norm() <= rel && h.d_t.norm() <= rel && h.d_prev.norm() <= rel)
      it = c.history.erase(it);
    else
      ++it;
  }
  const geometry::Aabb local = field_->bounds();
  const bool bounded = !local.is_unbounded();
  const double extent = bounded ? 0.5 * (local.max - local.min).norm() : 1.0;
  double object_motion = 0;
  if (dynamic_) {
    // The object's pose at t (the broad phase's reference) and its motion over the last step, doubled.
    require(ctx.bound.size() == 2 && ctx.bound[1].q_prev != nullptr, name(),
            ": a dynamic object's contact is bound to the body and the object");
    const Isometry& G = ctx.bound[1].q_prev->bones[0];
    c.field_pose = G * shape_in_frame_;
    if (ctx.bound[1].q_prev2 && !ctx.bound[1].q_prev2->bones.empty()) {
      const Isometry& Gp = ctx.bound[1].q_prev2->bones[0];
      const double angle = Eigen::AngleAxisd(G.linear() * Gp.linear().transpose()).angle();
      object_motion = 2 * ((G.translation() - Gp.translation()).norm() + angle * extent);
    }
  } else {
    require(ctx.frame() != nullptr, name(), ": the step inputs have no world frame '", object_, "'");
    const WorldFrame& f = *ctx.frame();
    require(f.pose.matrix().allFinite(), name(), ": world frame '", object_, "' is not finite");
    c.field_pose = f.pose * shape_in_frame_;
    object_motion = ctx.h * (f.linear_velocity.norm() + f.angular_velocity.norm() * extent);
  }
  const Isometry T_inv = c.field_pose.inverse();
  const geometry::Aabb box = bounded ? local.transformed(c.field_pose) : local;

  // Skin vertices near the object at time t.
  const BoundBody& b = ctx.bound.empty() ? BoundBody{0, 0, ctx.avatar, ctx.layout, nullptr, &ctx.q_prev, &ctx.q_prev2}
                                         : ctx.bound[0];
  const Configuration& qt = *b.q_prev;
  const bool has_prev = b.q_prev2 && b.q_prev2->bones.size() == qt.bones.size();
  std::vector<int> near;
  std::vector<double> near_phi;  // φ of each near vertex at t
  for (const VertexCluster& cl : clusters_) {
    // A cluster whose centre, carried by its bone, is farther from the object
    // than its radius (slack included) plus the reach holds no near vertex.
    const Vec3 xc = qt.bones[cl.bone] * cl.center;
    const double motion_c = has_prev ? 2 * (xc - b.q_prev2->bones[cl.bone] * cl.center).norm() : 0.0;
    if (field_->distance(T_inv * xc) > cl.radius + options_.margin + motion_c + object_motion) continue;
    for (int v : cl.vertices) {
      const Vec3 x = vertices_.world_point(v, qt);
      const double motion = has_prev ? 2 * (x - vertices_.world_point(v, *b.q_prev2)).norm() : 0.0;
      const double reach = options_.margin + motion + object_motion;
      if (bounded) {
        const Vec3 lo = box.min.array() - reach, hi = box.max.array() + reach;
        if ((x.array() < lo.array()).any() || (x.array() > hi.array()).any()) continue;
      }
      const double phi = field_->distance(T_inv * x);
      if (phi < reach) near.push_back(v), near_phi.push_back(phi);
    }
  }
  std::vector<size_t> order(near.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t i, size_t j) { return near[i] < near[j]; });
  {
    std::vector<int> n2;
    std::vector<double> p2;
    for (size_t i : order) n2.push_back(near[i]), p2.push_back(near_phi[i]);
    near.swap(n2);
    near_phi.swap(p2);
  }
  // Candidate faces and their samples.
  std::vector<char> face_mark(a.surface_faces.rows(), 0);
  c.faces.clear();
  for (int v : near)
    for (int fc : vertex_faces_[v])
      if (!face_mark[fc]) face_mark[fc] = 1, c.faces.push_back(fc);
  std::sort(c.faces.begin(), c.faces.end());
  c.samples.clear();
  c.face_first.assign(1, 0);
  c.vertices.clear();
  c.vertex_slot.clear();
  for (int fc : c.faces) {
    append_face_samples(a.surface_rest, a.surface_faces, fc, options_.spacing, c.samples);
    c.face_first.push_back(int(c.samples.size()));
    for (int i = 0; i < 3; ++i) {
      const int v = a.surface_faces(fc, i);
      if (c.vertex_slot.emplace(v, int(c.vertices.size())).second) c.vertices.push_back(v);
    }
  }
  // Patch nodes: Simulated nodes within the radius of a near vertex (unposed),
  // and every node still displaced.
  c.nodes.clear();
  c.node_slot.clear();
  auto add_node = [&](int n) {
    if (c.node_slot.emplace(n, int(c.nodes.size())).second) c.nodes.push_back(n);
  };
  if (options_.patch) {
    const double r2 = options_.patch_radius * options_.patch_radius;
    if (!near.empty()) {
      // Bounding box of the near vertices first: most nodes are far.
      Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
      for (int v : near) {
        lo = lo.cwiseMin(Vec3(a.surface_rest.row(v).transpose()));
        hi = hi.cwiseMax(Vec3(a.surface_rest.row(v).transpose()));
      }
      lo.array() -= options_.patch_radius;
      hi.array() += options_.patch_radius;
      // Each node within the radius, ranked by its distance to a near vertex
      // plus that vertex's φ: the deepest contact's nodes first when the patch
      // is over max_patch_nodes (a broad press).
      std::vector<std::pair<double, int>> ranked;
      for (int n = 0; n < a.tet.num_nodes(); ++n) {
        if (a.node_role.size() && a.node_role[n] != int(NodeRole::Simulated)) continue;
        const Vec3 y = a.tet.nodes.row(n).transpose();
        if ((y.array() < lo.array()).any() || (y.array() > hi.array()).any()) continue;
        double rank = std::numeric_limits<double>::infinity();
        for (size_t i = 0; i < near.size(); ++i) {
          const double d2 = (y - a.surface_rest.row(near[i]).transpose()).squaredNorm();
          if (d2 <= r2) rank = std::min(rank, std::sqrt(d2) + near_phi[i]);
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
  std::sort(c.nodes.begin(), c.nodes.end());
  c.node_slot.clear();
  for (int i = 0; i < int(c.nodes.size()); ++i) c.node_slot[c.nodes[i]] = i;
  std::vector<char> tet_mark(a.tet.num_elements(), 0);
  c.tets.clear();
  for (int n : c.nodes)
    for (int t : node_tets_[n])
      if (!tet_mark[t]) tet_mark[t] = 1, c.tets.push_back(t);
  std::sort(c.tets.begin(), c.tets.end());
  // Predictions and the warm start.
  const size_t P = c.nodes.size();
  c.x_star.assign(P, Vec3::Zero());
  c.d_pred.assign(P, Vec3::Zero());
  c.du = VecX::Zero(3 * P);
  c.inner_iterations = c.minimizations = 0;
  c.solved = c.linearized = false;
  for (size_t i = 0; i < P; ++i) {
    const int n = c.nodes[i];
    const Vec3 xt = nodes_.world_point(n, qt);
    c.x_star[i] = has_prev ? Vec3(2 * xt - nodes_.world_point(n, *b.q_prev2)) : xt;
    const auto h = c.history.find(n);
    if (h == c.history.end()) continue;
    c.d_pred[i] = 2 * h->second.d_t - h->second.d_prev;
    c.du.segment<3>(3 * i) = h->second.du;
  }
  c.samples_in_patch.clear();
  c.sample_x_star.clear();
  for (int s = 0; s < int(sample_node_.size()); ++s)
    if (c.node_slot.count(sample_node_[s])) {
      const Vec3 xt = inertia_points_.world_point(s, qt);
      c.samples_in_patch.push_back(s);
      c.sample_x_star.push_back(has_prev ? Vec3(2 * xt - inertia_points_.world_point(s, *b.q_prev2)) : xt);
    }
}

bool ContactPatchTerm::active(const StepContext& ctx) const {
  const PatchCache& c = patch_cache(ctx, name());
  return !c.faces.empty() || !c.nodes.empty();
}

double ContactPatchTerm::evaluate_patch(const StepContext& ctx, const Configuration& q, const VecX& du,
                                        const EvaluationMode& mode, Evaluation& out) const {
  const bool q_derivatives = mode.q_derivatives, p_derivatives = mode.p_derivatives || mode.q_derivatives;
  const PatchCache& c = patch_cache(ctx, name());
  const Avatar& a = *avatar_;
  const DofLayout& L = local_layout(ctx);
  const int ob = object_offset(ctx);  // the object's 6 DoFs in the term's system, or −1
  const int nq = std::max(L.end(), ob + 6), np = int(du.size()), z0 = L.z_offset();
  const double inv_h2 = 1.0 / (ctx.h * ctx.h);
  out = Evaluation();
  out.gp = VecX::Zero(np);
  out.Hpp = MatX::Zero(np, np);
  if (q_derivatives) {
    out.gq = VecX::Zero(nq);
    out.Hqq = MatX::Zero(nq, nq);
    out.Hqp = MatX::Zero(nq, np);
    out.K0pp = MatX::Zero(np, np);
  }
  double E = 0;
  Eigen::Matrix<double, 3, Eigen::Dynamic> J;
  std::vector<int> cols;
  auto simulated = [&](int n) { return a.node_role.size() == 0 || a.node_role[n] == int(NodeRole::Simulated); };

  // Inertia and gravity of the patch's offsets.
  std::vector<Mat3> A(c.nodes.size());
  for (size_t i = 0; i < c.nodes.size(); ++i) {
    const int n = c.nodes[i];
    const double m = node_mass_[n];
    A[i] = skinning_rotation_blend(a.node_weights.row(n), q.bones);
    const Vec3 d = A[i] * du.segment<3>(3 * i);
    const Vec3 e = d - c.d_pred[i];
    const Vec3 r = nodes_.world_point(n, q) - c.x_star[i];
    E += 0.5 * m * inv_h2 * (r + e).squaredNorm() - m * ctx.gravity.dot(d);
    if (!p_derivatives) continue;
    const Vec3 fd = m * inv_h2 * (r + e) - m * ctx.gravity;  // ∂Φ/∂d
    out.gp.segment<3>(3 * i) += A[i].transpose() * fd;
    out.Hpp.block<3, 3>(3 * i, 3 * i) += m * inv_h2 * A[i].transpose() * A[i];
    if (!q_derivatives) continue;
    add_offset_rotation_gradient(a.node_weights.row(n), q.bones, du.segment<3>(3 * i), fd, L, out.gq);
    nodes_.local_jacobian(n, q, L, J, cols);
    const Vec3 ge = m * inv_h2 * (r + e);
    const MatX JA = J.transpose() * (m * inv_h2 * A[i]);
    const MatX JJ = (m * inv_h2) * (J.transpose() * J);
    for (size_t k = 0; k < cols.size(); ++k) {
      out.gq[cols[k]] += J.col(k).dot(ge);
      out.Hqp.block<1, 3>(cols[k], 3 * i) += JA.row(k);
      for (size_t l = 0; l < cols.size(); ++l) out.Hqq(cols[k], cols[l]) += JJ(long(k), long(l));
    }
  }
  // What the subspace's inertia term holds of the patch: its samples there
  // (header comment, "What the patch subtracts").
  if (mode.subspace_energy || q_derivatives)
    for (size_t k = 0; k < c.samples_in_patch.size(); ++k) {
      const int s = c.samples_in_patch[k];
      const double m = inertia_mass_[s];
      const Vec3 r = inertia_points_.world_point(s, q) - c.sample_x_star[k];
      E -= 0.5 * m * inv_h2 * r.squaredNorm();
      if (!q_derivatives) continue;
      inertia_points_.local_jacobian(s, q, L, J, cols);
      const Vec3 gr = m * inv_h2 * r;
      const MatX JJ = (m * inv_h2) * (J.transpose() * J);
      for (size_t i = 0; i < cols.size(); ++i) {
        out.gq[cols[i]] -= J.col(long(i)).dot(gr);
        for (size_t j = 0; j < cols.size(); ++j) out.Hqq(cols[i], cols[j]) -= JJ(long(i), long(j));
      }
    }

  // Elasticity: the exact change δu brings to each patch tet.
  // With mean dilatation the subspace holds only α of each tet's own bulk
  // stiffness (subspace_density), so Φ_zz gains the rest, (1 − α) κ_t V_t
  // (Wᵀ b_t)(Wᵀ b_t)ᵀ with b_t the tet's volume-change gradient (κ_t = vᵀH₂v/9,
  // the rank-one bulk part of the material's small-strain Hessian): a PSD
  // Gauss–Newton part of Φ_zz that the one Newton step needs (without it the
  // step overshoots where the patch is). Collected as columns over the
  // handles the patch's tets touch, then one rank update.
  const bool bulk_hessian = q_derivatives && dilatation_cell_.size() > 0;
  std::unordered_map<int, int> bulk_handle;  // handle → compressed index
  std::vector<std::pair<int, Vec3>> bulk_entries;
  std::vector<int> bulk_first{0};
  for (int t : c.tets) {
    std::array<int, 4> slot;
    Mat3 F0 = Mat3::Identity(), F1 = Mat3::Identity();
    for (int k = 0; k < 4; ++k) {
      const int n = a.tet.elements(t, k);
      Vec3 us = Vec3::Zero();
      if (simulated(n))
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, n); it; ++it)
          us += it.value() * q.z.segment<3>(3 * it.col());
      const auto s = c.node_slot.find(n);
      slot[k] = s == c.node_slot.end() ? -1 : s->second;
      const Vec3 u1 = slot[k] >= 0 ? Vec3(us + du.segment<3>(3 * slot[k])) : us;
      F0 += us * grads_[t].row(k);
      F1 += u1 * grads_[t].row(k);
    }
    Mat3 P0, P1;
    Mat9 H1;
    const double psi1 = strain_energy_density(F1, materials_[t], p_derivatives ? &P1 : nullptr,
                                              p_derivatives ? &H1 : nullptr, mode.project);
    if (!std::isfinite(psi1)) return out.energy = std::numeric_limits<double>::infinity();
    const double V = tet_volume_[t];
    E += V * psi1;
    // What the subspace's elastic term holds of the tet: constant while δu varies (left out then).
    Mat9 H0, H2;
    if (mode.subspace_energy || q_derivatives) H2 = linearized_hessian(materials_[t]);
    if (mode.subspace_energy || q_derivatives)
      E -= V * subspace_density(t, F0, H2, q_derivatives ? &P0 : nullptr, q_derivatives ? &H0 : nullptr);
    if (!p_derivatives) continue;
    // Element blocks K_kl (3x3) = V Σ_{b,l} ∇N_k[b] H(i + 3b, j + 3l) ∇N_l[l].
    auto element_blocks = [&](const Mat9& H) {
      std::array<std::array<Mat3, 4>, 4> K;
      for (int k = 0; k < 4; ++k)
        for (int l = 0; l < 4; ++l) {
          const Vec3 gk = grads_[t].row(k).transpose(), gl = grads_[t].row(l).transpose();
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
              double v = 0;
              for (int bb = 0; bb < 3; ++bb)
                for (int ll = 0; ll < 3; ++ll) v += gk[bb] * H(i + 3 * bb, j + 3 * ll) * gl[ll];
              K[k][l](i, j) = V * v;
            }
        }
      return K;
    };
    const auto K = element_blocks(H1);
    // The cross block Φ_zp = Wᵀ K(Wz + δu) is taken at the subspace's own
    // state, Wᵀ K(Wz): the Schur complement Wᵀ K0 (K1 + M + C)⁻¹ K0 W then
    // stays below the subspace's stiffness of these tets, Wᵀ K0 W, which its
    // elastic term carries, so the step's Hessian stays positive semi-definite
    // where the dent stiffens the tissue (K1 ≫ K0 under the Fung saturation).
    // Only the Hessian is approximated: the gradient and the energy are exact.
    std::array<std::array<Mat3, 4>, 4> K0;
    if (q_derivatives) K0 = element_blocks(H0);
    if (bulk_hessian && dilatation_cell_[t] >= 0) {
      Vec9 v = Vec9::Zero();
      v[0] = v[4] = v[8] = 1.0;
      const double kappa = v.dot(H2 * v) / 9.0;
      const double scale = std::sqrt((1.0 - kPerTetVolumeShare) * kappa * V);
      for (int k = 0; k < 4; ++k) {
        const int n = a.tet.elements(t, k);
        if (!simulated(n)) continue;
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, n); it; ++it) {
          const int h = bulk_handle.try_emplace(int(it.col()), int(bulk_handle.size())).first->second;
          bulk_entries.emplace_back(h, scale * it.value() * grads_[t].row(k).transpose());
        }
      }
      bulk_first.push_back(int(bulk_entries.size()));
    }
    for (int k = 0; k < 4; ++k) {
      const Vec3 gk = grads_[t].row(k).transpose();
      if (slot[k] >= 0) {
        out.gp.segment<3>(3 * slot[k]) += V * (P1 * gk);
        for (int l = 0; l < 4; ++l)
          if (slot[l] >= 0) {
            out.Hpp.block<3, 3>(3 * slot[k], 3 * slot[l]) += K[k][l];
            if (q_derivatives) out.K0pp.block<3, 3>(3 * slot[k], 3 * slot[l]) += K0[k][l];
          }
      }
      if (!q_derivatives) continue;
      const int n = a.tet.elements(t, k);
      if (!simulated(n)) continue;
      const Vec3 dg = V * ((P1 - P0) * gk);
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, n); it; ++it) {
        const int row = z0 + 3 * int(it.col());
        out.gq.segment<3>(row) += it.value() * dg;
        for (int l = 0; l < 4; ++l)
          if (slot[l] >= 0) out.Hqp.block<3, 3>(row, 3 * slot[l]) += it.value() * K0[k][l];
      }
    }
  }

  if (bulk_hessian && !bulk_handle.empty()) {
    MatX C = MatX::Zero(3 * long(bulk_handle.size()), long(bulk_first.size()) - 1);
    for (size_t e = 0; e + 1 < bulk_first.size(); ++e)
      for (int i = bulk_first[e]; i < bulk_first[e + 1]; ++i)
        C.block<3, 1>(3 * bulk_entries[size_t(i)].first, long(e)) += bulk_entries[size_t(i)].second;
    MatX G = MatX::Zero(C.rows(), C.rows());
    G.selfadjointView<Eigen::Lower>().rankUpdate(C);
    for (const auto& [ha, ia] : bulk_handle)
      for (const auto& [hb, ib] : bulk_handle)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) {
            const int r = 3 * ia + i, s = 3 * ib + j;
            out.Hqq(z0 + 3 * ha + i, z0 + 3 * hb + j) += r >= s ? G(r, s) : G(s, r);
          }
  }

  // Contact over the candidate faces' samples.
  const Isometry T = dynamic_ ? Isometry(ctx.bound[1].q->bones[0] * shape_in_frame_) : c.field_pose;
  const Isometry T_inv = T.inverse();
  // A dynamic object: g_o = Σ_s −J_oᵀ g_s, H_oo = Σ_s J_oᵀ H_s J_o, and per vertex
  // N_v = Σ_s −λ_v J_oᵀ H_s, J_o = [−[x_s]×, I] (the object's point at x_s moves by ω × x + v).
  using Mat63 = Eigen::Matrix<double, 6, 3>;
  std::vector<Mat63> Nv(ob >= 0 && q_derivatives ? c.vertices.size() : 0, Mat63::Zero());
  const double kappa = options_.pressure_stiffness;
  const size_t nv = c.vertices.size();
  std::vector<Vec3> xv(nv);
  std::vector<Mat3> Av(nv);
  std::vector<Vec3> offset(nv);  // Σ_c b_c δu_c of each vertex (unposed)
  // Patch coupling of each vertex: (patch slot, barycentric weight) over its tet's nodes.
  std::vector<std::array<std::pair<int, double>, 4>> couple(nv);
  for (size_t i = 0; i < nv; ++i) {
    const int v = c.vertices[i];
    Av[i] = skinning_rotation_blend(a.surface_weights.row(v), q.bones);
    Vec3 off = Vec3::Zero();
    const int t = a.surface_tet[v];
    for (int k = 0; k < 4; ++k) {
      const auto s = c.node_slot.find(a.tet.elements(t, k));
      couple[i][k] = {s == c.node_slot.end() ? -1 : s->second, a.surface_bary(v, k)};
      if (couple[i][k].first >= 0) off += couple[i][k].second * du.segment<3>(3 * couple[i][k].first);
    }
    offset[i] = off;
    xv[i] = vertices_.world_point(v, q) + Av[i] * off;
  }
  // Per vertex (slot): g_v = Σ_s λ_v g_s, and per vertex pair M_vw = Σ_s λ_v λ_w H_s
  // over the touching samples of their faces; the Jacobians are applied once per vertex pair.
  std::vector<Vec3> gv(p_derivatives ? nv : 0, Vec3::Zero());
  std::unordered_map<long, Mat3> Mvw;
  for (size_t fi = 0; fi < c.faces.size(); ++fi) {
    const int fc = c.faces[fi];
    std::array<int, 3> vs;
    for (int i = 0; i < 3; ++i) vs[i] = c.vertex_slot.at(a.surface_faces(fc, i));
    std::array<Vec3, 3> g{Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
    std::array<std::array<Mat3, 3>, 3> M;
    for (auto& row : M) row.fill(Mat3::Zero());
    bool touching = false;
    for (int s = c.face_first[fi]; s < c.face_first[fi + 1]; ++s) {
      const SkinFaceSample& smp = c.samples[s];
      const Vec3 x = smp.lambda[0] * xv[vs[0]] + smp.lambda[1] * xv[vs[1]] + smp.lambda[2] * xv[vs[2]];
      const geometry::SdfSample sd = field_->evaluate(T_inv * x);
      if (!(sd.distance < 0)) continue;
      touching = p_derivatives;
      const double k = kappa * smp.area, d = sd.distance;
      const Vec3 nrm = T.linear() * sd.gradient;
      E += 0.5 * k * d * d;
      out.force -= k * d * nrm;
      ++out.active;
      out.depth = std::max(out.depth, -d);
      out.area += smp.area;
      if (!p_derivatives) continue;
      const Mat3 H = k * nrm * nrm.transpose();
      for (int i = 0; i < 3; ++i) {
        g[i] += smp.lambda[i] * k * d * nrm;
        for (int j = 0; j < 3; ++j) M[i][j] += smp.lambda[i] * smp.lambda[j] * H;
      }
      if (Nv.empty()) continue;
      Mat63 JoT;  // J_oᵀ
      JoT << hat(x), Mat3::Identity();
      const Vec3 gs = k * d * nrm;
      out.gq.segment<6>(ob) -= JoT * gs;
      out.Hqq.block<6, 6>(ob, ob) += JoT * H * JoT.transpose();
      for (int i = 0; i < 3; ++i) Nv[vs[i]] -= smp.lambda[i] * (JoT * H);
    }
    if (!touching) continue;
    for (int i = 0; i < 3; ++i) {
      gv[vs[i]] += g[i];
      for (int j = 0; j < 3; ++j)
        Mvw.try_emplace(long(vs[i]) * long(nv) + vs[j], Mat3::Zero()).first->second += M[i][j];
    }
  }
  if (!p_derivatives || Mvw.empty()) return out.energy = E;
  // Patch DoFs: ∂x_v/∂δu_c = b_vc A_v.
  for (size_t v = 0; v < nv; ++v)
    for (const auto& [pi, bi] : couple[v])
      if (pi >= 0 && bi != 0.0) out.gp.segment<3>(3 * pi) += (bi * Av[v]).transpose() * gv[v];
  for (const auto& [key, M] : Mvw) {
    const int v = int(key / long(nv)), w = int(key % long(nv));
    for (const auto& [pi, bi] : couple[v]) {
      if (pi < 0 || bi == 0.0) continue;
      const Mat3 BM = (bi * Av[v]).transpose() * M;
      for (const auto& [pj, bj] : couple[w])
        if (pj >= 0 && bj != 0.0) out.Hpp.block<3, 3>(3 * pi, 3 * pj) += BM * (bj * Av[w]);
    }
  }
  if (!q_derivatives) return out.energy = E;
  // Subspace DoFs: ∂x_v/∂q = J_v (and the offsets' rotation with the bones).
  std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>> Jv(nv);
  std::vector<std::vector<int>> cv(nv);
  std::vector<char> touched(nv, 0);
  for (const auto& [key, M] : Mvw) touched[size_t(key / long(nv))] = 1;
  for (size_t v = 0; v < nv; ++v) {
    if (!touched[v]) continue;
    vertices_.local_jacobian(c.vertices[v], q, L, Jv[v], cv[v]);
    add_offset_rotation_gradient(a.surface_weights.row(c.vertices[v]), q.bones, offset[v], gv[v], L, out.gq);
    const Eigen::VectorXd gq = Jv[v].transpose() * gv[v];
    for (size_t k = 0; k < cv[v].size(); ++k) out.gq[cv[v][k]] += gq[k];
  }
  for (size_t v = 0; v < Nv.size(); ++v) {
    if (!touched[v]) continue;
    // Object rows: N_v J_v against the body, N_v b A_v against the patch.
    const Eigen::Matrix<double, 6, Eigen::Dynamic> B = Nv[v] * Jv[v];
    for (size_t k = 0; k < cv[v].size(); ++k) {
      out.Hqq.block<6, 1>(ob, cv[v][k]) += B.col(long(k));
      out.Hqq.block<1, 6>(cv[v][k], ob) += B.col(long(k)).transpose();
    }
    for (const auto& [pj, bj] : couple[v])
      if (pj >= 0 && bj != 0.0) out.Hqp.block<6, 3>(ob, 3 * pj) += Nv[v] * (bj * Av[v]);
  }
  for (const auto& [key, M] : Mvw) {
    const int v = int(key / long(nv)), w = int(key % long(nv));
    const Eigen::Matrix<double, Eigen::Dynamic, 3> JM = Jv[v].transpose() * M;
    const MatX B = JM * Jv[w];
    for (size_t k = 0; k < cv[v].size(); ++k)
      for (size_t l = 0; l < cv[w].size(); ++l) out.Hqq(cv[v][k], cv[w][l]) += B(long(k), long(l));
    for (const auto& [pj, bj] : couple[w]) {
      if (pj < 0 || bj == 0.0) continue;
      const Eigen::Matrix<double, Eigen::Dynamic, 3> C = JM * (bj * Av[w]);
      for (size_t k = 0; k < cv[v].size(); ++k) out.Hqp.block<1, 3>(cv[v][k], 3 * pj) += C.row(long(k));
    }
  }
  return out.energy = E;
}

namespace {
bool same_configuration(const Configuration& a, const Configuration& b) {
  if (a.z.size() != b.z.size() || a.bones.size() != b.bones.size() || a.z != b.z) return false;
  for (size_t j = 0; j < a.bones.size(); ++j)
    if (a.bones[j].matrix() != b.bones[j].matrix()) return false;
  return true;
}
}  // namespace

VecX ContactPatchTerm::minimize_patch(const StepContext& ctx, const Configuration& q) const {
  PatchCache& c = patch_cache(ctx, name());
  if (c.du.size() == 0) return c.du;
  // The integrator evaluates the final configuration several times (trial,
  // report): the minimizer is kept.
  const Isometry object = dynamic_ ? ctx.bound[1].q->bones[0] : Isometry::Identity();
  if (c.solved && same_configuration(q, c.q_solved) && object.matrix() == c.object_solved.matrix()) return c.du;
  VecX du = c.du;
  // Warm start from the last linearization: the back-substitution of the
  // bordered Newton system for the change of z (the bones' change is left out).
  if (c.linearized && c.z_lin.size() == q.z.size()) du = c.du_lin - c.Hpp_llt.solve(c.Hpz * (q.z - c.z_lin));
  Evaluation ev, trial;
  ++c.minimizations;
  EvaluationMode exact, energy_only;
  exact.project = false;
  exact.subspace_energy = false;
  energy_only.p_derivatives = false;
  energy_only.subspace_energy = false;
  // Newton on δu: the exact element Hessians (quadratic convergence) unless
  // compression makes them indefinite, then their PSD majorizers; Armijo
  // backtracking; stops when the Newton decrement −gᵀs falls below
  // inner_tolerance × |Φ| (or the gradient vanishes).
  // A start that inverts a tet (the warm start, or the subspace itself at
  // this q): the last minimizer, then no patch displacement; if every start
  // is inadmissible the term's energy is +inf there and the step backtracks.
  if (!std::isfinite(evaluate_patch(ctx, q, du, energy_only, trial))) {
    du = c.du;
    if (!std::isfinite(evaluate_patch(ctx, q, du, energy_only, trial))) du.setZero();
  }
  for (int it = 0; it < options_.max_inner_iterations; ++it) {
    const double E0 = evaluate_patch(ctx, q, du, exact, ev);
    if (!std::isfinite(E0)) break;
    if (ev.gp.norm() < 1e-12) break;
    Eigen::LLT<MatX> llt(ev.Hpp);
    if (llt.info() != Eigen::Success) {
      EvaluationMode projected = exact;
      projected.project = true;
      evaluate_patch(ctx, q, du, projected, ev);
      llt.compute(ev.Hpp);
      if (llt.info() != Eigen::Success) {
        // PSD by construction and PD with mass: only a degenerate tet gets here.
        ev.Hpp.diagonal() *= 1.0 + 1e-8;
        llt.compute(ev.Hpp);
        require(llt.info() == Eigen::Success, name(), ": the patch's Hessian is not positive definite");
      }
    }
    const VecX step = llt.solve(-ev.gp);
    const double slope = ev.gp.dot(step);
    if (-slope <= options_.inner_tolerance * std::max(std::abs(E0), 1e-12)) break;
    double alpha = 1;
    bool ok = false;
    for (int halving = 0; halving < 30; ++halving, alpha *= 0.5) {
      const double E1 = evaluate_patch(ctx, q, du + alpha * step, energy_only, trial);
      if (std::isfinite(E1) && E1 <= E0 + 1e-4 * alpha * slope + 1e-15 * std::abs(E0)) {
        ok = true;
        break;
      }
    }
    if (!ok) break;
    du += alpha * step;
    ++c.inner_iterations;
    if (alpha * step.cwiseAbs().maxCoeff() < 1e-13) break;
  }
  c.du = du;
  c.solved = true;
  c.q_solved = q;
  c.object_solved = object;
  return du;
}

double ContactPatchTerm::compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const {
  const VecX du = minimize_patch(ctx, q);
  Evaluation ev;
  EvaluationMode mode;
  mode.q_derivatives = grad || hess;
  mode.p_derivatives = hess != nullptr;
  const double E = evaluate_patch(ctx, q, du, mode, ev);
  if (!std::isfinite(E) || (!grad && !hess)) return E;
  PatchCache& c = patch_cache(ctx, name());
  if (grad) *grad += ev.gq;
  if (!hess) return E;
  *hess += ev.Hqq;
  if (du.size() == 0) return E;
  // Schur complement over the rows of the layout the patch touches.
  std::vector<int> rows;
  for (int r = 0; r < ev.Hqp.rows(); ++r)
    if (ev.Hqp.row(r).squaredNorm() > 0) rows.push_back(r);
  if (rows.empty()) return E;
  MatX Hc(ev.Hqp.cols(), int(rows.size()));
  for (size_t k = 0; k < rows.size(); ++k) Hc.col(int(k)) = ev.Hqp.row(rows[k]).transpose();
  Eigen::LLT<MatX>& llt = c.Hpp_llt;
  llt.compute(ev.Hpp);
  require(llt.info() == Eigen::Success, name(), ": the patch's Hessian is not positive definite");
  // The complement must stay below what the other terms carry for these DoFs
  // (Wᵀ K0 W over the patch tets, the nodes' inertia, the contact): by the
  // element-wise block argument it does when Φ_pp ⪰ K0_pp + M + C, i.e. when
  // the dented state is at least as stiff as the subspace's own (K1 ⪰ K0 over
  // the patch DoFs). When the patch relaxes a strained subspace state, K1 ≪ K0
  // and the complement can exceed the whole step's Hessian many times (no
  // diagonal shift makes it positive definite): Φ_pp + K0_pp is used instead,
  // which is ⪰ K0_pp + M + C because K1 is PSD-projected. Only the Hessian
  // changes; in the first case it is as before.
  Eigen::LLT<MatX> below(ev.Hpp - ev.K0pp + MatX::Identity(ev.Hpp.rows(), ev.Hpp.cols()) *
                                                (1e-9 * ev.Hpp.diagonal().cwiseAbs().maxCoeff()));
  const bool relaxed = below.info() != Eigen::Success;
  Eigen::LLT<MatX> guarded;
  if (relaxed) guarded.compute(ev.Hpp + ev.K0pp);
  require(!relaxed || guarded.info() == Eigen::Success, name(), ": the patch's guarded Hessian is not positive definite");
  const DofLayout& L = local_layout(ctx);
  c.linearized = true;
  c.z_lin = q.z;
  c.du_lin = du;
  c.Hpz = ev.Hqp.middleRows(L.z_offset(), L.num_reduced).transpose();
  const MatX X = (relaxed ? guarded : llt).matrixL().solve(Hc);
  const MatX S = X.transpose() * X;
  for (size_t k = 0; k < rows.size(); ++k)
    for (size_t l = 0; l < rows.size(); ++l) (*hess)(rows[k], rows[l]) -= S(int(k), int(l));
  return E;
}

std::vector<TermQuantity> ContactPatchTerm::report(const StepContext& ctx, const Configuration& q) const {
  PatchCache& c = patch_cache(ctx, name());
  const VecX du = minimize_patch(ctx, q);
  Evaluation ev;
  EvaluationMode mode;
  mode.p_derivatives = false;
  evaluate_patch(ctx, q, du, mode, ev);
  double max_du = 0;
  VecX packed(4 * c.nodes.size());
  for (size_t i = 0; i < c.nodes.size(); ++i) {
    const int n = c.nodes[i];
    PatchHistory& h = c.history[n];
    h.du_next = du.segment<3>(3 * i);
    h.d_next = skinning_rotation_blend(avatar_->node_weights.row(n), q.bones) * h.du_next;
    max_du = std::max(max_du, h.du_next.norm());
    packed.segment<4>(4 * i) << double(n), h.du_next;
  }
  return {{"force", "N", ev.force},
          {"active_samples", "", VecX::Constant(1, ev.active)},
          {"max_penetration", "m", VecX::Constant(1, ev.depth)},
          {"contact_area", "m^2", VecX::Constant(1, ev.area)},
          {"patch_nodes", "", VecX::Constant(1, double(c.nodes.size()))},
          {"max_patch_displacement", "m", VecX::Constant(1, max_du)},
          {"patch_displacement", "m", packed},
          {"patch_iterations", "", VecX::Constant(1, c.inner_iterations)},
          {"patch_minimizations", "", VecX::Constant(1, c.minimizations)}};
}

Points patch_surface_displacement(const Avatar& a, const StepReport& report, int body) {
  std::unordered_map<int, Vec3> du;
  for (const TermQuantityReport& q : report.quantities) {
    if (q.body != body || q.name != "patch_displacement") continue;
    require(q.value.size() % 4 == 0, "patch_surface_displacement: '", q.term, "' reports ", q.value.size(),
            " values, expected 4 per patch node");
    for (size_t i = 0; i < q.value.size(); i += 4) {
      const int n = int(q.value[i]);
      require(n >= 0 && n < a.tet.num_nodes(), "patch_surface_displacement: node ", n, " out of [0, ",
              a.tet.num_nodes(), ")");
      du.try_emplace(n, Vec3::Zero()).first->second += Vec3(q.value[i + 1], q.value[i + 2], q.value[i + 3]);
    }
  }
  Points u = Points::Zero(a.surface_rest.rows(), 3);
  if (du.empty()) return u;
  for (int v = 0; v < u.rows(); ++v)
    for (int c = 0; c < 4; ++c) {
      const auto it = du.find(a.tet.elements(a.surface_tet[v], c));
      if (it != du.end()) u.row(v) += a.surface_bary(v, c) * it->second.transpose();
    }
  return u;
}

}  // namespace sflsh
