#pragma once
// Per-vertex normals of a triangle surface, for shading and for exports that
// carry normals (glTF).
#include "sflsh/core/types.hpp"

namespace sflsh::io {

/// Area-weighted vertex normals (#V by 3, unit length; zero for vertices in
/// no face or only in degenerate faces). `F` is #F by 3, counter-clockwise
/// seen from outside, so normals point outwards.
Points vertex_normals(const Points& V, const Triangles& F);

}  // namespace sflsh::io
