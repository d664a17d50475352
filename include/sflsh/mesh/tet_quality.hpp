#pragma once
// Element quality of tetrahedral meshes: signed volume, dihedral angles and
// radius ratio per tet, and a summary for reports (precompute, inspect).
#include <string>
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh {

/// Quality figures of one tetrahedron.
struct TetQuality {
  double signed_volume = 0;     ///< m^3, (x1-x0)·((x2-x0)×(x3-x0))/6; > 0 for positive orientation
  double min_dihedral_deg = 0;  ///< smallest of the 6 interior dihedral angles (degrees)
  double max_dihedral_deg = 0;  ///< largest of the 6 interior dihedral angles (degrees)
  /// 3·inradius/circumradius in [0,1]: 1 for the regular tet, 0 for a flat one.
  double radius_ratio = 0;
};

/// Quality of the tet with corners x0..x3 (metres).
TetQuality tet_quality(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3);

/// Quality of tet `t` of `mesh`.
TetQuality tet_quality(const TetMesh& mesh, int t);

/// Summary over a whole mesh.
struct TetQualityReport {
  int num_nodes = 0;
  int num_tets = 0;
  int num_inverted = 0;     ///< signed volume <= 0 (degenerate or inverted)
  double total_volume = 0;  ///< m^3, sum of signed volumes
  double min_volume = 0;    ///< m^3, smallest signed volume
  double min_dihedral_deg = 0, max_dihedral_deg = 0;
  double min_radius_ratio = 0, mean_radius_ratio = 0;
  /// Tets whose smallest dihedral angle is below `sliver_threshold_deg`.
  int num_below_threshold = 0;
  double sliver_threshold_deg = 8.0;

  /// Multi-line human-readable summary.
  std::string describe() const;
};

/// Measures every tet of `mesh`; `sliver_threshold_deg` sets the count
/// `num_below_threshold`.
TetQualityReport tet_quality_report(const TetMesh& mesh, double sliver_threshold_deg = 8.0);

/// Star of every node: the tets incident to it (#N lists of tet indices).
std::vector<std::vector<int>> tet_stars(const TetMesh& mesh);

/// Nodes sharing a tet with each node (#N sorted, unique lists).
std::vector<std::vector<int>> tet_node_neighbours(const TetMesh& mesh);

/// Smallest dihedral angle (deg) over the tets `star` with node `n` placed at
/// `x` instead of its mesh position; -1 if any of them is inverted or flat
/// (signed volume <= 0). The local objective of node relocation.
double star_min_dihedral(const TetMesh& mesh, const std::vector<int>& star, int n, const Vec3& x);

/// Reorders the nodes of every negatively oriented tet (swaps nodes 2 and 3)
/// so all tets are positively oriented; returns how many were flipped.
int orient_tets_positively(TetMesh& mesh);

}  // namespace sflsh
