#pragma once
// One tet connectivity judged at several node placements at once (for the
// template stage: one placement per design body shape, plus the template's
// own). A topological repair made for one placement must not spoil another:
// the rule below decides whether replacing some tets by others is an
// improvement over the whole set.
#include <array>
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_quality.hpp"

namespace sflsh {

/// #G node placements of the same nodes, each #N by 3 (m). The first is the
/// reference: new tets take their orientation from it.
using GeometrySet = std::vector<Points>;

using TetNodes = std::array<int, 4>;

/// Quality of the tet `t` (node indices, in order) at node positions `x` (#N by 3).
TetQuality tet_quality_at(const Points& x, const TetNodes& t);

/// Smallest dihedral angle (deg) of `tets` at node positions `x` (#N by 3),
/// or −1 when any of them is not positively oriented (so an inverted tet
/// rates below every valid one). 180 for an empty list.
double worst_dihedral_deg(const Points& x, const std::vector<TetNodes>& tets);

/// The acceptance rule of a repair that replaces the tets `old` by `fresh`
/// (an empty `fresh` is a removal): true iff at every geometry of `set`
///   (a) every fresh tet is positively oriented, and
///   (b) min(worst(fresh), cap_deg) >= min(worst(old), cap_deg),
/// and at one geometry at least (b) holds with > (by more than 1e-9 deg). So
/// no placement gets a tet worse than its worst before (or below cap_deg
/// where it was above), no placement gets an inverted tet, and the repair
/// helps one of them. A removal passes (a) and (b) trivially: it must still
/// help one placement (an old tet below cap_deg or inverted there).
bool replacement_accepted(const GeometrySet& set, const std::vector<TetNodes>& fresh,
                          const std::vector<TetNodes>& old, double cap_deg);

/// Orients every tet of `tets` positively at the reference geometry set[0]
/// on its own (swapping two nodes when needed); false if one is degenerate there.
bool orient_at_reference(const GeometrySet& set, std::vector<TetNodes>& tets);

}  // namespace sflsh
