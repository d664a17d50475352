#include "sflsh/geometry/primitive_meshes.hpp"

#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "sflsh/core/error.hpp"

namespace sflsh::geometry {
namespace {

constexpr double kPi = 3.14159265358979323846;

void require_resolution(int resolution, int minimum, const char* shape) {
  require(resolution >= minimum, shape, ": resolution must be >= ", minimum, ", got ", resolution);
}

/// A profile point (ρ, y) of a surface of revolution about Y.
using ProfilePoint = std::pair<double, double>;

/// Revolves `profile` (from the bottom pole to the top pole, both with ρ = 0,
/// every other point with ρ > 0) about Y in `segments` steps. Ring points are
/// (ρ cos θ, y, −ρ sin θ): walking θ forward and up the profile spans an
/// outward normal, so the quads (lower k, lower k+1, upper k+1, upper k) are
/// counter-clockwise from outside; at the poles they collapse to fans.
PrimitiveMesh revolve(const std::vector<ProfilePoint>& profile, int segments) {
  const int rings = int(profile.size()) - 2;  // without the poles
  PrimitiveMesh m;
  m.vertices.resize(2 + Eigen::Index(rings) * segments, 3);
  m.vertices.row(0) << 0.0, profile.front().second, 0.0;
  for (int i = 0; i < rings; ++i) {
    const auto [rho, y] = profile[size_t(i) + 1];
    for (int k = 0; k < segments; ++k) {
      const double t = 2 * kPi * k / segments;
      m.vertices.row(1 + Eigen::Index(i) * segments + k) << rho * std::cos(t), y, -rho * std::sin(t);
    }
  }
  const int top = int(m.vertices.rows()) - 1;
  m.vertices.row(top) << 0.0, profile.back().second, 0.0;
  auto ring = [&](int i, int k) { return 1 + i * segments + k % segments; };
  m.faces.resize(2 * Eigen::Index(segments) * rings, 3);
  Eigen::Index f = 0;
  for (int k = 0; k < segments; ++k) {
    m.faces.row(f++) << 0, ring(0, k + 1), ring(0, k);
    m.faces.row(f++) << ring(rings - 1, k), ring(rings - 1, k + 1), top;
    for (int i = 0; i + 1 < rings; ++i) {
      m.faces.row(f++) << ring(i, k), ring(i, k + 1), ring(i + 1, k + 1);
      m.faces.row(f++) << ring(i, k), ring(i + 1, k + 1), ring(i + 1, k);
    }
  }
  return m;
}

/// Rows along a straight side of length `length` spaced about like the
/// segments of a circle of radius r (at least 1).
int side_rows(double length, double radius, int segments) {
  return std::max(1, int(std::lround(length / (2 * kPi * radius / segments))));
}

/// Appends the quarter arc of radius r about (0, y_center) from angle a0 to a1
/// (measured from −Y towards +ρ... i.e. point (r sin a, y_center − r cos a)),
/// `steps` points, the first excluded.
void add_arc(std::vector<ProfilePoint>& p, double r, double y_center, double a0, double a1, int steps) {
  for (int j = 1; j <= steps; ++j) {
    const double a = a0 + (a1 - a0) * j / steps;
    p.push_back({r * std::sin(a), y_center - r * std::cos(a)});
  }
}

void add_segment(std::vector<ProfilePoint>& p, ProfilePoint to, int steps) {
  const ProfilePoint from = p.back();
  for (int j = 1; j <= steps; ++j) {
    const double s = double(j) / steps;
    p.push_back({from.first + (to.first - from.first) * s, from.second + (to.second - from.second) * s});
  }
}

}  // namespace

PrimitiveMesh sphere_mesh(double radius, int resolution) { return capsule_mesh(radius, 0.0, resolution); }

PrimitiveMesh capsule_mesh(double radius, double half_length, int resolution) {
  const CapsuleSdf check(radius, half_length);  // validates the sizes
  require_resolution(resolution, 3, "capsule mesh");
  const int arc = std::max(2, resolution / 4);
  std::vector<ProfilePoint> p = {{0.0, -half_length - radius}};
  add_arc(p, radius, -half_length, 0.0, kPi / 2, arc);  // ends at (r, −h)
  if (half_length > 0) add_segment(p, {radius, half_length}, side_rows(2 * half_length, radius, resolution));
  add_arc(p, radius, half_length, kPi / 2, kPi, arc);  // ends at (0, h + r)
  p.back() = {0.0, half_length + radius};              // exactly on the axis
  return revolve(p, resolution);
}

PrimitiveMesh cylinder_mesh(double radius, double half_height, int resolution) {
  const CylinderSdf check(radius, half_height);
  require_resolution(resolution, 3, "cylinder mesh");
  const int cap = std::max(1, int(std::lround(resolution / (2 * kPi))));
  std::vector<ProfilePoint> p = {{0.0, -half_height}};
  add_segment(p, {radius, -half_height}, cap);
  add_segment(p, {radius, half_height}, side_rows(2 * half_height, radius, resolution));
  add_segment(p, {0.0, half_height}, cap);
  return revolve(p, resolution);
}

PrimitiveMesh box_mesh(const Vec3& half_extents, int resolution) {
  const BoxSdf check(half_extents);
  require_resolution(resolution, 1, "box mesh");
  const int n = resolution;
  // Surface points of the integer lattice [0, n]³, each made once.
  const auto lattice = [n](int i, int j, int k) { return (size_t(i) * size_t(n + 1) + size_t(j)) * size_t(n + 1) + size_t(k); };
  std::vector<int> index(size_t(n + 1) * size_t(n + 1) * size_t(n + 1), -1);
  std::vector<Vec3> verts;
  std::vector<std::array<int, 3>> faces;
  auto vertex = [&](const std::array<int, 3>& c) {
    int& id = index[lattice(c[0], c[1], c[2])];
    if (id < 0) {
      id = int(verts.size());
      Vec3 x;
      for (int a = 0; a < 3; ++a) x[a] = half_extents[a] * (2.0 * c[a] / n - 1.0);
      verts.push_back(x);
    }
    return id;
  };
  for (int a = 0; a < 3; ++a) {
    // Face axes u, v with e_u × e_v = e_a: counter-clockwise in (u, v) faces +a.
    const int u = (a + 1) % 3, v = (a + 2) % 3;
    for (int side = 0; side < 2; ++side)
      for (int p = 0; p < n; ++p)
        for (int q = 0; q < n; ++q) {
          std::array<int, 3> c00{}, c10{}, c11{}, c01{};
          for (auto* c : {&c00, &c10, &c11, &c01}) (*c)[size_t(a)] = side * n;
          c00[size_t(u)] = p, c00[size_t(v)] = q;
          c10[size_t(u)] = p + 1, c10[size_t(v)] = q;
          c11[size_t(u)] = p + 1, c11[size_t(v)] = q + 1;
          c01[size_t(u)] = p, c01[size_t(v)] = q + 1;
          const int i00 = vertex(c00), i10 = vertex(c10), i11 = vertex(c11), i01 = vertex(c01);
          if (side == 1) {
            faces.push_back({i00, i10, i11});
            faces.push_back({i00, i11, i01});
          } else {  // the −a side faces the other way
            faces.push_back({i00, i11, i10});
            faces.push_back({i00, i01, i11});
          }
        }
  }
  PrimitiveMesh m;
  m.vertices.resize(Eigen::Index(verts.size()), 3);
  for (size_t i = 0; i < verts.size(); ++i) m.vertices.row(Eigen::Index(i)) = verts[i].transpose();
  m.faces.resize(Eigen::Index(faces.size()), 3);
  for (size_t i = 0; i < faces.size(); ++i) m.faces.row(Eigen::Index(i)) << faces[i][0], faces[i][1], faces[i][2];
  return m;
}

PrimitiveMesh plane_patch_mesh(const Vec3& normal, double offset, double half_size, const Vec3& center,
                               int resolution) {
  const PlaneSdf plane(normal, offset);  // validates and normalizes
  require(std::isfinite(half_size) && half_size > 0, "plane patch: half size must be finite and > 0 (m), got ",
          half_size);
  require(center.allFinite(), "plane patch: centre must be finite");
  require_resolution(resolution, 1, "plane patch");
  const Vec3& n = plane.normal();
  Eigen::Index least = 0;
  n.cwiseAbs().minCoeff(&least);
  const Vec3 t1 = n.cross(Vec3::Unit(least)).normalized();
  const Vec3 t2 = n.cross(t1);  // t1 × t2 = n: counter-clockwise in (t1, t2) faces along n
  const Vec3 c = center - (n.dot(center) - offset) * n;
  const int r = resolution;
  PrimitiveMesh m;
  m.vertices.resize(Eigen::Index(r + 1) * (r + 1), 3);
  for (int i = 0; i <= r; ++i)
    for (int j = 0; j <= r; ++j) {
      const double s = half_size * (2.0 * i / r - 1.0), t = half_size * (2.0 * j / r - 1.0);
      m.vertices.row(Eigen::Index(i) * (r + 1) + j) = (c + s * t1 + t * t2).transpose();
    }
  m.faces.resize(2 * Eigen::Index(r) * r, 3);
  Eigen::Index f = 0;
  for (int i = 0; i < r; ++i)
    for (int j = 0; j < r; ++j) {
      const int a = i * (r + 1) + j, b = (i + 1) * (r + 1) + j;  // b: one step along t1
      m.faces.row(f++) << a, b, b + 1;
      m.faces.row(f++) << a, b + 1, a + 1;
    }
  return m;
}

PrimitiveMesh primitive_mesh(const SphereSdf& s, int resolution) { return sphere_mesh(s.radius(), resolution); }
PrimitiveMesh primitive_mesh(const BoxSdf& s, int resolution) { return box_mesh(s.half_extents(), resolution); }
PrimitiveMesh primitive_mesh(const CapsuleSdf& s, int resolution) {
  return capsule_mesh(s.radius(), s.half_length(), resolution);
}
PrimitiveMesh primitive_mesh(const CylinderSdf& s, int resolution) {
  return cylinder_mesh(s.radius(), s.half_height(), resolution);
}
PrimitiveMesh primitive_mesh(const PlaneSdf& s, double half_size, const Vec3& center, int resolution) {
  return plane_patch_mesh(s.normal(), s.offset(), half_size, center, resolution);
}

PrimitiveMesh split_sharp_edges(const Points& V, const Triangles& F, double crease_degrees) {
  require(F.rows() == 0 || (F.minCoeff() >= 0 && F.maxCoeff() < V.rows()), "split_sharp_edges: face indices must lie in [0, ",
          V.rows(), ")");
  const double cos_crease = std::cos(crease_degrees * kPi / 180.0);
  std::vector<Vec3> face_normal(size_t(F.rows()));
  std::vector<std::vector<int>> corners(size_t(V.rows()));  // faces around each vertex
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Vec3 a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const Vec3 n = (b - a).cross(c - a);
    face_normal[size_t(f)] = n.norm() > 0 ? Vec3(n.normalized()) : Vec3::Zero();
    for (int k = 0; k < 3; ++k) corners[size_t(F(f, k))].push_back(int(f));
  }
  // Per vertex, faces join the first group whose first face is within the
  // crease angle (degenerate faces join the first group); each group is a vertex.
  PrimitiveMesh m;
  m.faces = F;
  std::vector<Vec3> verts;
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    std::vector<int> seeds;  // a face per group
    std::vector<int> ids;    // the group's vertex
    for (int f : corners[size_t(v)]) {
      size_t g = 0;
      const Vec3& n = face_normal[size_t(f)];
      while (g < seeds.size() && !(n.isZero() || n.dot(face_normal[size_t(seeds[g])]) >= cos_crease)) ++g;
      if (g == seeds.size()) {
        seeds.push_back(f);
        ids.push_back(int(verts.size()));
        verts.push_back(V.row(v).transpose());
      }
      for (int k = 0; k < 3; ++k)
        if (F(f, k) == v) m.faces(f, k) = ids[g];
    }
  }
  m.vertices.resize(Eigen::Index(verts.size()), 3);
  for (size_t i = 0; i < verts.size(); ++i) m.vertices.row(Eigen::Index(i)) = verts[i].transpose();
  return m;
}

}  // namespace sflsh::geometry
