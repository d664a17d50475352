#pragma once
// Outputs of a simulation that people open elsewhere (the HDF5 result stays
// canonical): PC2 point cache + rest mesh (Blender/Maya/Max), per-frame mesh
// sequences, and a PNG strip of frames coloured by soft displacement.
#include <string>

#include "sflsh/scene/simulation_run.hpp"

namespace sflsh {

/// By extension: ".pc2" writes the cache plus "<stem>_rest.obj" beside it (the
/// first frame's mesh, which the cache animates); ".glb" an animated glTF
/// (morph targets, plays in any glTF viewer); a pattern with a printf-style
/// frame field (e.g. "frames_%04d.obj", .ply, .glb) one mesh per frame.
/// Returns a line saying what was written.
std::string export_result(const SimulationResult& result, const std::string& path);

/// A strip of `num_frames` evenly spaced frames, skin coloured by the soft
/// displacement magnitude |u| in mm, with a colour bar. PNG.
void render_result(const SimulationResult& result, const std::string& path, int num_frames = 6);

}  // namespace sflsh
