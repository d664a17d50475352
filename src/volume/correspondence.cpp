#include "sflsh/volume/correspondence.hpp"

#include <algorithm>
#include <limits>

#include "sflsh/core/error.hpp"

namespace sflsh {

SurfaceCorrespondence compute_surface_correspondence(const BodyModel& model, const Points& vertices,
                                                     const Points& joints, const std::vector<BoneSegment>& segments,
                                                     const CorrespondenceOptions& o) {
  const int V = int(vertices.rows()), J = model.num_joints();
  require(!segments.empty(), "compute_surface_correspondence: no bone segments");
  std::vector<Vec3> A(segments.size()), B(segments.size());
  for (size_t s = 0; s < segments.size(); ++s) segment_endpoints(segments[s], model.parents, joints, A[s], B[s]);

  SurfaceCorrespondence out;
  out.coefficients = MatXr::Zero(V, J);
  out.segment.resize(V);
  for (int v = 0; v < V; ++v) {
    const Vec3 x = vertices.row(v);
    const auto w = model.weights.row(v);
    const double wmin = o.candidate_weight_fraction * w.maxCoeff();
    double best = std::numeric_limits<double>::infinity();
    int best_s = -1;
    double best_t = 0;
    // Candidates first; if none qualifies (cannot happen with wmin <= max
    // weight unless every segment misses the dominant joint), all segments.
    for (int pass = 0; pass < 2 && best_s < 0; ++pass)
      for (size_t s = 0; s < segments.size(); ++s) {
        const auto& seg = segments[s];
        const bool candidate = w[seg.joint] >= wmin || (seg.child >= 0 && w[seg.child] >= wmin);
        if (pass == 0 && !candidate) continue;
        const double t = closest_segment_parameter(A[s], B[s], x);
        const double d = (A[s] + t * (B[s] - A[s]) - x).squaredNorm();
        if (d < best) best = d, best_s = int(s), best_t = t;
      }
    out.segment[v] = best_s;
    out.coefficients.row(v) = segment_point_coefficients(segments[best_s], model.parents, J, best_t).transpose();
  }

  // Laplacian smoothing of the (linear) coefficients over the surface graph.
  std::vector<std::vector<int>> nbr(V);
  const Triangles& F = model.faces;
  for (int f = 0; f < F.rows(); ++f)
    for (int i = 0; i < 3; ++i) {
      nbr[F(f, i)].push_back(F(f, (i + 1) % 3));
      nbr[F(f, (i + 1) % 3)].push_back(F(f, i));
    }
  for (auto& n : nbr) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  MatXr next(V, J);
  for (int it = 0; it < o.smoothing_iterations; ++it) {
    for (int v = 0; v < V; ++v) {
      if (nbr[v].empty()) {
        next.row(v) = out.coefficients.row(v);
        continue;
      }
      Eigen::RowVectorXd mean = Eigen::RowVectorXd::Zero(J);
      for (int u : nbr[v]) mean += out.coefficients.row(u);
      mean /= double(nbr[v].size());
      next.row(v) = (1.0 - o.smoothing_lambda) * out.coefficients.row(v) + o.smoothing_lambda * mean;
    }
    out.coefficients.swap(next);
  }
  out.skeleton_points = out.coefficients * joints;
  out.thickness = (vertices - out.skeleton_points).rowwise().norm();
  return out;
}

}  // namespace sflsh
