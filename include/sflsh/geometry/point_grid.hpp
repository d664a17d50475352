#pragma once
// Broad phase over sample points: a uniform grid hash (Teschner et al. 2003,
// "Optimized spatial hashing for collision detection") built from #N by 3
// points. query() returns the points inside a box, visiting only the cells the
// box overlaps (or, for a box larger than the occupied region, only the
// occupied cells), so contact cost follows the samples near an object rather
// than the surface size. Rebuild it whenever the points move (O(N log N)).
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/geometry/aabb.hpp"

namespace sflsh::geometry {

class PointGrid {
 public:
  PointGrid() = default;
  /// Bins #N by 3 points (m, finite) into cubic cells of `cell_size` m (> 0;
  /// about the size of the typical query box or the sample spacing works well).
  PointGrid(const Points& points, double cell_size);

  /// Indices (ascending) of the points p with box.min <= p <= box.max
  /// (closed box; an unbounded box returns every point). `out` is overwritten.
  void query(const Aabb& box, std::vector<int>& out) const;
  /// Convenience form of query().
  std::vector<int> query(const Aabb& box) const;
  /// The point nearest x within `max_distance` (m): its index, or −1 when
  /// none is that close; its distance goes to `distance`. Visits the cells in
  /// rings of growing Chebyshev radius around x's cell and stops once no
  /// farther ring can hold a nearer point, so a query costs what lies
  /// between x and its nearest point.
  int nearest(const Vec3& x, double max_distance, double* distance = nullptr) const;
  /// Whether some occupied cell overlaps `box`: false guarantees that query(box)
  /// is empty (true does not guarantee a point inside). Costs the cells the
  /// box overlaps, not their points: a cheap first test with a coarse grid.
  bool occupied(const Aabb& box) const;

  int num_points() const { return int(points_.rows()); }
  int num_cells() const { return int(cells_.size()); }
  double cell_size() const { return cell_; }

 private:
  using Key = std::uint64_t;
  Eigen::Vector3i cell_of(const Vec3& p) const;
  static Key key(const Eigen::Vector3i& c);

  Points points_;
  double cell_ = 1;
  Eigen::Vector3i lo_ = Eigen::Vector3i::Zero(), hi_ = Eigen::Vector3i::Zero();  ///< occupied cell range
  std::vector<int> order_;                           ///< point indices sorted by cell
  std::unordered_map<Key, std::pair<int, int>> cells_;  ///< cell -> [begin, end) in order_
};

}  // namespace sflsh::geometry
