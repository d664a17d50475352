// The template volume's node correspondence: for every tet node, the skin point
// whose correspondence path (skeleton point -> skin point) passes through it.
#include <cmath>
#include <limits>

#include "sflsh/core/progress.hpp"
#include "volume/template_volume_internal.hpp"

namespace sflsh::template_internal {

namespace {

/// Solves x = s(b) + d (σ(b) - s(b)) for the barycentric point b of triangle
/// (i,j,k) of the skin and the depth d, where s and σ are interpolated
/// linearly over the triangle (the correspondence path field). Gauss–Newton
/// on (u, v, d), b = (1-u-v, u, v). Returns the residual norm.
double solve_path_in_triangle(const Vec3 S[3], const Vec3 X[3], const Vec3& x, Vec3& bary, double& depth) {
  double u = 1.0 / 3, v = 1.0 / 3, d = 0.5;
  double res = std::numeric_limits<double>::infinity();
  for (int it = 0; it < 12; ++it) {
    const Vec3 s = (1 - u - v) * S[0] + u * S[1] + v * S[2];
    const Vec3 g = (1 - u - v) * X[0] + u * X[1] + v * X[2];
    const Vec3 r = s + d * (g - s) - x;
    res = r.norm();
    if (res < 1e-12) break;
    Mat3 Jm;
    Jm.col(0) = (S[1] - S[0]) + d * ((X[1] - S[1]) - (X[0] - S[0]));
    Jm.col(1) = (S[2] - S[0]) + d * ((X[2] - S[2]) - (X[0] - S[0]));
    Jm.col(2) = g - s;
    const Vec3 step = Jm.colPivHouseholderQr().solve(-r);
    if (!step.allFinite()) break;
    u += step[0], v += step[1], d += step[2];
    if (std::abs(u) > 10 || std::abs(v) > 10) break;  // diverging: not this triangle
  }
  bary = Vec3(1 - u - v, u, v);
  depth = d;
  const Vec3 s = bary[0] * S[0] + bary[1] * S[1] + bary[2] * S[2];
  const Vec3 g = bary[0] * X[0] + bary[1] * X[1] + bary[2] * X[2];
  return (s + d * (g - s) - x).norm();
}

}  // namespace

/// Node correspondence: finds, for every node, the skin point σ whose path s(σ) -> σ passes
/// through the node (seed §2 "following the correspondence path").
void correspond_nodes(TemplateVolume& tv, const BodyModel& model, const Points& J0, const SurfaceQuery& skin,
                      const std::vector<char>& outer) {
  TemplateReport& rep = tv.report;
  const Points& V = model.v_template;
  const Triangles& F = model.faces;
  const int J = model.num_joints(), nV = model.num_vertices();
  const Points& S = tv.surface.skeleton_points;
  const int N = tv.tet.num_nodes();
  std::vector<std::vector<int>> vertex_faces(nV);
  for (int f = 0; f < F.rows(); ++f)
    for (int i = 0; i < 3; ++i) vertex_faces[F(f, i)].push_back(f);
  tv.node_face.resize(N);
  tv.node_face_bary.resize(N, 3);
  tv.node_depth.resize(N);
  tv.node_residual.resize(N, 3);
  tv.node_segment.resize(N);
  tv.node_skeleton_coefficients.resize(N, J);
  Progress progress("template: node correspondence", N);
  for (int n = 0; n < N; ++n) {
    if (n % 256 == 0) progress.update(n);
    const Vec3 x = tv.tet.nodes.row(n);
    int face = -1;
    Vec3 bary;
    double depth = 1.0;
    if (outer[n]) {
      skin.closest_point(x, &face, &bary);
    } else {
      // Nearest path segment [s_v, x_v] over all skin vertices ...
      double best = std::numeric_limits<double>::infinity();
      int best_v = 0;
      for (int v = 0; v < nV; ++v) {
        const Vec3 s = S.row(v), g = V.row(v);
        const double t = closest_segment_parameter(s, g, x);
        const double d2 = (s + t * (g - s) - x).squaredNorm();
        if (d2 < best) best = d2, best_v = v;
      }
      // ... then the exact path point in the triangles around that vertex.
      double best_res = std::numeric_limits<double>::infinity();
      for (int f : vertex_faces[best_v]) {
        Vec3 Sf[3], Xf[3];
        for (int i = 0; i < 3; ++i) Sf[i] = S.row(F(f, i)), Xf[i] = V.row(F(f, i));
        Vec3 b;
        double d;
        solve_path_in_triangle(Sf, Xf, x, b, d);
        // Clamp to the triangle and re-project onto its path.
        b = b.cwiseMax(0.0);
        b /= b.sum();
        const Vec3 s = b[0] * Sf[0] + b[1] * Sf[1] + b[2] * Sf[2];
        const Vec3 g = b[0] * Xf[0] + b[1] * Xf[1] + b[2] * Xf[2];
        d = closest_segment_parameter(s, g, x);
        const double res = (s + d * (g - s) - x).norm();
        if (res < best_res) best_res = res, face = f, bary = b, depth = d;
      }
    }
    tv.node_face[n] = face;
    tv.node_face_bary.row(n) = bary.transpose();
    tv.node_depth[n] = depth;
    Eigen::RowVectorXd c = Eigen::RowVectorXd::Zero(J);
    int dom = 0;
    bary.maxCoeff(&dom);
    for (int i = 0; i < 3; ++i) c += bary[i] * tv.surface.coefficients.row(F(face, i));
    tv.node_skeleton_coefficients.row(n) = c;
    tv.node_segment[n] = tv.surface.segment[F(face, dom)];
    const Vec3 s = (c * J0).transpose();
    Vec3 g = Vec3::Zero();
    for (int i = 0; i < 3; ++i) g += bary[i] * V.row(F(face, i)).transpose();
    tv.node_residual.row(n) = (x - (s + depth * (g - s))).transpose();
    rep.max_path_residual = std::max(rep.max_path_residual, tv.node_residual.row(n).norm());
  }
  progress.finish();
}

}  // namespace sflsh::template_internal
