#pragma once
// Surface -> skeleton correspondence (seed §2, after Romero et al. 2020): each
// surface vertex gets its closest point on the bone segments, then the
// correspondence is smoothed with a Laplacian on the surface so that it
// varies smoothly across joints (where the closest bone jumps).
#include <vector>

#include "sflsh/body/body_model.hpp"
#include "sflsh/core/types.hpp"
#include "sflsh/volume/skeleton_segments.hpp"

namespace sflsh {

struct CorrespondenceOptions {
  /// A segment is a candidate for a vertex when the skinning weight of its
  /// start or end joint is at least this fraction of the vertex's largest
  /// weight: keeps crotch/armpit vertices off the other limb's bone.
  double candidate_weight_fraction = 0.2;
  /// Uniform-Laplacian smoothing: iterations of c <- (1-λ) c + λ mean(neighbours).
  int smoothing_iterations = 20;
  double smoothing_lambda = 0.5;
};

struct SurfaceCorrespondence {
  /// #V by #J: skeleton point of vertex v = coefficients.row(v) · joints
  /// (rows sum to 1), valid for the joints of any shape.
  MatXr coefficients;
  VecXi segment;          ///< #V index into the segments of the closest bone (before smoothing)
  Points skeleton_points; ///< #V by 3 for the joints it was computed with (m)
  VecX thickness;         ///< #V distance vertex - skeleton point (m)
};

/// Correspondence of the vertices `vertices` (#V by 3, faces model.faces) to
/// `segments` for joints `joints` (#J by 3).
SurfaceCorrespondence compute_surface_correspondence(const BodyModel& model, const Points& vertices,
                                                     const Points& joints, const std::vector<BoneSegment>& segments,
                                                     const CorrespondenceOptions& options = {});

}  // namespace sflsh
