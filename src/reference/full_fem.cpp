#include "sflsh/reference/full_fem.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "reference/full_fem_cholmod.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/material.hpp"

namespace sflsh {

FullFem::FullFem(std::shared_ptr<const Avatar> avatar, FullFemOptions options)
    : avatar_(std::move(avatar)), options_(std::move(options)), chol_(std::make_unique<Cholmod>()) {
  require(avatar_ != nullptr, "FullFem: null avatar");
  require(options_.h > 0, "FullFemOptions::h = ", options_.h, " s, expected > 0");
  const Avatar& a = *avatar_;
  const int N = a.tet.num_nodes(), T = a.tet.num_elements();
  require(a.node_weights.rows() == N, "FullFem: node_weights has ", a.node_weights.rows(), " rows, expected #N = ", N);
  node_free_.assign(N, -1);
  for (int n = 0; n < N; ++n)
    if (a.node_role.size() == 0 || a.node_role[n] == int(NodeRole::Simulated)) {
      node_free_[n] = int(free_node_.size());
      free_node_.push_back(n);
    }
  require(!free_node_.empty(), "FullFem: the avatar has no Simulated nodes");

  grads_ = fem::tet_gradients(a.tet);
  volume_.resize(T);
  mass_ = VecX::Zero(N);
  for (int t = 0; t < T; ++t) {
    Mat3 D;
    for (int c = 1; c < 4; ++c) D.col(c - 1) = (a.tet.nodes.row(a.tet.elements(t, c)) - a.tet.nodes.row(a.tet.elements(t, 0))).transpose();
    volume_[t] = D.determinant() / 6.0;
    const RegionMaterial& material = tet_material(a, t);
    materials_.emplace_back(material, tet_frame(a, t));
    for (int c = 0; c < 4; ++c) mass_[a.tet.elements(t, c)] += material.density * volume_[t] / 4.0;
  }

  build_pattern(false);

  surface_ = PosedPoints::at_surface(a);
  require(a.surface_tet.size() == a.surface_rest.rows() && a.surface_bary.rows() == a.surface_rest.rows() &&
              a.surface_weights.rows() == a.surface_rest.rows(),
          "FullFem: surface_tet / surface_bary / surface_weights do not have #V = ", a.surface_rest.rows(), " rows");
  reset(std::vector<Isometry>(24, Isometry::Identity()));
}

FullFem::~FullFem() = default;

void FullFem::build_pattern(bool couple_skin_faces) {
  const Avatar& a = *avatar_;
  const int T = a.tet.num_elements();
  // Sparsity pattern (lower triangle) and the value slot of every contribution.
  const int n = num_dofs();
  std::vector<Eigen::Triplet<double, int>> pattern;
  auto dof = [&](int node, int axis) { return node_free_[node] < 0 ? -1 : 3 * node_free_[node] + axis; };
  for (int t = 0; t < T; ++t)
    for (int r = 0; r < 12; ++r)
      for (int c = 0; c < 12; ++c) {
        const int i = dof(a.tet.elements(t, r / 3), r % 3), j = dof(a.tet.elements(t, c / 3), c % 3);
        if (i >= 0 && j >= 0 && i >= j) pattern.emplace_back(i, j, 0.0);
      }
  for (int i = 0; i < n; ++i) pattern.emplace_back(i, i, 0.0);
  if (couple_skin_faces) {
    // Node pairs of every skin face's three tets (deduplicated per node before
    // expanding to 3x3 blocks: a face couples up to 12 nodes).
    std::vector<std::vector<int>> coupled(free_node_.size());
    for (int f = 0; f < a.surface_faces.rows(); ++f) {
      std::vector<int> nodes;
      for (int i = 0; i < 3; ++i)
        for (int c = 0; c < 4; ++c) {
          const int fr = node_free_[a.tet.elements(a.surface_tet[a.surface_faces(f, i)], c)];
          if (fr >= 0) nodes.push_back(fr);
        }
      for (int p : nodes)
        for (int q : nodes)
          if (p > q) coupled[p].push_back(q);
    }
    for (int p = 0; p < int(coupled.size()); ++p) {
      std::sort(coupled[p].begin(), coupled[p].end());
      coupled[p].erase(std::unique(coupled[p].begin(), coupled[p].end()), coupled[p].end());
      for (int q : coupled[p])
        for (int i = 0; i < 3; ++i)
          for (int l = 0; l < 3; ++l) pattern.emplace_back(3 * p + i, 3 * q + l, 0.0);
    }
  }
  chol_->H.resize(n, n);
  chol_->H.setFromTriplets(pattern.begin(), pattern.end());
  chol_->H.makeCompressed();
  auto slot = [&](int i, int j) -> int {
    if (i < 0 || j < 0 || i < j) return -1;
    return int(&chol_->H.coeffRef(i, j) - chol_->H.valuePtr());
  };
  tet_slot_.assign(size_t(T) * 144, -1);
  for (int t = 0; t < T; ++t)
    for (int r = 0; r < 12; ++r)
      for (int c = 0; c < 12; ++c)
        tet_slot_[size_t(t) * 144 + 12 * r + c] =
            slot(dof(a.tet.elements(t, r / 3), r % 3), dof(a.tet.elements(t, c / 3), c % 3));
  node_slot_.assign(free_node_.size() * 9, -1);
  for (int f = 0; f < int(free_node_.size()); ++f)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) node_slot_[9 * f + 3 * r + c] = slot(3 * f + r, 3 * f + c);
  chol_->reset_factor();  // a new pattern needs a new symbolic analysis
  face_nodes_.clear();
  skin_faces_coupled_ = couple_skin_faces;
}

Points FullFem::world_nodes(const Points& u, const std::vector<Isometry>& bones) const {
  const Avatar& a = *avatar_;
  Points x(u.rows(), 3);
  for (int n = 0; n < u.rows(); ++n) {
    const Vec3 y = (a.tet.nodes.row(n) + u.row(n)).transpose();
    Vec3 xn = Vec3::Zero();
    for (int j = 0; j < a.node_weights.cols(); ++j)
      if (a.node_weights(n, j) != 0.0) xn += a.node_weights(n, j) * (bones[j] * y);
    x.row(n) = xn.transpose();
  }
  return x;
}

void FullFem::reset(const std::vector<Isometry>& bones) {
  require(bones.size() == 24, "FullFem::reset: ", bones.size(), " bones, expected 24");
  bones_ = bones;
  u_ = Points::Zero(avatar_->tet.num_nodes(), 3);
  x_now_ = x_prev_ = world_nodes(u_, bones_);
  time_ = 0;
}

double FullFem::energy(const Points& u) const {
  return const_cast<FullFem*>(this)->evaluate(u, nullptr, false);
}

double FullFem::energy(const Points& u, VecX* gradient, Eigen::SparseMatrix<double>* hessian) const {
  require(u.rows() == avatar_->tet.num_nodes() && u.cols() == 3, "FullFem::energy: u is ", u.rows(), " by ", u.cols(),
          ", expected #N = ", avatar_->tet.num_nodes(), " by 3");
  const double E = const_cast<FullFem*>(this)->evaluate(u, gradient, hessian != nullptr);
  if (hessian) *hessian = chol_->H.selfadjointView<Eigen::Lower>();
  return E;
}

double FullFem::evaluate(const Points& u, VecX* grad, bool hessian) {
  const Avatar& a = *avatar_;
  const double inv_h2 = 1.0 / (options_.h * options_.h);
  if (grad) grad->setZero(num_dofs());
  double* values = chol_->H.valuePtr();
  if (hessian) std::fill(values, values + chol_->H.nonZeros(), 0.0);
  double E = 0;
  // Inertia and gravity on the free nodes (fixed nodes only add a constant).
  const Points x = world_nodes(u, bones_);
  for (int f = 0; f < int(free_node_.size()); ++f) {
    const int n = free_node_[f];
    const Vec3 r = (x.row(n) - x_pred_.row(n)).transpose();
    const Vec3 xn = x.row(n).transpose();
    E += 0.5 * inv_h2 * mass_[n] * r.squaredNorm() - mass_[n] * options_.gravity.dot(xn);
    if (grad) grad->segment<3>(3 * f) += A_[n].transpose() * (mass_[n] * (inv_h2 * r - options_.gravity));
    if (hessian) {
      const Mat3 M = mass_[n] * inv_h2 * A_[n].transpose() * A_[n];  // exact: x is affine in u
      for (int k = 0; k < 9; ++k)
        if (node_slot_[9 * f + k] >= 0) values[node_slot_[9 * f + k]] += M(k / 3, k % 3);
    }
  }
  // Elasticity, every tet.
  for (int t = 0; t < a.tet.num_elements(); ++t) {
    Mat3 F = Mat3::Identity();
    for (int c = 0; c < 4; ++c) F += u.row(a.tet.elements(t, c)).transpose() * grads_[t].row(c);
    Mat3 P;
    Mat9 H9;
    const double psi = strain_energy_density(F, materials_[t], grad ? &P : nullptr,
                                             hessian ? &H9 : nullptr, project_hessian_);
    if (!std::isfinite(psi)) return std::numeric_limits<double>::infinity();
    E += volume_[t] * psi;
    if (grad)
      for (int c = 0; c < 4; ++c) {
        const int f = node_free_[a.tet.elements(t, c)];
        if (f >= 0) grad->segment<3>(3 * f) += volume_[t] * (P * grads_[t].row(c).transpose());
      }
    if (hessian) {
      // K(3c + i, 3d + k) = V Σ_{b,l} ∇N_c[b] H9(i + 3b, k + 3l) ∇N_d[l].
      const int* slots = &tet_slot_[size_t(t) * 144];
      for (int c = 0; c < 4; ++c)
        for (int d = 0; d < 4; ++d) {
          const Vec3 gc = grads_[t].row(c).transpose(), gd = grads_[t].row(d).transpose();
          for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) {
              const int s = slots[12 * (3 * c + i) + 3 * d + k];
              if (s < 0) continue;
              double v = 0;
              for (int b = 0; b < 3; ++b)
                for (int l = 0; l < 3; ++l) v += gc[b] * H9(i + 3 * b, k + 3 * l) * gd[l];
              values[s] += volume_[t] * v;
            }
        }
    }
  }
  return E + evaluate_contact(u, grad, hessian, nullptr) + evaluate_anchors(u, grad, hessian, nullptr);
}

FullFemReport FullFem::step(const std::vector<Isometry>& bones_next, const std::vector<Isometry>& obstacle_poses) {
  require(bones_next.size() == 24, "FullFem::step: ", bones_next.size(), " bones, expected 24");
  require(obstacle_poses.size() == obstacles_.size(), "FullFem::step: ", obstacle_poses.size(),
          " obstacle poses, expected one per obstacle (", obstacles_.size(), ")");
  Timer total;
  FullFemReport rep;
  const Avatar& a = *avatar_;
  x_pred_ = 2.0 * x_now_ - x_prev_;
  anchor_start_.clear();  // at t: the bones and u before the step
  for (const FullFemAnchor& p : anchors_) anchor_start_.push_back(skin_point(p.vertex, u_));
  bones_ = bones_next;
  obstacle_poses_ = obstacle_poses;
  ms_contact_ = 0;
  A_.assign(a.tet.num_nodes(), Mat3::Zero());
  for (int n = 0; n < a.tet.num_nodes(); ++n)
    for (int j = 0; j < a.node_weights.cols(); ++j)
      if (a.node_weights(n, j) != 0.0) A_[n] += a.node_weights(n, j) * bones_[j].linear();
  skin_A_.assign(a.surface_rest.rows(), Mat3::Zero());
  for (size_t v = 0; v < skin_A_.size(); ++v)
    for (int j = 0; j < a.surface_weights.cols(); ++j)
      if (a.surface_weights(v, j) != 0.0) skin_A_[v] += a.surface_weights(v, j) * bones_[j].linear();

  VecX g;
  for (int it = 0; it < options_.max_iterations; ++it) {
    const double E0 = evaluate(u_, &g, true);
    require(std::isfinite(E0), "FullFem::step: inadmissible state at t = ", time_, " (inverted element)");
    rep.grad_norm = g.norm();
    if (it == 0) rep.grad_norm_initial = rep.grad_norm;
    rep.energy = E0;
    if (rep.grad_norm <= options_.gradient_tolerance * (rep.grad_norm_initial + 1e-12)) {
      rep.converged = true;
      break;
    }
    Timer tf;
    // The exact Hessian converges quadratically and is positive definite unless
    // compression outweighs the lumped masses / h²; then the elements' PSD
    // majorizers (sim/material.hpp) make it so for this iteration.
    bool factorized = chol_->factorize();
    if (!factorized) {
      project_hessian_ = true;
      evaluate(u_, &g, true);
      project_hessian_ = false;
      factorized = chol_->factorize();
      ++rep.projected_iterations;
    }
    if (!factorized) {
      // PSD elasticity + positive lumped masses make H positive definite; a failure
      // means a degenerate mass or NaN, which regularization would only hide.
      fail("FullFem::step: Hessian not positive definite at t = ", time_, " (CHOLMOD status ", chol_->common.status,
           ")");
    }
    const VecX delta = chol_->solve(-g);
    rep.ms_factorize += tf.ms();
    ++rep.iterations;
    const double slope = g.dot(delta);
    double alpha = 1.0;
    Points trial;
    bool ok = false;
    for (int halving = 0; halving < 30; ++halving, alpha *= 0.5) {
      trial = u_;
      for (int f = 0; f < int(free_node_.size()); ++f) trial.row(free_node_[f]) += alpha * delta.segment<3>(3 * f).transpose();
      const double E1 = evaluate(trial, nullptr, false);
      if (std::isfinite(E1) && (!options_.line_search || E1 <= E0 + 1e-4 * alpha * slope + 1e-15 * std::abs(E0))) {
        ok = true;
        break;
      }
    }
    if (!ok) break;  // no decrease possible at machine precision: converged as far as it goes
    u_ = trial;
    if (alpha * delta.cwiseAbs().maxCoeff() <= options_.step_tolerance) {
      rep.converged = true;
      rep.energy = evaluate(u_, &g, false);
      rep.grad_norm = g.norm();
      break;
    }
  }
  evaluate_contact(u_, nullptr, false, &rep.contacts);
  evaluate_anchors(u_, nullptr, false, &rep.anchor_forces);
  for (const Vec3& f : rep.anchor_forces) rep.anchor_force += f;
  rep.ms_contact = ms_contact_;
  x_prev_ = x_now_;
  x_now_ = world_nodes(u_, bones_);
  time_ += options_.h;
  rep.ms_total = total.ms();
  return rep;
}

Points FullFem::soft_displacement() const {
  const Avatar& a = *avatar_;
  Points u(a.surface_rest.rows(), 3);
  for (int v = 0; v < u.rows(); ++v) {
    Vec3 s = Vec3::Zero();
    for (int c = 0; c < 4; ++c) s += a.surface_bary(v, c) * u_.row(a.tet.elements(a.surface_tet[v], c)).transpose();
    u.row(v) = s.transpose();
  }
  return u;
}

Points FullFem::posed_surface() const {
  const Avatar& a = *avatar_;
  Configuration q;
  q.bones = bones_;
  q.z = VecX::Zero(a.num_reduced());
  const Points offsets = soft_displacement() + surface_pose_offsets(a, bones_);
  return surface_.world(q, &offsets);  // basis part is zero: the nodal u enters as an offset
}

}  // namespace sflsh
