#include "scene/result_file_format.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

#include "sflsh/core/error.hpp"

namespace sflsh::result_file_detail {
namespace {

constexpr const char* kShapes[] = {"plane", "sphere", "box", "capsule", "cylinder", "mesh"};
constexpr const char* kKinds[] = {"static", "kinematic", "dynamic"};
/// Largest |‖q‖ − 1| a stored quaternion may have (they are written normalized in float64).
constexpr double kUnitTolerance = 1e-6;

template <size_t N>
bool one_of(const std::string& s, const char* const (&list)[N]) {
  return std::find(std::begin(list), std::end(list), s) != std::end(list);
}

template <size_t N>
std::string joined(const char* const (&list)[N]) {
  std::string out;
  for (const char* x : list) out += (out.empty() ? "" : ", ") + std::string(x);
  return out;
}

}  // namespace

void check_scene(const ResultScene& scene, Eigen::Index V, const std::string& where) {
  const auto& names = scene.body_names;
  const auto& off = scene.body_vertex_offsets;
  require(!names.empty() || off.empty(), where, ": /bodies/vertex_offsets given without /bodies/names");
  if (!names.empty()) {
    require(off.size() == names.size() + 1, where, ": /bodies/names has ", names.size(), " bodies, so /bodies/vertex_offsets needs ",
            names.size() + 1, " entries, got ", off.size());
    require(off.front() == 0 && off.back() == V, where, ": /bodies/vertex_offsets must start at 0 and end at the ", V,
            " skin vertices, got ", off.front(), " ... ", off.back());
    for (size_t b = 0; b + 1 < off.size(); ++b)
      require(off[b] <= off[b + 1], where, ": /bodies/vertex_offsets must not decrease (entry ", b + 1, ")");
  }
  for (size_t o = 0; o < scene.objects.size(); ++o) {
    const ObjectTrack& t = scene.objects[o];
    const std::string at = where + ": " + object_group(o) + " ('" + t.name + "')";
    require(one_of(t.shape, kShapes), at, ": shape '", t.shape, "' is not one of ", joined(kShapes));
    require(one_of(t.kind, kKinds), at, ": kind '", t.kind, "' is not one of ", joined(kKinds));
    require(t.vertices.rows() > 0 && t.faces.rows() > 0, at, ": needs a surface (", t.vertices.rows(), " vertices, ",
            t.faces.rows(), " faces)");
    require(t.vertices.allFinite(), at, ": vertices contain NaN or Inf");
    require(t.faces.minCoeff() >= 0 && t.faces.maxCoeff() < t.vertices.rows(), at, ": face indices must lie in [0, ",
            t.vertices.rows(), ")");
  }
}

void pose_to_row(const Isometry& T, double* out, const std::string& what) {
  const Mat3 R = T.linear();
  require(T.translation().allFinite() && R.allFinite(), what, " is not finite");
  require((R.transpose() * R - Mat3::Identity()).norm() < kUnitTolerance && R.determinant() > 0, what,
          " is not a rigid motion (its linear part is not a rotation)");
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1.0;
  const Vec3 p = T.translation();
  const double row[7] = {p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z()};
  std::copy(row, row + 7, out);
}

Isometry pose_from_row(const double* in, const std::string& what) {
  require(std::all_of(in, in + 7, [](double v) { return std::isfinite(v); }), what, ": the pose is not finite");
  Eigen::Quaterniond q(in[3], in[4], in[5], in[6]);
  require(std::abs(q.norm() - 1.0) < kUnitTolerance, what, ": quaternion (w x y z) has norm ", q.norm(),
          ", expected a unit quaternion");
  Isometry T = Isometry::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Vec3(in[0], in[1], in[2]);
  return T;
}

}  // namespace sflsh::result_file_detail
