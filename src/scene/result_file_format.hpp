#pragma once
// The result file's layout shared by its writer (result_file.cpp) and reader
// (result_file_reader.cpp): the names of object shapes and kinds, the groups,
// the scene's checks and the 7-number pose rows.
#include <algorithm>
#include <cstddef>
#include <iterator>
#include <string>

#include "sflsh/scene/result_file.hpp"

namespace sflsh::result_file_detail {

inline constexpr const char* kShapes[] = {"plane", "sphere", "box", "capsule", "cylinder", "mesh"};
inline constexpr const char* kKinds[] = {"static", "kinematic", "dynamic"};
/// Largest |‖q‖ − 1| a stored quaternion may have (they are written normalized in float64).
inline constexpr double kUnitTolerance = 1e-6;

template <size_t N>
bool one_of(const std::string& s, const char* const (&list)[N]) {
  return std::find(std::begin(list), std::end(list), s) != std::end(list);
}

template <size_t N>
inline std::string joined(const char* const (&list)[N]) {
  std::string out;
  for (const char* x : list) out += (out.empty() ? "" : ", ") + std::string(x);
  return out;
}

inline std::string object_group(size_t o) { return "/objects/" + std::to_string(o); }
inline std::string tool_group(size_t t) { return "/tools/" + std::to_string(t); }

/// Checks that `scene` fits a skin of V vertices; `where` starts every message
/// (the file path).
void check_scene(const ResultScene& scene, Eigen::Index V, const std::string& where);

/// Pose as 7 numbers: position (m), then the unit quaternion w x y z (w >= 0).
/// Throws naming `what` when T is not finite or not a rigid motion.
void pose_to_row(const Isometry& T, double* out, const std::string& what);
/// The pose of 7 numbers; throws naming `what` when they are not finite or the quaternion is not of unit norm.
Isometry pose_from_row(const double* in, const std::string& what);

}  // namespace sflsh::result_file_detail
