#pragma once
// Quality-improving flips of a tet mesh (no node moves): the 2-3 flip (two
// tets sharing an interior face become three around the edge joining their
// opposite nodes) and the 3-2 flip (the three tets around an interior edge
// become two sharing the face of the three other nodes). The boundary
// faces are kept as they are; used by the shape stage on tets a shape
// flattened where no node move helps (all four nodes on the skin).
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh {

struct TetFlipReport {
  int flips_2_3 = 0, flips_3_2 = 0;
  int flips_2_2 = 0;  ///< boundary 2-2 flips (flip_bad_boundary_edges)
  double min_dihedral_before = 0, min_dihedral_after = 0;  ///< deg, over the whole mesh
};

/// Repeatedly (at most `rounds` sweeps, until no flip is made) tries, for
/// every tet whose smallest dihedral angle is below `target_deg` (deg), the
/// 2-3 flip across each of its interior faces and the 3-2 flip around each of
/// its edges that has exactly three tets in a closed ring; a flip is made only
/// if every new tet is positively oriented and the smallest dihedral angle of
/// the new tets exceeds that of the tets they replace, so the mesh's minimum
/// never drops, no tet inverts and the boundary surface is unchanged.
/// `parent` (#T', optional) receives for every output tet the index of an
/// input tet it replaces (itself if untouched), so per-tet fields can follow.
/// Deterministic.
TetFlipReport flip_bad_tets(TetMesh& mesh, double target_deg, int rounds = 4, std::vector<int>* parent = nullptr);

/// The boundary 2-2 flip, for a bad tet whose boundary face is itself a
/// needle or a flat triangle on the surface (no fourth-node position helps
/// then): two tets (a, q, r, i), (b, q, r, i) that are the only tets around
/// the boundary edge (q, r), with boundary faces (a, q, r), (b, q, r), become
/// (a, b, q, i), (a, b, r, i): the surface edge q–r gives way to a–b, the
/// surface is retriangulated on the same four surface nodes (`on_surface`,
/// #N flags) and no node moves. Made, for every tet below `target_deg` (deg),
/// only if a–b is not an edge yet, q and r lie on opposite sides of the plane
/// (a, b, i), both new tets are positively oriented and their smallest
/// dihedral angle exceeds that of the two they replace. Repeats up to
/// `rounds` sweeps. The enclosed volume changes by the sliver (a, b, q, r)
/// between the two triangulations of the surface quad. `parent` as above.
/// Counts go to flips_2_2. Deterministic.
TetFlipReport flip_bad_boundary_edges(TetMesh& mesh, const std::vector<char>& on_surface, double target_deg,
                                      int rounds = 4, std::vector<int>* parent = nullptr);

}  // namespace sflsh
