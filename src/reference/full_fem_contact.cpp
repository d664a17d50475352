// The full-FEM reference's rigid obstacles: skin points, the contact samples of
// each skin face and the penalty's energy, gradient and Gauss–Newton Hessian.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "reference/full_fem_cholmod.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"

namespace sflsh {

int FullFem::add_obstacle(FullFemObstacle obstacle) {
  const std::string what = "FullFem obstacle '" + obstacle.name + "'";
  require(obstacle.field != nullptr, what, ": no signed-distance field");
  check_contact_sampling(obstacle.pressure_stiffness, obstacle.spacing, what);
  if (!skin_faces_coupled_) build_pattern(true);
  obstacles_.push_back(std::move(obstacle));
  obstacle_poses_.push_back(Isometry::Identity());
  face_samples_.emplace_back();
  return int(obstacles_.size()) - 1;
}

Vec3 FullFem::skin_point(int v, const Points& u) const {
  const Avatar& a = *avatar_;
  Vec3 y = a.surface_rest.row(v).transpose();
  for (int c = 0; c < 4; ++c) y += a.surface_bary(v, c) * u.row(a.tet.elements(a.surface_tet[v], c)).transpose();
  Vec3 x = Vec3::Zero();
  for (int j = 0; j < a.surface_weights.cols(); ++j)
    if (a.surface_weights(v, j) != 0.0) x += a.surface_weights(v, j) * (bones_[j] * y);
  return x;
}

Points FullFem::skin_points(const Points& u) const {
  Points x(avatar_->surface_rest.rows(), 3);
  for (int v = 0; v < x.rows(); ++v) x.row(v) = skin_point(v, u).transpose();
  return x;
}

const FullFem::FaceNodes& FullFem::face_nodes(int f) const {
  auto it = face_nodes_.find(f);
  if (it != face_nodes_.end()) return it->second;
  const Avatar& a = *avatar_;
  FaceNodes fn;
  for (int i = 0; i < 3; ++i)
    for (int c = 0; c < 4; ++c) {
      const int node = a.tet.elements(a.surface_tet[a.surface_faces(f, i)], c);
      fn.local[i][c] = -1;
      if (node_free_[node] < 0) continue;
      const auto at = std::find(fn.nodes.begin(), fn.nodes.end(), node);
      fn.local[i][c] = int(at - fn.nodes.begin());
      if (at == fn.nodes.end()) fn.nodes.push_back(node);
    }
  const int m = int(fn.nodes.size()), w = 3 * m;
  fn.slots.assign(size_t(w) * w, -1);
  const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& H = chol_->H;
  for (int r = 0; r < w; ++r)
    for (int c = 0; c < w; ++c) {
      const int i = 3 * node_free_[fn.nodes[r / 3]] + r % 3, j = 3 * node_free_[fn.nodes[c / 3]] + c % 3;
      if (i < j) continue;
      // Binary search of row i in column j (sorted, compressed); present by build_pattern.
      const int* begin = H.innerIndexPtr() + H.outerIndexPtr()[j];
      const int* end = H.innerIndexPtr() + H.outerIndexPtr()[j + 1];
      const int* hit = std::lower_bound(begin, end, i);
      require(hit != end && *hit == i, "FullFem: skin face ", f, " coupling missing from the Hessian pattern");
      fn.slots[size_t(r) * w + c] = int(hit - H.innerIndexPtr());
    }
  return face_nodes_.emplace(f, std::move(fn)).first->second;
}

const std::vector<SkinFaceSample>& FullFem::face_samples(int obstacle, int f) const {
  auto& cache = face_samples_[size_t(obstacle)];
  auto it = cache.find(f);
  if (it != cache.end()) return it->second;
  std::vector<SkinFaceSample> samples;
  append_face_samples(avatar_->surface_rest, avatar_->surface_faces, f, obstacles_[size_t(obstacle)].spacing, samples);
  return cache.emplace(f, std::move(samples)).first->second;
}

double FullFem::evaluate_contact(const Points& u, VecX* grad, bool hessian,
                                 std::vector<FullFemContact>* report) const {
  if (obstacles_.empty()) return 0;
  Timer timer;
  const Avatar& a = *avatar_;
  require(skin_A_.size() == size_t(a.surface_rest.rows()), "FullFem: contact evaluated before the first step");
  double* values = chol_->H.valuePtr();
  const Points x = skin_points(u);  // #V by 3, world
  double E = 0;
  // Per face, derivatives over its three vertices' world positions first (the
  // samples share them: x_s = Σ_i λ_i x_{v_i}), then mapped to the nodes once:
  //   ∂E/∂x_{v_i} = Σ_s w_s φ_s λ_i ∇φ_s,   K_ij = Σ_s w_s λ_i λ_j ∇φ_s ∇φ_sᵀ  (w_s = κ a_s).
  Eigen::Matrix<double, 9, 1> g_vertex;
  Eigen::Matrix<double, 9, 9> K_vertex;
  MatX H_face;  // the face's free-node block, 3m by 3m
  std::vector<double> phi_vertex;  // unbounded fields: φ at every skin vertex
  for (size_t o = 0; o < obstacles_.size(); ++o) {
    const FullFemObstacle& ob = obstacles_[o];
    const Isometry& T = obstacle_poses_[o];
    const Isometry T_inv = T.inverse();
    const geometry::Aabb box = ob.field->bounds().transformed(T);
    const bool bounded = !box.is_unbounded();
    const double kappa = ob.pressure_stiffness;
    if (!bounded) {
      phi_vertex.resize(size_t(x.rows()));
      for (int v = 0; v < int(x.rows()); ++v) phi_vertex[size_t(v)] = ob.field->evaluate(T_inv * x.row(v).transpose()).distance;
    }
    FullFemContact rep;
    rep.name = ob.name;
    for (int f = 0; f < int(a.surface_faces.rows()); ++f) {
      const int v[3] = {a.surface_faces(f, 0), a.surface_faces(f, 1), a.surface_faces(f, 2)};
      const Vec3 p[3] = {x.row(v[0]).transpose(), x.row(v[1]).transpose(), x.row(v[2]).transpose()};
      if (bounded) {
        const geometry::Aabb face_box(p[0].cwiseMin(p[1]).cwiseMin(p[2]), p[0].cwiseMax(p[1]).cwiseMax(p[2]));
        if (!face_box.intersects(box)) continue;  // every sample outside the solid's box: φ ≥ 0
      } else {
        const double longest = std::max({(p[1] - p[0]).norm(), (p[2] - p[1]).norm(), (p[0] - p[2]).norm()});
        if (std::max({phi_vertex[size_t(v[0])], phi_vertex[size_t(v[1])], phi_vertex[size_t(v[2])]}) > longest) continue;
      }
      bool touched = false;
      g_vertex.setZero();
      K_vertex.setZero();
      for (const SkinFaceSample& s : face_samples(int(o), f)) {
        const Vec3 xs = s.lambda[0] * p[0] + s.lambda[1] * p[1] + s.lambda[2] * p[2];
        if (bounded && !box.contains(xs)) continue;
        const geometry::SdfSample q = ob.field->evaluate(T_inv * xs);
        const double d = q.distance;
        if (!(d < 0)) continue;
        touched = true;
        const double w = kappa * s.area;
        E += 0.5 * w * d * d;
        const Vec3 n = T.linear() * q.gradient;  // ∂φ/∂x, world
        if (report) {
          rep.force -= w * d * n;
          ++rep.active_samples;
          rep.max_penetration = std::max(rep.max_penetration, -d);
          rep.contact_area += s.area;
        }
        if (grad)
          for (int i = 0; i < 3; ++i) g_vertex.segment<3>(3 * i) += (w * d * s.lambda[i]) * n;
        if (hessian) {
          const Mat3 nn = w * n * n.transpose();
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) K_vertex.block<3, 3>(3 * i, 3 * j) += (s.lambda[i] * s.lambda[j]) * nn;
        }
      }
      if (!touched || (!grad && !hessian)) continue;
      // x_v = Σ_j w_vj G_j (x̄_v + Σ_k b_vk u_{n_k}): ∂x_v/∂u_{n_k} = b_vk A_v.
      const FaceNodes& fn = face_nodes(f);
      if (grad)
        for (int i = 0; i < 3; ++i) {
          const Vec3 g = skin_A_[size_t(v[i])].transpose() * g_vertex.segment<3>(3 * i);
          for (int k = 0; k < 4; ++k)
            if (fn.local[i][k] >= 0)
              grad->segment<3>(3 * node_free_[fn.nodes[fn.local[i][k]]]) += a.surface_bary(v[i], k) * g;
        }
      if (hessian) {
        const int width = 3 * int(fn.nodes.size());
        H_face.setZero(width, width);
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) {
            const Mat3 K = skin_A_[size_t(v[i])].transpose() * K_vertex.block<3, 3>(3 * i, 3 * j) * skin_A_[size_t(v[j])];
            for (int k = 0; k < 4; ++k)
              for (int l = 0; l < 4; ++l) {
                const double bb = a.surface_bary(v[i], k) * a.surface_bary(v[j], l);
                if (fn.local[i][k] >= 0 && fn.local[j][l] >= 0 && bb != 0.0)
                  H_face.block<3, 3>(3 * fn.local[i][k], 3 * fn.local[j][l]) += bb * K;
              }
          }
        // Lower triangle of the symmetric block; the slot table maps (r, c) or
        // its transpose onto the global lower triangle.
        for (int r = 0; r < width; ++r)
          for (int c = 0; c <= r; ++c) {
            const int sl = fn.slots[size_t(r) * width + c];
            values[sl >= 0 ? sl : fn.slots[size_t(c) * width + r]] += H_face(r, c);
          }
      }
    }
    if (report) report->push_back(rep);
  }
  ms_contact_ += timer.ms();
  return E;
}

}  // namespace sflsh
