#pragma once
// Body ↔ body contact between the two bodies' skins, so that the flesh of
// both gives (DESIGN.md §7). Bone capsules (capsule_contact.hpp) meet rigidly:
// a walker stopped by another body's capsules feels the stiffness of the
// penalty alone, and at 0.6 m/s the peak reaches tens of kilonewtons. Here the
// skin of one body presses on the skin of the other, and the soft tissue under
// both carries the load, as between two people.
//
// Samples s over body a's skin faces (skin_face_samples.hpp, area a_s) meet
// the surface of body b: at the start of the step each sample near b gets
// the point of b's skin closest to it, y_s = Σ_i μ_i x^b_{w_i} (face w of b,
// barycentric μ), and that face's outward normal n_s, both at time t; over the
// step the gap is measured from that moving point along that normal,
//   g_s(q) = n_sᵀ (x^a_s(q_a) − y_s(q_b)),
// (a tangent plane that moves with b's skin; lagged per step like friction),
// and the penalty is a pressure per unit area,
//   E = Σ_s ½ (κ/2) a_s min(g_s, 0)²,
// applied from both sides (a's samples on b's skin and b's samples on a's
// skin; κ/2 each, so a contact's pressure is κ × penetration whichever side
// measures it). ∂g/∂x^a = n, ∂g/∂y = −n: gradient κ/2 a g nᵀ(J_a − J_b),
// Gauss–Newton Hessian κ/2 a (J_a − J_b)ᵀ n nᵀ (J_a − J_b) (PSD), J the
// points' Jacobians over each body's bones and soft DoFs (posed_points.hpp).
// The forces on the two skins are equal and opposite and act along n through
// points g n apart, so linear and angular momentum are conserved.
//
// Broad phase (begin_step): both skins at time t, and how far each vertex
// moved over the last step (m). A vertex of a is near b when b's nearest
// vertex (a grid's ring search) is within the margin plus 1.5 × the two
// vertices' motion plus b's longest edge; the faces around near vertices are
// a's candidate faces. Each of their samples gets its closest point among the
// faces around b's nearest vertex and that vertex's neighbours. The normal n
// is that face's where the closest point lies inside the face, else (an edge
// or a corner of b) the direction from it to the sample, signed by the side
// of the faces that meet there (the sum of their normals), so that g is the
// signed distance at time t and the pair's forces are collinear there. A sample whose own face turns the same way as b's (coplanar
// neighbours, the far side of a thin part) does not touch; nor does one already
// deeper than `max_depth` behind b's skin at time t (the bone capsules' cores
// keep bodies from passing through).
//
// The plane is lagged: a sample that slides over a curved part within the
// step (a foot swinging past a shin at 3 m/s moves 5 cm per step at 60 Hz) can
// end far behind it while it is outside b. The reported penetration is the
// depth behind b's skin found afresh at the step's end; the plane's gap is
// reported apart (a walker meeting a standing body: 5.8 mm against 16.6 mm).
//
// Cost: per evaluation, the pairs' gaps plus (DoFs a sample touches)² for each
// sample in contact; the broad phase once per step. Two default avatars
// walking into each other form up to ~18,000 pairs (median ~9,000), up to ~740 in contact.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "sflsh/sim/energy_term.hpp"
#include "sflsh/sim/posed_points.hpp"
#include "sflsh/sim/skin_face_samples.hpp"

namespace sflsh {

struct SkinContactOptions {
  double pressure_stiffness = kDefaultPressureStiffness;  ///< κ, N/m³
  /// m: face sample spacing; body–body contacts are broad (a trunk, a thigh),
  /// so coarser than a probe's.
  double spacing = 0.01;
  double margin = 0.01;     ///< m: a sample is a candidate when its gap at time t is below this plus the motion
  double max_depth = 0.05;  ///< m: samples deeper than this behind the other skin at time t are left out
  int max_handles = 8;      ///< basis row truncation of the skin vertices (sdf_contact.hpp)
};

class SkinContactTerm : public EnergyTerm {
 public:
  /// Between the term's two bound bodies, avatars `a` (bound first) and `b`.
  /// Throws one line on bad options.
  SkinContactTerm(const Avatar& a, const Avatar& b, const SkinContactOptions& options = {});
  std::string name() const override { return "skin_contact"; }
  bool in_nonlinearity_check() const override { return false; }  // a contact term (energy_term.hpp)
  std::unique_ptr<TermCache> make_cache() const override;
  void begin_step(const StepContext& ctx) const override;
  bool active(const StepContext& ctx) const override;
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override;
  /// "force" (3, N: what b exerts on a, world), "active_samples" (1: samples
  /// with g < 0), "max_penetration" (1, m: the deepest of them behind the
  /// other skin at q, its closest point found afresh), "contact_area" (1, m²,
  /// rest area of the samples in contact) and "max_plane_gap" (1, m: the
  /// deepest −g, behind the lagged plane the penalty acts on) at the final q;
  /// while any sample is in contact also "contact_point" (3, m, world: the
  /// active samples' mean weighted by their pressure force).
  std::vector<TermQuantity> report(const StepContext& ctx, const Configuration& q) const override;

  const SkinContactOptions& options() const { return options_; }

  /// One body's skin as the term uses it.
  struct Skin {
    PosedPoints vertices;  // skin vertices, rows truncated
    Points rest;           // unposed rest positions (for face samples)
    Triangles faces;
    std::vector<std::vector<int>> vertex_faces;
    std::vector<std::vector<int>> vertex_neighbours;  // the 1-ring
    double max_edge = 0;  // m, longest rest edge
  };
  /// One sample of a side's skin against the other skin's closest point.
  struct Pair {
    int side = 0;  // 0: a's sample on b's skin; 1: b's sample on a's skin
    int face = 0;  // the sample's face (its own skin)
    Vec3 lambda;   // its barycentric coordinates
    double area = 0;
    int other_face = 0;  // the closest face of the other skin
    Vec3 mu;             // the closest point's barycentric coordinates there
    Vec3 normal;         // the other face's outward normal at time t
  };

 private:
  /// Appends side `side`'s pairs (samples of `from` near `to`), given both
  /// skins at time t and how far each vertex moved over the last step (m).
  void collect_pairs(int side, const Skin& from, const Points& x_from, const VecX& m_from, const Skin& to,
                     const Points& x_to, const VecX& m_to, std::vector<Pair>& out) const;
  /// World positions of the vertices the step's pairs use (the cache's list per skin) at q[0], q[1].
  std::array<Points, 2> posed_vertices(const TermCache& cache, const Configuration* const q[2]) const;
  /// The pair's gap g (m), given posed_vertices().
  double gap(const Pair& p, const TermCache& cache, const std::array<Points, 2>& x) const;
  Skin skins_[2];
  SkinContactOptions options_;
};

}  // namespace sflsh
