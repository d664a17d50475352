#pragma once
// The result file's layout shared by its writer (result_file.cpp) and reader
// (result_file_reader.cpp): the groups, the scene's checks and the 7-number
// pose rows.
#include <cstddef>
#include <string>

#include "sflsh/scene/result_file.hpp"

namespace sflsh::result_file_detail {

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
