// Assembly of the built-in procedural body: surface, skinning weights, joint
// regressor and linear shape space around the parametric body of
// procedural_anatomy.cpp (DESIGN.md §3: SMPL's arrays and semantics).
#include "sflsh/body/procedural_body.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "body/procedural_body_internal.hpp"
#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh {
namespace procedural {
namespace {

/// Blend radius of the smooth union (metres): rounds armpits, crotch, neck.
constexpr double kBlendRadius = 0.016;
/// Surface area of the template (m², measured) used to pick the grid size.
constexpr double kTemplateArea = 1.74;
/// Marching tetrahedra on the Freudenthal grid give ≈ 4.49·A/h² vertices
/// (mean crossings of its 7 edge directions with a random plane); the grid
/// is made fine enough to give ~35 % more than the target, which the edge
/// collapses of improve_surface then remove.
constexpr double kMarchingTetDensity = 4.49;
constexpr double kOversampling = 1.35;
/// Falloff of the skinning weights with distance to the bone beyond the
/// nearest bone (metres), and the number of surface smoothing iterations.
constexpr double kWeightFalloff = 0.02;
constexpr int kWeightSmoothing = 10;
/// Surface smoothing iterations of the shape directions: the conformed
/// offsets change abruptly across creases (crotch, under the chest, hip
/// sides); smoothing them lets large |β| deepen a crease without folding it.
constexpr int kShapeSmoothing = 20;

/// Uniform-Laplacian smoothing (half step per iteration) of a per-vertex field.
template <class M>
M smooth_field(M field, const std::vector<std::vector<int>>& nb, int iterations) {
  for (int it = 0; it < iterations; ++it) {
    M next = field;
    for (int v = 0; v < int(field.rows()); ++v) {
      auto mean = field.row(nb[v][0]).eval();
      for (size_t k = 1; k < nb[v].size(); ++k) mean += field.row(nb[v][k]);
      next.row(v) = 0.5 * field.row(v) + (0.5 / double(nb[v].size())) * mean;
    }
    field.swap(next);
  }
  return field;
}

/// Closest point parameter of x on segment [a, b] (clamped to [0, 1]).
double segment_parameter(const Vec3& x, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  return std::clamp((x - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
}

double segment_distance(const Vec3& x, const Vec3& a, const Vec3& b) {
  const double t = segment_parameter(x, a, b);
  return (x - (a + t * (b - a))).norm();
}

/// #V by 24 LBS weights: exp(−(d_j − d_min)/τ) of the distance d_j to joint
/// j's bone (the nearest bone dominates, neighbours share near joints),
/// normalized, then averaged over surface neighbours (uniform Laplacian
/// smoothing keeps rows non-negative and summing to 1).
MatXr skinning_weights(const Points& V, const std::vector<std::vector<int>>& nb, const Landmarks& L) {
  const int n = int(V.rows());
  MatXr W = MatXr::Zero(n, kSmplJoints);
  for (int v = 0; v < n; ++v) {
    const Vec3 x = V.row(v).transpose();
    std::array<double, kSmplJoints> d;
    d.fill(std::numeric_limits<double>::infinity());
    for (const WeightSegment& s : weight_segments())
      d[s.joint] = std::min(d[s.joint], segment_distance(x, L[s.from], L[s.to]));
    const double dmin = *std::min_element(d.begin(), d.end());
    for (int j = 0; j < kSmplJoints; ++j) {
      const double z = (d[j] - dmin) / kWeightFalloff;
      if (z < 8.0) W(v, j) = std::exp(-z);
    }
    W.row(v) /= W.row(v).sum();
  }
  W = smooth_field(std::move(W), nb, kWeightSmoothing);
  for (int v = 0; v < n; ++v) W.row(v) /= W.row(v).sum();
  return W;
}

/// 24 by #V regressor. Joint j = weighted mean of the ring of vertices around
/// it: vertices near the plane through the joint across its bone (Gaussian
/// band), within a radius, skinned mainly to j, its parent or a child, on the
/// joint's side of the body. The Gaussian weights w0 are then corrected by the
/// smallest change (in the w0-weighted norm) that makes Σw = 1 and Σ w v = J
/// exactly: w = w0 + D Aᵀ (A D Aᵀ)⁻¹ (b − A w0), D = diag(w0), A = [Vᵀ; 1ᵀ].
Eigen::SparseMatrix<double, Eigen::RowMajor> joint_regressor(const Points& V, const MatXr& W, const Landmarks& L) {
  const int n = int(V.rows());
  std::vector<int> dominant(n);
  for (int v = 0; v < n; ++v) W.row(v).maxCoeff(&dominant[v]);
  std::vector<Eigen::Triplet<double>> triplets;
  for (int j = 0; j < kSmplJoints; ++j) {
    const Vec3 J = L[j];
    Vec3 axis = Vec3::UnitY();  // trunk, neck and head: horizontal rings
    const bool trunk = j == 0 || j == 3 || j == 6 || j == 9 || j == 12 || j == 15;
    if (!trunk && j != 1 && j != 2)  // hips: horizontal ring through the upper thigh too
      for (const WeightSegment& s : weight_segments())
        if (s.joint == j) axis = (L[s.to] - L[s.from]).normalized();
    if (j == 7 || j == 8) axis = Vec3::UnitY();  // ankle: ring round the lower shank
    const double radius = (j == 0 || j == 3 || j == 6 || j == 9) ? 0.24 : (j <= 2 || j == 12 || j == 13 || j == 14) ? 0.15 : 0.10;
    const double band = 0.012;
    std::vector<int> group = {j};
    if (j > 0) group.push_back(kSmplParents[j]);
    for (int c = 0; c < kSmplJoints; ++c)
      if (kSmplParents[c] == j) group.push_back(c);
    std::vector<int> idx;
    std::vector<double> w0;
    for (int v = 0; v < n; ++v) {
      const Vec3 x = V.row(v).transpose();
      if (std::find(group.begin(), group.end(), dominant[v]) == group.end()) continue;
      if (std::abs(J.x()) > 0.03 && x.x() * J.x() <= 0) continue;
      if ((x - J).norm() > radius) continue;
      const double s = (x - J).dot(axis) / band;
      if (std::abs(s) > 2.5) continue;
      idx.push_back(v);
      w0.push_back(std::exp(-s * s));
    }
    require(idx.size() >= 8, "procedural body: only ", idx.size(), " surface vertices around joint ",
            kSmplJointNames[j], " for the regressor (internal error)");
    const int m = int(idx.size());
    Eigen::VectorXd w = Eigen::Map<Eigen::VectorXd>(w0.data(), m);
    w /= w.sum();
    Eigen::MatrixXd A(4, m);
    for (int k = 0; k < m; ++k) A.col(k) << V(idx[k], 0), V(idx[k], 1), V(idx[k], 2), 1.0;
    Eigen::Vector4d b(J.x(), J.y(), J.z(), 1.0);
    const Eigen::MatrixXd ADAt = A * w.asDiagonal() * A.transpose();
    const Eigen::Vector4d lambda = ADAt.ldlt().solve(b - A * w);
    w += w.asDiagonal() * (A.transpose() * lambda);
    for (int k = 0; k < m; ++k) triplets.emplace_back(j, idx[k], w[k]);
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor> R(kSmplJoints, n);
  R.setFromTriplets(triplets.begin(), triplets.end());
  return R;
}

/// The template carried to the body of `params`: each vertex follows its
/// bones (the skinning-weighted displacement of the closest point on each
/// weighted bone), then is projected onto the new implicit surface, so the
/// topology is shared and vertices keep their place on the body.
Points conform_to(const Points& V, const MatXr& W, const Landmarks& L0, const BodyParams& params) {
  const Landmarks L1 = make_landmarks(params);
  const BodyImplicit body(make_primitives(params), kBlendRadius);
  Points out(V.rows(), 3);
  for (int v = 0; v < V.rows(); ++v) {
    const Vec3 x = V.row(v).transpose();
    Vec3 moved = x;
    for (int j = 0; j < kSmplJoints; ++j) {
      if (W(v, j) < 1e-6) continue;
      double best = std::numeric_limits<double>::infinity();
      Vec3 shift = Vec3::Zero();
      for (const WeightSegment& s : weight_segments()) {
        if (s.joint != j) continue;
        const double t = segment_parameter(x, L0[s.from], L0[s.to]);
        const double d = segment_distance(x, L0[s.from], L0[s.to]);
        if (d < best) {
          best = d;
          shift = (1 - t) * (L1[s.from] - L0[s.from]) + t * (L1[s.to] - L0[s.to]);
        }
      }
      moved += W(v, j) * shift;
    }
    out.row(v) = body.project(moved).transpose();
  }
  return out;
}

BodyParams params_from_betas(const VecX& betas) {
  require(betas.size() <= kNumShapeParameters, "procedural body: ", betas.size(), " shape coefficients given, at most ",
          kNumShapeParameters, " expected");
  BodyParams p;
  for (int b = 0; b < betas.size(); ++b) p.add(b, betas[b]);
  return p;
}

}  // namespace
}  // namespace procedural

Points procedural_body_joints(const VecX& betas) {
  const auto L = procedural::make_landmarks(procedural::params_from_betas(betas));
  Points J(kSmplJoints, 3);
  for (int j = 0; j < kSmplJoints; ++j) J.row(j) = L[j].transpose();
  return J;
}

BodyModel make_procedural_body(const ProceduralBodyOptions& options) {
  using namespace procedural;
  require(options.target_vertices >= 2000 && options.target_vertices <= 100000,
          "procedural body: target_vertices = ", options.target_vertices, ", expected 2000..100000");
  require(options.num_betas >= 8 && options.num_betas <= kNumShapeParameters, "procedural body: num_betas = ",
          options.num_betas, ", expected 8..", kNumShapeParameters);
  const BodyParams base;
  const Landmarks L = make_landmarks(base);
  const BodyImplicit body(make_primitives(base), kBlendRadius);

  BodyModel model;
  const double cell = std::sqrt(kMarchingTetDensity * kTemplateArea / (kOversampling * options.target_vertices));
  polygonize(body, cell, &model.v_template, &model.faces);
  // Equilateral triangles of side ℓ: V ≈ A / (ℓ²·√3/2) → ℓ for the target count.
  const double edge = std::sqrt(2.0 * kTemplateArea / (std::sqrt(3.0) * options.target_vertices));
  improve_surface(body, options.target_vertices, 1.6 * edge, 4, &model.v_template, &model.faces);

  const int n = model.num_vertices();
  const auto nb = vertex_neighbours(n, model.faces);
  model.weights = skinning_weights(model.v_template, nb, L);
  model.J_regressor = joint_regressor(model.v_template, model.weights, L);

  // Shape space. β0 is an exact uniform scale about the origin (the floor
  // point between the feet), as the parametric body's size parameter is; the
  // others are central differences of the template conformed to the body
  // with parameter ±1.
  model.shapedirs.push_back(kStaturePerUnit * model.v_template);
  for (int b = 1; b < options.num_betas; ++b) {
    BodyParams plus = base, minus = base;
    plus.add(b, 1.0);
    minus.add(b, -1.0);
    const Points dir = 0.5 * (conform_to(model.v_template, model.weights, L, plus) -
                              conform_to(model.v_template, model.weights, L, minus));
    model.shapedirs.push_back(smooth_field(dir, nb, kShapeSmoothing));
  }
  const auto& meanings = shape_parameter_meanings();
  model.shape_meanings.assign(meanings.begin(), meanings.begin() + options.num_betas);

  model.posedirs = MatX();  // no pose blend shapes (empty = none; see body_model.hpp)
  model.parents.assign(kSmplParents.begin(), kSmplParents.end());
  for (auto name : kSmplJointNames) model.joint_names.emplace_back(name);
  model.source = "procedural";
  return model;
}

}  // namespace sflsh
