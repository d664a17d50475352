#pragma once
// Animated surfaces as one glTF 2.0 binary (.glb) that viewers play back
// (Blender's glTF importer, three.js / Babylon viewers, Windows 3D Viewer).
//
// Assimp 5.2's glTF2 exporter writes node animations but not morph-weight
// animations, so this writer produces the file itself (glTF 2.0 spec §3.7.2.2
// morph targets, §3.11 animations): frame 0 is the base mesh, every later
// frame k is a morph target holding (positions_k − positions_0) and
// (normals_k − normals_0), and one animation drives the mesh weights with a
// one-hot keyframe per frame. LINEAR interpolation between keyframes then
// reproduces linear interpolation of vertex positions between frames.
// Size: about 24 bytes per vertex per frame (10k vertices, 300 frames: 72 MB).
#include <string>
#include <vector>

#include "sflsh/core/types.hpp"

namespace sflsh::io {

/// Writes `frames` (each #V by 3, metres, same #V) with faces F (#F by 3) as
/// an animated .glb playing at `fps` frames per second. `colors` is empty or
/// #V by 3 RGB in [0, 1] (constant over time). Atomic; throws naming the path
/// on empty input, mismatched sizes, NaN or a name not ending in .glb.
void write_animated_glb(const std::string& path, const std::vector<Points>& frames, const Triangles& F, double fps,
                        const Points& colors = Points());

}  // namespace sflsh::io
