#include "sflsh/scene/result_export.hpp"

#include <cstdio>
#include <filesystem>

#include "sflsh/core/error.hpp"
#include "sflsh/io/gltf_animation.hpp"
#include "sflsh/io/mesh_export.hpp"
#include "sflsh/io/png_image.hpp"
#include "sflsh/io/point_cache.hpp"
#include "sflsh/io/render.hpp"

namespace sflsh {

std::string export_result(const SimulationResult& r, const std::string& path) {
  require(!r.frame_positions.empty(), path, ": the simulation has no frames to export");
  const std::filesystem::path p(path);
  if (p.extension() == ".pc2") {
    const double fps = r.frame_time.size() > 1 ? 1.0 / (r.frame_time[1] - r.frame_time[0]) : 30.0;
    io::write_pc2(path, r.frame_positions, 0.0, 1.0);
    const std::string rest = (p.parent_path() / (p.stem().string() + "_rest.obj")).string();
    io::write_mesh(rest, r.frame_positions.front(), r.faces);
    char line[512];
    std::snprintf(line, sizeof line, "wrote %s (%zu frames at %.1f fps, %ld points) and its mesh %s", path.c_str(),
                  r.frame_positions.size(), fps, long(r.frame_positions[0].rows()), rest.c_str());
    return line;
  }
  if (p.extension() == ".glb" && path.find('%') == std::string::npos) {
    const double fps = r.frame_time.size() > 1 ? 1.0 / (r.frame_time[1] - r.frame_time[0]) : 30.0;
    io::write_animated_glb(path, r.frame_positions, r.faces, fps);
    return "wrote " + path + " (animated glTF, " + std::to_string(r.frame_positions.size()) + " frames)";
  }
  if (path.find('%') == std::string::npos)
    fail(path, ": --export takes a .pc2 file, an animated .glb, or a per-frame pattern such as frames_%04d.obj");
  io::require_mesh_export_extension(path, "--export");
  for (size_t f = 0; f < r.frame_positions.size(); ++f)
    io::write_mesh(io::format_frame_path(path, int(f)), r.frame_positions[f], r.faces);
  return "wrote " + std::to_string(r.frame_positions.size()) + " meshes " + path;
}

void render_result(const SimulationResult& r, const std::string& path, int num_frames) {
  require(!r.frame_positions.empty(), path, ": the simulation has no frames to render");
  const int F = int(r.frame_positions.size());
  const int n = std::max(1, std::min(num_frames, F));
  std::vector<io::StripFrame> frames;
  double vmax = 0;
  for (int i = 0; i < n; ++i) {
    // Evenly spaced, the last frame included.
    const int f = n == 1 ? 0 : int(std::lround(double(i) * (F - 1) / (n - 1)));
    io::StripFrame fr;
    fr.vertices = r.frame_positions[f];
    fr.values = 1e3 * r.frame_displacement[f].rowwise().norm();
    vmax = std::max(vmax, fr.values.maxCoeff());
    char label[64];
    std::snprintf(label, sizeof label, "t=%.2f s", r.frame_time[f]);
    fr.label = label;
    frames.push_back(std::move(fr));
  }
  io::StripOptions o;
  o.value_min = 0.0;
  o.value_max = std::max(vmax, 1e-3);
  o.value_label = "soft displacement mm";
  o.title = r.motion + ", " + (r.bones_dynamic ? "dynamic" : "kinematic") + " bones";
  io::write_png(path, io::render_strip(frames, r.faces, o));
}

}  // namespace sflsh
