#pragma once
// Removal of flat or inverted boundary caps: a tet whose four nodes lie on the
// outer surface and two of whose faces are on the boundary spans a ridge of
// the surface. Where a shape turns that ridge from convex to concave (a
// crease deepening at the crotch, the armpit, under the breast), the tet
// flattens and then inverts, and no node move that keeps the nodes on the
// surface can help. Removing it flips the boundary edge: the faces (a,b,c),
// (a,b,d) give way to (a,c,d), (b,c,d), every node stays where it is and on
// the surface, and the boundary follows the concave surface more closely.
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/mesh/geometry_set.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh {

struct BoundaryCapReport {
  int removed = 0;  ///< tets removed (remove_bad_boundary_ears: also the apex nodes removed)
  /// Caps still below the floor or inverted that could not be removed
  /// (removal would make an edge or a node non-manifold or orphan a node).
  int kept_bad = 0;
};

/// Removes, repeatedly until none is left, every tet of `mesh` whose four
/// nodes have `on_surface[n] != 0` (#N flags), exactly two of whose faces are
/// boundary faces, and whose smallest dihedral angle is below `floor_deg`
/// (deg) or whose signed volume is <= 0, provided the removal keeps the
/// boundary 2-manifold: the edge (c,d) opposite the shared boundary edge
/// (a,b) must not already be a boundary edge, and every node must keep at
/// least one tet. `kept` (#T' indices into the input's tets, in order)
/// receives the surviving tets, so per-tet fields can follow. Nodes are not
/// moved or renumbered. Deterministic (lowest tet index first).
BoundaryCapReport remove_bad_boundary_caps(TetMesh& mesh, const std::vector<char>& on_surface, double floor_deg,
                                           std::vector<int>* kept = nullptr);
/// The same for the tets `elements` (#T by 4) judged at every geometry of
/// `set`: a cap goes if it is inverted or below `floor_deg` at one of them,
/// or if `bad_elsewhere` (#T flags, optional) flags it (bad at placements
/// measured outside `set`). Removing a tet makes no other worse anywhere
/// (see replacement_accepted).
BoundaryCapReport remove_bad_boundary_caps(Tets& elements, const GeometrySet& set,
                                           const std::vector<char>& on_surface, double floor_deg,
                                           std::vector<int>* kept = nullptr,
                                           const std::vector<char>* bad_elsewhere = nullptr);

/// Removes, repeatedly until none is left, every *ear* of `mesh` below the
/// floor: a tet three of whose faces are boundary faces around an apex node
/// that is in no other tet, whose four nodes have `on_surface[n] != 0`, and
/// whose smallest dihedral angle is below `floor_deg` (deg) or whose signed
/// volume is <= 0. No node move that keeps the nodes on the surface raises
/// such a tet when the surface flattens under it; removing it makes its
/// fourth face boundary (the base's edges stay in exactly two boundary faces,
/// so the boundary stays 2-manifold) and drops the apex node, which is then in
/// no tet. The remaining nodes keep their order: `kept_nodes` (#N' indices
/// into the input's nodes) and `kept_tets` (#T' indices into the input's
/// tets) receive the survivors, so per-node and per-tet fields can follow.
/// `removed` counts tets (= nodes) removed; `kept_bad` ears below the floor
/// that stay (their apex is in other tets too, e.g. at a pinched vertex).
/// Deterministic (lowest tet index first).
BoundaryCapReport remove_bad_boundary_ears(TetMesh& mesh, const std::vector<char>& on_surface, double floor_deg,
                                           std::vector<int>* kept_tets = nullptr,
                                           std::vector<int>* kept_nodes = nullptr);
/// The same for the tets `elements` judged at every geometry of `set` (an
/// ear goes if it is inverted or below `floor_deg` at one of them).
/// `elements` is renumbered to the kept nodes; the geometries are not touched
/// (compact them with `kept_nodes`).
BoundaryCapReport remove_bad_boundary_ears(Tets& elements, const GeometrySet& set,
                                           const std::vector<char>& on_surface, double floor_deg,
                                           std::vector<int>* kept_tets = nullptr,
                                           std::vector<int>* kept_nodes = nullptr);

}  // namespace sflsh
