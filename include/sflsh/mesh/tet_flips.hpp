#pragma once
// Quality-improving flips of a tet mesh (no node moves): the 2-3 flip (two
// tets sharing an interior face become three around the edge joining their
// opposite nodes) and the 3-2 flip (the three tets around an interior edge
// become two sharing the face of the three other nodes). The boundary
// faces are kept as they are; and the boundary 2-2 flip. Used by the
// template stage on tets some body shape flattens where no node move helps
// (all four nodes on the skin), judged at every design shape at once
// (mesh/geometry_set.hpp), so that one connectivity serves every shape.
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/mesh/geometry_set.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh {

struct TetFlipReport {
  int flips_2_3 = 0, flips_3_2 = 0;
  int flips_2_2 = 0;  ///< boundary 2-2 flips (flip_bad_boundary_edges)
  double min_dihedral_before = 0, min_dihedral_after = 0;  ///< deg, over the whole mesh
};

/// Repeatedly (at most `rounds` sweeps, until no flip is made) tries, for
/// every tet of `elements` (#T by 4) whose smallest dihedral angle is below
/// `target_deg` (deg) or that is inverted at some geometry of `set`, the 2-3
/// flip across each of its interior faces and the 3-2 flip around each of its
/// edges that has exactly three tets in a closed ring. The new tets take their
/// orientation at set[0] (where the flip must be geometric: they fill exactly
/// the old ones); a flip is made only if replacement_accepted(set, new, old,
/// target_deg): positive everywhere, no geometry worse (capped at target_deg),
/// one better. So no geometry's minimum drops, no tet inverts anywhere and the
/// boundary surface is unchanged. `parent` (#T', optional) receives for every
/// output tet the index of an input tet it replaces (itself if untouched), so
/// per-tet fields can follow. Deterministic.
TetFlipReport flip_bad_tets(Tets& elements, const GeometrySet& set, double target_deg, int rounds = 4,
                            std::vector<int>* parent = nullptr);
/// The same at the one geometry mesh.nodes (min_dihedral_* are over it).
TetFlipReport flip_bad_tets(TetMesh& mesh, double target_deg, int rounds = 4, std::vector<int>* parent = nullptr);

/// The boundary 2-2 flip, for a bad tet whose boundary face is itself a
/// needle or a flat triangle on the surface (no fourth-node position helps
/// then): two tets (a, q, r, i), (b, q, r, i) that are the only tets around
/// the boundary edge (q, r), with boundary faces (a, q, r), (b, q, r), become
/// (a, b, q, i), (a, b, r, i): the surface edge q–r gives way to a–b, the
/// surface is retriangulated on the same four surface nodes (`on_surface`,
/// #N flags) and no node moves. Made, for every tet below `target_deg` (deg)
/// or inverted at some geometry of `set`, only if a–b is not an edge yet, q
/// and r lie on opposite sides of the plane (a, b, i) at set[0] (the two new
/// tets, oriented there, then positive at every geometry says the same
/// everywhere) and replacement_accepted(set, new, old, target_deg). Repeats up
/// to `rounds` sweeps. The enclosed volume changes by the sliver (a, b, q, r)
/// between the two triangulations of the surface quad. `parent` as above.
/// Counts go to flips_2_2. Deterministic.
TetFlipReport flip_bad_boundary_edges(Tets& elements, const GeometrySet& set, const std::vector<char>& on_surface,
                                      double target_deg, int rounds = 4, std::vector<int>* parent = nullptr);
/// The same at the one geometry mesh.nodes.
TetFlipReport flip_bad_boundary_edges(TetMesh& mesh, const std::vector<char>& on_surface, double target_deg,
                                      int rounds = 4, std::vector<int>* parent = nullptr);

}  // namespace sflsh
