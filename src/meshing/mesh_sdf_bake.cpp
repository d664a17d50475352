#include "sflsh/meshing/mesh_sdf_bake.hpp"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <vector>

#include "sflsh/core/error.hpp"
#include "sflsh/core/fnv_hash.hpp"
#include "sflsh/io/mesh_export.hpp"
#include "sflsh/meshing/surface_checks.hpp"

namespace sflsh {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<K::Point_3>;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<SurfaceMesh>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
using Side = CGAL::Side_of_triangle_mesh<SurfaceMesh, K, CGAL::Default, Tree>;

constexpr int kBlock = 4;  // nodes per block edge in the narrow-band pass

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void check_options(const MeshSdfBakeOptions& o, const std::string& what) {
  require(std::isfinite(o.voxel_size) && o.voxel_size > 0, what, ": mesh SDF voxel size must be > 0 m, got ", o.voxel_size);
  require(std::isfinite(o.padding) && o.padding >= 0, what, ": mesh SDF padding must be >= 0 m, got ", o.padding);
  require(std::isfinite(o.band) && o.band >= 0, what, ": mesh SDF band must be >= 0 m, got ", o.band);
}

}  // namespace

void require_closed_mesh(const Points& V, const Triangles& F, const std::string& what) {
  require(V.rows() > 0 && F.rows() > 0, what, ": the mesh is empty");
  const SurfaceReport r = check_surface(V, F, false);  // also rejects NaN and bad indices
  if (!r.is_closed || !r.is_manifold)
    fail(what, ": a mesh SDF needs a closed manifold triangle mesh; this one has ", r.num_boundary_edges,
         " boundary edges, ", r.num_nonmanifold_edges, " non-manifold edges, ", r.num_nonmanifold_vertices,
         " non-manifold vertices and ", r.num_degenerate_faces, " degenerate faces");
}

std::string MeshSdfBakeReport::describe() const {
  std::ostringstream o;
  o << "mesh SDF " << dims.x() << "x" << dims.y() << "x" << dims.z();
  if (cache_hit)
    o << " loaded from " << cache_path;
  else
    o << " baked (" << exact_nodes << " exact, " << estimated_nodes << " estimated nodes)"
      << (cache_path.empty() ? "" : ", cached in " + cache_path);
  o << " in " << seconds << " s";
  return o.str();
}

geometry::GridSdf bake_mesh_sdf(const Points& V, const Triangles& F, const MeshSdfBakeOptions& options,
                                const std::string& what, MeshSdfBakeReport* report) {
  const auto t0 = std::chrono::steady_clock::now();
  check_options(options, what);
  require_closed_mesh(V, F, what);

  SurfaceMesh mesh;
  std::vector<SurfaceMesh::Vertex_index> vi(V.rows());
  for (int v = 0; v < V.rows(); ++v) vi[v] = mesh.add_vertex(K::Point_3(V(v, 0), V(v, 1), V(v, 2)));
  for (int f = 0; f < F.rows(); ++f)
    if (mesh.add_face(vi[F(f, 0)], vi[F(f, 1)], vi[F(f, 2)]) == SurfaceMesh::null_face())
      fail(what, ": face ", f, " cannot be added to a manifold surface (inconsistent orientation?)");
  Tree tree(faces(mesh).first, faces(mesh).second, mesh);
  tree.accelerate_distance_queries();
  const Side side(tree);

  const double h = options.voxel_size;
  const Vec3 lo = V.colwise().minCoeff().transpose().array() - options.padding;
  const Vec3 hi = V.colwise().maxCoeff().transpose().array() + options.padding;
  Eigen::Vector3i dims;
  for (int a = 0; a < 3; ++a) dims[a] = std::max(2, int(std::ceil((hi[a] - lo[a]) / h)) + 1);
  const long n = long(dims.x()) * dims.y() * dims.z();
  require(n <= options.max_nodes, what, ": a mesh SDF of voxel size ", h, " m needs ", n, " nodes (", dims.transpose(),
          "), more than the limit ", options.max_nodes, "; use a larger voxel size");
  // Centre the grid on the padded box.
  const Vec3 origin = 0.5 * (lo + hi) - 0.5 * h * (dims - Eigen::Vector3i::Ones()).cast<double>();

  std::vector<double> values(n);
  auto node = [&](int i, int j, int k) { return Vec3(origin + h * Vec3(i, j, k)); };
  auto index = [&](int i, int j, int k) { return std::size_t(i) + std::size_t(dims.x()) * (j + std::size_t(dims.y()) * k); };
  // Signed distance, the closest surface point of x, and whether x is inside.
  auto exact = [&](const Vec3& x, Vec3* closest) {
    const K::Point_3 p(x.x(), x.y(), x.z());
    const K::Point_3 c = tree.closest_point(p);
    *closest = Vec3(c.x(), c.y(), c.z());
    const double d = (x - *closest).norm();
    return side(p) == CGAL::ON_BOUNDED_SIDE ? -d : d;
  };
  long n_exact = 0, n_estimated = 0;
  const double half_diagonal = 0.5 * std::sqrt(3.0) * h * (kBlock - 1);
  for (int bk = 0; bk < dims.z(); bk += kBlock)
    for (int bj = 0; bj < dims.y(); bj += kBlock)
      for (int bi = 0; bi < dims.x(); bi += kBlock) {
        const int ei = std::min(bi + kBlock, dims.x()), ej = std::min(bj + kBlock, dims.y()),
                  ek = std::min(bk + kBlock, dims.z());
        if (options.band > 0) {
          const Vec3 c = 0.5 * (node(bi, bj, bk) + node(ei - 1, ej - 1, ek - 1));
          Vec3 closest;
          const double dc = exact(c, &closest);
          ++n_exact;
          if (std::abs(dc) > options.band + half_diagonal) {
            // The whole block is farther than `band` and on c's side: the
            // tangent-plane estimate φ(c) + ∇φ(c)·(x − c), ∇φ(c) = (c − closest)/φ(c).
            const Vec3 grad = (c - closest) / dc;
            for (int k = bk; k < ek; ++k)
              for (int j = bj; j < ej; ++j)
                for (int i = bi; i < ei; ++i) values[index(i, j, k)] = dc + grad.dot(node(i, j, k) - c);
            n_estimated += long(ei - bi) * (ej - bj) * (ek - bk);
            continue;
          }
        }
        for (int k = bk; k < ek; ++k)
          for (int j = bj; j < ej; ++j)
            for (int i = bi; i < ei; ++i) {
              Vec3 closest;
              values[index(i, j, k)] = exact(node(i, j, k), &closest);
              ++n_exact;
            }
      }
  geometry::GridSdf grid(origin, h, dims, std::move(values));
  if (report) {
    report->cache_hit = false;
    report->dims = dims;
    report->exact_nodes = n_exact;
    report->estimated_nodes = n_estimated;
    report->seconds = seconds_since(t0);
  }
  return grid;
}

std::string mesh_sdf_cache_key(const Points& V, const Triangles& F, const MeshSdfBakeOptions& options) {
  Fnv1a64 h;
  h.add("sflsh mesh sdf v1");
  const std::int64_t sizes[2] = {V.rows(), F.rows()};
  h.add(sizes, sizeof sizes);
  h.add(V.data(), sizeof(double) * std::size_t(V.size()));
  h.add(F.data(), sizeof(int) * std::size_t(F.size()));
  const double o[3] = {options.voxel_size, options.padding, options.band};
  h.add(o, sizeof o);
  return h.hex();
}

geometry::GridSdf load_or_bake_mesh_sdf(const std::string& mesh_path, double scale, const MeshSdfBakeOptions& options,
                                        const std::string& cache_dir, MeshSdfBakeReport* report) {
  const auto t0 = std::chrono::steady_clock::now();
  require(std::isfinite(scale) && scale > 0, mesh_path, ": mesh scale must be > 0, got ", scale);
  io::ImportedMesh m = io::read_mesh(mesh_path);
  m.vertices *= scale;
  MeshSdfBakeReport local;
  MeshSdfBakeReport& r = report ? *report : local;
  r = MeshSdfBakeReport();
  if (!cache_dir.empty()) {
    // Check the mesh before trusting (or filling) the cache.
    check_options(options, mesh_path);
    require_closed_mesh(m.vertices, m.faces, mesh_path);
    r.cache_path =
        (std::filesystem::path(cache_dir) / "mesh_sdf" / (mesh_sdf_cache_key(m.vertices, m.faces, options) + ".h5")).string();
    if (std::filesystem::exists(r.cache_path)) {
      try {
        geometry::GridSdf grid = geometry::read_grid_sdf(r.cache_path);
        r.cache_hit = true;
        r.dims = grid.dims();
        r.seconds = seconds_since(t0);
        return grid;
      } catch (const Error&) {
        // A damaged cache file: bake again and replace it.
      }
    }
  }
  geometry::GridSdf grid = bake_mesh_sdf(m.vertices, m.faces, options, mesh_path, &r);
  if (!r.cache_path.empty()) {
    std::filesystem::create_directories(std::filesystem::path(r.cache_path).parent_path());
    geometry::write_grid_sdf(grid, r.cache_path);
  }
  r.seconds = seconds_since(t0);
  return grid;
}

}  // namespace sflsh
