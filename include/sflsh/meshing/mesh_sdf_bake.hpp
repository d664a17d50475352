#pragma once
// Baking a closed triangle mesh into a grid SDF (rigid mesh objects in
// contact): the unsigned distance of each grid node comes from
// CGAL's AABB tree (exact closest point on the triangles), the sign from
// CGAL::Side_of_triangle_mesh (ray parity; needs a closed mesh). The runtime
// then samples the grid (geometry/grid_sdf.hpp) without CGAL.
//
// Narrow band: with band > 0 the nodes are visited in blocks of 4×4×4; a
// block whose centre c is farther than band + (block half-diagonal) from the
// surface is "far": its nodes get the first-order estimate
// φ(c) + ∇φ(c)·(x − c) (the distance to the tangent plane at c's closest
// point, same sign as c) instead of exact queries. Every node with |φ| < band
// is exact.
#include <string>

#include "sflsh/core/types.hpp"
#include "sflsh/geometry/grid_sdf.hpp"

namespace sflsh {

struct MeshSdfBakeOptions {
  /// Grid node spacing (m, > 0). Contact error is about voxel_size²·curvature.
  double voxel_size = 0.005;
  /// Room around the mesh's bounding box on every side (m, >= 0); should
  /// exceed the deepest expected approach so that contact stays in the grid.
  double padding = 0.02;
  /// Exact-distance band (m): 0 computes every node exactly; > 0 computes
  /// nodes with |φ| < band exactly and estimates the far ones (see above).
  double band = 0;
  /// Largest number of grid nodes (guards against a voxel size typo).
  long max_nodes = 64l * 1024 * 1024;
};

/// What a bake or cache lookup did.
struct MeshSdfBakeReport {
  bool cache_hit = false;       ///< the grid came from the cache
  std::string cache_path;       ///< cache file used or written ("" without a cache)
  Eigen::Vector3i dims = Eigen::Vector3i::Zero();
  long exact_nodes = 0;         ///< nodes with an exact AABB-tree query (bake only)
  long estimated_nodes = 0;     ///< far nodes estimated from their block centre (bake only)
  double seconds = 0;           ///< wall time of the bake or the load
  std::string describe() const; ///< one line
};

/// Throws "<what>: a mesh SDF needs a closed manifold triangle mesh; this one
/// has N boundary edges, ..." unless (V, F) is non-empty, finite, closed and
/// manifold (mesh/surface_checks.hpp).
void require_closed_mesh(const Points& V, const Triangles& F, const std::string& what);

/// Bakes the closed mesh (V: #V by 3 m, F: #F by 3) into a grid covering its
/// bounding box plus `padding`, in the mesh's own coordinates. `what` names
/// the mesh in errors (e.g. its file). Throws one sflsh::Error naming `what`
/// when the mesh is not closed and manifold (boundary or non-manifold edges),
/// is empty or non-finite, or the options are out of range.
geometry::GridSdf bake_mesh_sdf(const Points& V, const Triangles& F, const MeshSdfBakeOptions& options = {},
                                const std::string& what = "mesh", MeshSdfBakeReport* report = nullptr);

/// Cache key of a bake: FNV-1a (core/fnv_hash.hpp) of a format tag, V, F and
/// the options; 16 hex digits.
std::string mesh_sdf_cache_key(const Points& V, const Triangles& F, const MeshSdfBakeOptions& options);

/// Reads the triangle mesh at `mesh_path` (OBJ, STL, PLY, ... through
/// assimp, io::read_mesh), multiplies its coordinates by `scale` (e.g. 0.001
/// for a file in mm), and returns its grid SDF: from
/// `<cache_dir>/mesh_sdf/<key>.h5` when present, otherwise baked and stored
/// there (atomically). An empty `cache_dir` disables the cache; an unreadable
/// cache file is baked again and replaced. Errors name `mesh_path`.
geometry::GridSdf load_or_bake_mesh_sdf(const std::string& mesh_path, double scale, const MeshSdfBakeOptions& options,
                                        const std::string& cache_dir, MeshSdfBakeReport* report = nullptr);

}  // namespace sflsh
