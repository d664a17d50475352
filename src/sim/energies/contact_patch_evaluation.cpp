// One evaluation of the patch's Φ(q, δu) and its derivatives
// (contact_patch.hpp's header comment): inertia, elasticity, contact.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <vector>

#include "sflsh/core/rotation.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/linearized_stiffness.hpp"
#include "sflsh/sim/point_hessian.hpp"
#include "sim/energies/contact_patch_cache.hpp"
#include "sim/energies/lagged_friction.hpp"

namespace sflsh {

using contact_patch_detail::add_offset_rotation_gradient;
using contact_patch_detail::element_blocks;
using contact_patch_detail::ElementBlocks;
using contact_patch_detail::local_layout;
using contact_patch_detail::patch_cache;
using contact_patch_detail::PatchCache;
using contact_patch_detail::patched_vertex;
using contact_patch_detail::PatchedVertex;
using contact_patch_detail::tet_node_subspace_displacements;

namespace contact_patch_detail {
std::vector<Vec3> tet_node_subspace_displacements(const Avatar& a, const PatchCache& c, const VecX& z) {
  std::vector<Vec3> u(c.tet_nodes.size(), Vec3::Zero());
  for (size_t i = 0; i < c.tet_nodes.size(); ++i) {
    const int n = c.tet_nodes[i];
    if (a.node_role.size() && a.node_role[n] != int(NodeRole::Simulated)) continue;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, n); it; ++it)
      u[i] += it.value() * z.segment<3>(3 * it.col());
  }
  return u;
}

PatchedVertex patched_vertex(const Avatar& a, const PosedPoints& vertices, const PatchCache& c, int v,
                             const Configuration& q, const VecX& du) {
  PatchedVertex p;
  p.A = skinning_rotation_blend(a.surface_weights.row(v), q.bones);
  const int t = a.surface_tet[v];
  for (int k = 0; k < 4; ++k) {
    const auto s = c.node_slot.find(a.tet.elements(t, k));
    p.couple[size_t(k)] = {s == c.node_slot.end() ? -1 : s->second, a.surface_bary(v, k)};
    if (s != c.node_slot.end()) p.offset += a.surface_bary(v, k) * du.segment<3>(3 * s->second);
  }
  p.x = vertices.world_point(v, q) + p.A * p.offset;
  return p;
}
}  // namespace contact_patch_detail

Mat9 ContactPatchTerm::subspace_quadratic_hessian(int t, const Mat9& H2) const {
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
  return Hq;
}

double ContactPatchTerm::evaluate_patch(const StepContext& ctx, const Configuration& q, const VecX& du,
                                        const EvaluationMode& mode, Evaluation& out) const {
  const bool q_derivatives = mode.q_derivatives, q_hessian = q_derivatives && mode.q_hessian;
  const DofLayout& L = local_layout(ctx);
  const int ob = object_offset(ctx);  // the object's 6 DoFs in the term's system, or −1
  const int nq = std::max(L.end(), ob + 6), np = int(du.size());
  // Reset in place: the blocks keep their storage from the last evaluation
  // into `out` (a patch's blocks are a few hundred kB, and fresh pages cost
  // more than zeroing them).
  VecX gp = std::move(out.gp), gq = std::move(out.gq);
  MatX Hpp = std::move(out.Hpp), Hqq = std::move(out.Hqq), Hqp = std::move(out.Hqp);
  MatX Hzp = std::move(out.Hzp_stiffening);
  out = Evaluation();
  out.gp = std::move(gp);
  out.gp.setZero(np);
  out.Hpp = std::move(Hpp);
  out.has_Hpp = mode.pp_hessian();
  if (out.has_Hpp) out.Hpp.setZero(np, np);
  if (q_derivatives) (out.gq = std::move(gq)).setZero(nq);
  out.Hqq = std::move(Hqq);
  out.Hqp = std::move(Hqp);
  out.Hzp_stiffening = std::move(Hzp);
  if (q_hessian) {
    // The q blocks are zero outside the rows any evaluation has written (PatchCache::q_rows_written).
    const PatchCache& c = patch_cache(ctx, name());
    require(c.q_row_written.size() == size_t(nq) && (ob < 0 || c.q_row_written[size_t(ob)]), name(),
            ": the q blocks' rows were collected for another system (begin_step)");
    // A block of another size is allocated zeroed; else its written rows
    // (offset: the system's row of the block's first; square: and columns) are zeroed.
    auto reset = [&](MatX& m, long rows, long cols, int offset, bool square) {
      if (m.rows() != rows || m.cols() != cols) return void(m.setZero(rows, cols));
      auto zero_rows = [&](long j) {  // column j's written rows (column-major: down the column)
        for (int r : c.q_rows_written)
          if (r >= offset && r - offset < rows) m(r - offset, j) = 0;
      };
      if (square)
        for (int j : c.q_rows_written) zero_rows(j);
      else
        for (long j = 0; j < cols; ++j) zero_rows(j);
    };
    reset(out.Hqq, nq, nq, 0, true);
    reset(out.Hqp, nq, np, 0, false);
    reset(out.Hzp_stiffening, L.num_reduced, np, L.z_offset(), false);
  }
  const double inertia = add_patch_inertia(ctx, q, du, mode, out);
  const double elasticity = add_patch_elasticity(ctx, q, du, mode, out);
  if (!std::isfinite(elasticity)) return out.energy = std::numeric_limits<double>::infinity();
  const double contact = field_ ? add_patch_contact(ctx, q, du, mode, out) : 0.0;
  return out.energy = inertia + elasticity + contact + add_patch_anchors(ctx, q, du, mode, out);
}

double ContactPatchTerm::add_patch_inertia(const StepContext& ctx, const Configuration& q, const VecX& du,
                                           const EvaluationMode& mode, Evaluation& out) const {
  const bool q_derivatives = mode.q_derivatives, p_derivatives = mode.p_derivatives || mode.q_derivatives;
  const bool q_hessian = q_derivatives && mode.q_hessian;
  const PatchCache& c = patch_cache(ctx, name());
  const Avatar& a = *avatar_;
  const DofLayout& L = local_layout(ctx);
  const double inv_h2 = 1.0 / (ctx.h * ctx.h);
  double E = 0;
  Eigen::Matrix<double, 3, Eigen::Dynamic> J;
  std::vector<int> cols;
  MatRef Hqq(out.Hqq);  // c JᵀJ block by block (point_hessian.hpp)
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
    if (out.has_Hpp) out.Hpp.block<3, 3>(3 * i, 3 * i) += m * inv_h2 * A[i].transpose() * A[i];
    if (!q_derivatives) continue;
    add_offset_rotation_gradient(a.node_weights.row(n), q.bones, du.segment<3>(3 * i), fd, L, out.gq);
    nodes_.local_jacobian(n, q, L, J, cols);
    const Vec3 ge = m * inv_h2 * (r + e);
    if (!q_hessian) {
      for (size_t k = 0; k < cols.size(); ++k) out.gq[cols[k]] += J.col(long(k)).dot(ge);
      continue;
    }
    const MatX JA = J.transpose() * (m * inv_h2 * A[i]);
    for (size_t k = 0; k < cols.size(); ++k) {
      out.gq[cols[k]] += J.col(k).dot(ge);
      out.Hqp.block<1, 3>(cols[k], 3 * i) += JA.row(k);
    }
    add_point_hessian(nodes_, n, q, L, m * inv_h2, Hqq);
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
      for (size_t i = 0; i < cols.size(); ++i) out.gq[cols[i]] -= J.col(long(i)).dot(gr);
      if (q_hessian) add_point_hessian(inertia_points_, s, q, L, -m * inv_h2, Hqq);
    }
  return E;
}

namespace contact_patch_detail {
ElementBlocks element_blocks(const Eigen::Matrix<double, 4, 3>& G, double V, const Mat9& H) {
  std::array<Eigen::Matrix<double, 3, 9>, 4> T;  // T_k = Σ_b g_k[b] H(3b.., :)
  for (int k = 0; k < 4; ++k)
    T[k] = G(k, 0) * H.middleRows<3>(0) + G(k, 1) * H.middleRows<3>(3) + G(k, 2) * H.middleRows<3>(6);
  ElementBlocks K;
  for (int k = 0; k < 4; ++k)
    for (int l = k; l < 4; ++l) {
      K[k][l] = V * (G(l, 0) * T[k].middleCols<3>(0) + G(l, 1) * T[k].middleCols<3>(3) +
                     G(l, 2) * T[k].middleCols<3>(6));
      if (l != k) K[l][k] = K[k][l].transpose();
    }
  return K;
}
}  // namespace contact_patch_detail

// Elasticity: the exact change δu brings to each patch tet.
// With mean dilatation the subspace holds only α of each tet's own bulk
// stiffness (subspace_quadratic_hessian), so Φ_zz gains the rest, (1 − α) κ_t V_t
// (Wᵀ b_t)(Wᵀ b_t)ᵀ with b_t the tet's volume-change gradient (κ_t = vᵀH₂v/9,
// the rank-one bulk part of the material's small-strain Hessian): a PSD
// Gauss–Newton part of Φ_zz that the one Newton step needs (without it the
// step overshoots where the patch is). It depends on the patch's tets alone
// (prepare_bulk_hessian).
double ContactPatchTerm::add_patch_elasticity(const StepContext& ctx, const Configuration& q, const VecX& du,
                                              const EvaluationMode& mode, Evaluation& out) const {
  const bool q_derivatives = mode.q_derivatives, p_derivatives = mode.p_derivatives || mode.q_derivatives;
  const bool q_hessian = q_derivatives && mode.q_hessian;
  const bool hessian = mode.pp_hessian();  // a gradient alone (a trial's) needs no element Hessian
  const bool subspace = mode.subspace_energy || q_derivatives;
  PatchCache& c = patch_cache(ctx, name());
  const Avatar& a = *avatar_;
  const int z0 = local_layout(ctx).z_offset();
  auto simulated = [&](int n) { return a.node_role.size() == 0 || a.node_role[n] == int(NodeRole::Simulated); };
  const size_t nt = c.tet_nodes.size();
  const std::vector<Vec3> us = tet_node_subspace_displacements(a, c, q.z);
  // Per tet node: ∂Φ/∂u_n, and per (node, patch slot) pair the dented tets'
  // K1 − K0 (the subspace's own K0 per pair is constant: c.node_cross),
  // taken through W once per node after the loop. The cache's scratch keeps
  // their storage (fresh pages cost more than the sums).
  std::vector<Vec3>& node_grad = c.scratch_node_grad;
  std::vector<Mat3>& node_stiffening = c.scratch_node_stiffening;
  node_grad.assign(q_derivatives ? nt : 0, Vec3::Zero());
  node_stiffening.assign(q_hessian ? c.cross_slot.size() : 0, Mat3::Zero());
  const std::vector<Mat3>& node_cross = c.node_cross;
  double E = 0;
  for (size_t ti = 0; ti < c.tets.size(); ++ti) {
    const int t = c.tets[ti];
    const std::array<int, 4>& local = c.tet_local[ti];
    const std::array<int, 4>& slot = c.tet_slot[ti];
    Mat3 F0 = Mat3::Identity(), F1 = Mat3::Identity();
    for (int k = 0; k < 4; ++k) {
      const Vec3& u0 = us[size_t(local[k])];
      const Vec3 u1 = slot[k] >= 0 ? Vec3(u0 + du.segment<3>(3 * slot[k])) : u0;
      F0 += u0 * grads_[t].row(k);
      F1 += u1 * grads_[t].row(k);
    }
    Mat3 P0, P1;
    Mat9 H1;
    const double psi1 = strain_energy_density(F1, materials_[t], p_derivatives ? &P1 : nullptr,
                                              hessian ? &H1 : nullptr, mode.project);
    if (!std::isfinite(psi1)) return std::numeric_limits<double>::infinity();
    const double V = tet_volume_[t];
    E += V * psi1;
    // The subspace's quadratic share of the tet, ½ hᵀ H_q h with h = vec(F0 − I):
    // constant while δu varies (left out then).
    if (subspace) {
      const Mat3 D = F0 - Mat3::Identity();
      const Vec9 Hqh = c.tet_Hq[ti] * Eigen::Map<const Vec9>(D.data());
      E -= V * (0.5 * Eigen::Map<const Vec9>(D.data()).dot(Hqh));
      if (q_derivatives) P0 = Eigen::Map<const Mat3>(Hqh.data());
    }
    if (!p_derivatives) continue;
    ElementBlocks K;
    if (hessian) K = element_blocks(grads_[t], V, H1);
    // The cross block Φ_zp = Wᵀ K(Wz + δu) is taken as the subspace's own
    // quadratic stiffness of the tet, Wᵀ K0: the Schur complement
    // Wᵀ K0 (K1 + M + C)⁻¹ K0 W then stays below Wᵀ K0 W, which the body's
    // elastic term carries, so the step's Hessian stays positive semi-definite
    // where the dent stiffens the tissue (K1 ≫ K0 under the Fung saturation).
    // Only the Hessian is approximated: the gradient and the energy are exact.
    const ElementBlocks& K0 = c.tet_K0[ti];
    for (int k = 0; k < 4; ++k) {
      const Vec3 gk = grads_[t].row(k).transpose();
      if (slot[k] >= 0) {
        out.gp.segment<3>(3 * slot[k]) += V * (P1 * gk);
        if (hessian)
          for (int l = 0; l < 4; ++l)
            if (slot[l] >= 0) out.Hpp.block<3, 3>(3 * slot[k], 3 * slot[l]) += K[k][l];
      }
      if (!q_derivatives) continue;
      node_grad[size_t(local[k])] += V * ((P1 - P0) * gk);
      if (!q_hessian) continue;
      for (int l = 0; l < 4; ++l)
        if (slot[l] >= 0) {
          node_stiffening[size_t(c.tet_cross[ti][size_t(4 * k + l)])] += K[k][l] - K0[k][l];
        }
    }
  }
  if (q_derivatives)
    for (size_t i = 0; i < nt; ++i) {
      const int n = c.tet_nodes[i];
      if (!simulated(n)) continue;
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, n); it; ++it) {
        const int row = z0 + 3 * int(it.col());
        out.gq.segment<3>(row) += it.value() * node_grad[i];
        if (!q_hessian) continue;
        for (int e = c.cross_first[i]; e < c.cross_first[i + 1]; ++e) {
          out.Hqp.block<3, 3>(row, 3 * long(c.cross_slot[size_t(e)])) += it.value() * node_cross[size_t(e)];
          out.Hzp_stiffening.block<3, 3>(row - z0, 3 * long(c.cross_slot[size_t(e)])) +=
              it.value() * node_stiffening[size_t(e)];
        }
      }
    }
  if (q_hessian)  // the bulk share, constant over the step (prepare_bulk_hessian)
    for (size_t ia = 0; ia < c.bulk_handles.size(); ++ia)
      for (size_t ib = 0; ib < c.bulk_handles.size(); ++ib)
        out.Hqq.block<3, 3>(z0 + 3 * c.bulk_handles[ia], z0 + 3 * c.bulk_handles[ib]) +=
            c.bulk_hessian.block<3, 3>(3 * long(ia), 3 * long(ib));
  return E;
}

// Longer than the usual 120 lines: the sample loop and the chain rule that
// follows it share the per-vertex accumulators (g_v, M_vw, N_v, the vertices'
// couplings and rotations); split, they would travel as a handful of arguments.
double ContactPatchTerm::add_patch_contact(const StepContext& ctx, const Configuration& q, const VecX& du,
                                           const EvaluationMode& mode, Evaluation& out) const {
  const bool q_derivatives = mode.q_derivatives, p_derivatives = mode.p_derivatives || mode.q_derivatives;
  const bool q_hessian = q_derivatives && mode.q_hessian;
  const PatchCache& c = patch_cache(ctx, name());
  const Avatar& a = *avatar_;
  const DofLayout& L = local_layout(ctx);
  const int ob = object_offset(ctx);  // the object's 6 DoFs in the term's system, or −1
  double E = 0;
  // Contact over the candidate faces' samples.
  const Isometry T = dynamic_ ? Isometry(ctx.bound[1].q->bones[0] * c.shape_in_frame) : c.field_pose;
  const Isometry T_inv = T.inverse();
  // A dynamic object: g_o = Σ_s −J_oᵀ g_s, H_oo = Σ_s J_oᵀ H_s J_o, and per vertex
  // N_v = Σ_s −λ_v J_oᵀ H_s, J_o = [−[x_s]×, I] (the object's point at x_s moves by ω × x + v).
  using Mat63 = Eigen::Matrix<double, 6, 3>;
  std::vector<Mat63> Nv(ob >= 0 && q_hessian ? c.vertices.size() : 0, Mat63::Zero());
  const double kappa = options_.pressure_stiffness;
  const double eps = options_.static_slip_speed * ctx.h;  // friction's slip scale
  // A dynamic object carries the point it touched at t by G(q) G_t⁻¹.
  const Isometry carry = dynamic_ ? Isometry(ctx.bound[1].q->bones[0] * c.object_t.inverse()) : Isometry::Identity();
  const size_t nv = c.vertices.size();
  std::vector<Vec3> xv(nv);
  std::vector<Mat3> Av(nv);
  std::vector<Vec3> offset(nv);  // Σ_c b_c δu_c of each vertex (unposed)
  // Patch coupling of each vertex: (patch slot, barycentric weight) over its tet's nodes.
  std::vector<std::array<std::pair<int, double>, 4>> couple(nv);
  for (size_t i = 0; i < nv; ++i) {
    const PatchedVertex pv = patched_vertex(a, vertices_, c, c.vertices[i], q, du);
    xv[i] = pv.x, Av[i] = pv.A, offset[i] = pv.offset, couple[i] = pv.couple;
  }
  // Per vertex (slot): g_v = Σ_s λ_v g_s, and per vertex pair M_vw = Σ_s λ_v λ_w H_s
  // over the touching samples of their faces; the Jacobians are applied once per vertex pair.
  std::vector<Vec3> gv(p_derivatives ? nv : 0, Vec3::Zero());
  std::unordered_map<long, Mat3> Mvw;  // with Φ_pp (EvaluationMode::pp_hessian)
  std::vector<char> touched(nv, 0);     // a vertex of a touching sample's face
  for (size_t fi = 0; fi < c.faces.size(); ++fi) {
    const int fc = c.faces[fi];
    std::array<int, 3> vs;
    for (int i = 0; i < 3; ++i) vs[i] = c.vertex_slot.at(a.surface_faces(fc, i));
    // A face whose samples all lie outside: φ at its centre above twice its
    // radius (a distance field changes by at most the distance moved; twice,
    // and 1 mm, for interpolated grids) holds no touching sample.
    const Vec3 centre = (xv[vs[0]] + xv[vs[1]] + xv[vs[2]]) / 3.0;
    const double radius = std::sqrt(std::max({(xv[vs[0]] - centre).squaredNorm(), (xv[vs[1]] - centre).squaredNorm(),
                                              (xv[vs[2]] - centre).squaredNorm()}));
    const bool friction = !c.face_friction.empty() && c.face_friction[fi];
    if (!friction && field_->distance(T_inv * centre) > 2.0 * radius + 1e-3) continue;
    std::array<Vec3, 3> g{Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
    std::array<std::array<Mat3, 3>, 3> M;
    for (auto& row : M) row.fill(Mat3::Zero());
    bool touching = false;
    // A sample's gradient gs = ∂E/∂x and Hessian H into the face's
    // accumulators, and against a dynamic object whose point there is y.
    auto add_sample = [&](const SkinFaceSample& smp, const Vec3& gs, const Mat3& H, const Vec3& y) {
      touching = true;
      for (int i = 0; i < 3; ++i) {
        g[i] += smp.lambda[i] * gs;
        if (out.has_Hpp)
          for (int j = 0; j < 3; ++j) M[i][j] += smp.lambda[i] * smp.lambda[j] * H;
      }
      if (ob < 0 || !q_derivatives) return;
      Mat63 JoT;  // J_oᵀ
      JoT << hat(y), Mat3::Identity();
      out.gq.segment<6>(ob) -= JoT * gs;
      if (!q_hessian) return;
      out.Hqq.block<6, 6>(ob, ob) += JoT * H * JoT.transpose();
      for (int i = 0; i < 3; ++i) Nv[vs[i]] -= smp.lambda[i] * (JoT * H);
    };
    for (int s = c.face_first[fi]; s < c.face_first[fi + 1]; ++s) {
      const SkinFaceSample& smp = c.samples[s];
      const Vec3 x = smp.lambda[0] * xv[vs[0]] + smp.lambda[1] * xv[vs[1]] + smp.lambda[2] * xv[vs[2]];
      if (friction && c.friction_bound[s] > 0) {
        // Friction against the point y the object carries (header comment, "Friction").
        const Vec3 y = dynamic_ ? Vec3(carry * c.friction_point[s]) : c.friction_point[s];
        const contact_friction::PointFriction f =
            contact_friction::point_friction(x, y, c.friction_normal[s], c.friction_bound[s], eps, true);
        E += f.energy;
        out.force -= f.gradient;
        out.friction_force -= f.gradient;
        if (p_derivatives) add_sample(smp, f.gradient, f.hessian, y);
      }
      const geometry::SdfSample sd = field_->evaluate(T_inv * x);
      if (!(sd.distance < 0)) continue;
      const double k = kappa * smp.area, d = sd.distance;
      const Vec3 nrm = T.linear() * sd.gradient;
      E += 0.5 * k * d * d;
      out.force -= k * d * nrm;
      out.point_sum -= k * d * x;
      out.point_weight -= k * d;
      ++out.active;
      out.depth = std::max(out.depth, -d);
      out.area += smp.area;
      // The object's point at x itself.
      if (p_derivatives) add_sample(smp, k * d * nrm, k * nrm * nrm.transpose(), x);
    }
    if (!touching) continue;
    for (int i = 0; i < 3; ++i) {
      touched[vs[i]] = 1;
      gv[vs[i]] += g[i];
      if (out.has_Hpp)
        for (int j = 0; j < 3; ++j)
          Mvw.try_emplace(long(vs[i]) * long(nv) + vs[j], Mat3::Zero()).first->second += M[i][j];
    }
  }
  if (!p_derivatives || std::find(touched.begin(), touched.end(), 1) == touched.end()) return E;
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
  if (!q_derivatives) return E;
  // Subspace DoFs: ∂x_v/∂q = J_v (and the offsets' rotation with the bones).
  std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>> Jv(nv);
  std::vector<std::vector<int>> cv(nv);
  for (size_t v = 0; v < nv; ++v) {
    if (!touched[v]) continue;
    vertices_.local_jacobian(c.vertices[v], q, L, Jv[v], cv[v]);
    add_offset_rotation_gradient(a.surface_weights.row(c.vertices[v]), q.bones, offset[v], gv[v], L, out.gq);
    const Eigen::VectorXd gq = Jv[v].transpose() * gv[v];
    for (size_t k = 0; k < cv[v].size(); ++k) out.gq[cv[v][k]] += gq[k];
  }
  if (!q_hessian) return E;
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
  return E;
}


}  // namespace sflsh
