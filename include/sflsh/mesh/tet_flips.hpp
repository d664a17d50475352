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

}  // namespace sflsh
