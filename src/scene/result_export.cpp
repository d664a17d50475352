#include "sflsh/scene/result_export.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "sflsh/core/error.hpp"
#include "sflsh/io/gltf_animation.hpp"
#include "sflsh/io/mesh_export.hpp"
#include "sflsh/io/png_image.hpp"
#include "sflsh/io/point_cache.hpp"
#include "sflsh/io/render.hpp"

namespace sflsh {
namespace {

/// Albedo of rigid objects in exports and renders (neutral grey).
const Vec3 kObjectColor(0.6, 0.6, 0.6);

/// A plane's patch covers the bodies' projection: half size = kPatchScale·R + kPatchMargin.
constexpr double kPatchScale = 1.2, kPatchMargin = 0.25;  // 1, m

/// V (#N by 3, object frame) under `pose` (world).
Points posed(const Points& V, const Isometry& pose) {
  return (V * pose.linear().transpose()).rowwise() + pose.translation().transpose();
}

/// The square patch drawing plane object `t` under every frame's skin.
geometry::PrimitiveMesh plane_display_patch(const SimulationResult& r, const ObjectTrack& t) {
  Vec3 area = Vec3::Zero();
  for (Eigen::Index f = 0; f < t.faces.rows(); ++f) {
    const Vec3 a = t.vertices.row(t.faces(f, 0)), b = t.vertices.row(t.faces(f, 1)), c = t.vertices.row(t.faces(f, 2));
    area += (b - a).cross(c - a);
  }
  require(area.norm() > 0 && area.allFinite(), "object '", t.name,
          "': a plane's surface must be a flat patch with a normal (its faces have zero total area)");
  const Vec3 n = area.normalized();
  const double offset = n.dot(t.vertices.colwise().mean().transpose());
  // The skin in the plane's frame, projected onto the plane: its box centre
  // and the largest distance from it.
  std::vector<Points> local;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t f = 0; f < r.frame_positions.size(); ++f) {
    Points p = posed(r.frame_positions[f], t.poses[f].inverse());
    p -= ((p * n).array() - offset).matrix() * n.transpose();
    lo = lo.cwiseMin(p.colwise().minCoeff().transpose());
    hi = hi.cwiseMax(p.colwise().maxCoeff().transpose());
    local.push_back(std::move(p));
  }
  const Vec3 center = 0.5 * (lo + hi);
  double radius = 0;
  for (const Points& p : local) radius = std::max(radius, (p.rowwise() - center.transpose()).rowwise().norm().maxCoeff());
  return geometry::plane_patch_mesh(n, offset, kPatchScale * radius + kPatchMargin, center);
}

/// Skin faces followed by every object's faces, shifted to follow the skin's
/// vertices and the objects before them.
Triangles merged_faces(const Triangles& skin, Eigen::Index skin_vertices,
                       const std::vector<geometry::PrimitiveMesh>& objects) {
  Eigen::Index rows = skin.rows();
  for (const auto& m : objects) rows += m.faces.rows();
  Triangles F(rows, 3);
  F.topRows(skin.rows()) = skin;
  Eigen::Index row = skin.rows(), offset = skin_vertices;
  for (const auto& m : objects) {
    F.middleRows(row, m.faces.rows()) = m.faces.array() + int(offset);
    row += m.faces.rows();
    offset += m.vertices.rows();
  }
  return F;
}

/// Frame f's skin followed by every object's display mesh at its pose.
Points merged_frame(const SimulationResult& r, const std::vector<geometry::PrimitiveMesh>& objects, size_t f) {
  Eigen::Index rows = r.frame_positions[f].rows();
  for (const auto& m : objects) rows += m.vertices.rows();
  Points V(rows, 3);
  V.topRows(r.frame_positions[f].rows()) = r.frame_positions[f];
  Eigen::Index row = r.frame_positions[f].rows();
  for (size_t o = 0; o < objects.size(); ++o) {
    V.middleRows(row, objects[o].vertices.rows()) = posed(objects[o].vertices, r.objects[o].poses[f]);
    row += objects[o].vertices.rows();
  }
  return V;
}

/// ", with N rigid objects merged after the skin's M vertices" or "".
std::string merged_note(const SimulationResult& r) {
  if (r.objects.empty()) return "";
  return ", the " + std::to_string(r.objects.size()) + " rigid object(s) merged after the skin's " +
         std::to_string(r.frame_positions.front().rows()) + " vertices";
}

double export_fps(const SimulationResult& r) {
  return r.frame_time.size() > 1 ? 1.0 / (r.frame_time[1] - r.frame_time[0]) : 30.0;
}

}  // namespace

std::vector<geometry::PrimitiveMesh> object_display_meshes(const SimulationResult& r) {
  std::vector<geometry::PrimitiveMesh> out;
  for (const ObjectTrack& t : r.objects) {
    require(t.poses.size() == r.frame_positions.size(), "object '", t.name, "' has ", t.poses.size(), " poses for ",
            r.frame_positions.size(), " frames");
    out.push_back(t.shape == "plane" ? plane_display_patch(r, t) : geometry::PrimitiveMesh{t.vertices, t.faces});
  }
  return out;
}

// The export itself; export_result() adds the incomplete note.
static std::string export_frames(const SimulationResult& r, const std::string& path) {
  require(!r.frame_positions.empty(), path, ": the simulation has no frames to export");
  const std::filesystem::path p(path);
  const std::vector<geometry::PrimitiveMesh> objects = object_display_meshes(r);
  if (p.extension() == ".pc2") {
    std::vector<Points> frames;
    for (size_t f = 0; f < r.frame_positions.size(); ++f) frames.push_back(merged_frame(r, objects, f));
    io::write_pc2(path, frames, 0.0, 1.0);
    const std::string rest = (p.parent_path() / (p.stem().string() + "_rest.obj")).string();
    io::write_mesh(rest, frames.front(), merged_faces(r.faces, r.frame_positions[0].rows(), objects));
    char line[512];
    std::snprintf(line, sizeof line, "wrote %s (%zu frames at %.1f fps, %ld points", path.c_str(), frames.size(),
                  export_fps(r), long(frames[0].rows()));
    return line + merged_note(r) + ") and its mesh " + rest;
  }
  if (p.extension() == ".glb" && path.find('%') == std::string::npos) {
    std::vector<io::GltfRigidNode> nodes;
    for (size_t o = 0; o < objects.size(); ++o) {
      // Split at creases so that box edges and cylinder rims shade sharp.
      const geometry::PrimitiveMesh shown = geometry::split_sharp_edges(objects[o].vertices, objects[o].faces);
      io::GltfRigidNode n{r.objects[o].name, shown.vertices, shown.faces, {}, {}, kObjectColor,
                          r.objects[o].shape == "plane"};
      for (const Isometry& pose : r.objects[o].poses) {
        n.translations.push_back(pose.translation());
        n.rotations.push_back(Eigen::Quaterniond(pose.linear()).normalized());
      }
      nodes.push_back(std::move(n));
    }
    io::write_animated_glb(path, r.frame_positions, r.faces, export_fps(r), Points(), nodes);
    std::string line = "wrote " + path + " (animated glTF, " + std::to_string(r.frame_positions.size()) + " frames";
    if (!nodes.empty()) line += ", " + std::to_string(nodes.size()) + " rigid object node(s)";
    return line + ")";
  }
  if (path.find('%') == std::string::npos)
    fail(path, ": --export takes a .pc2 file, an animated .glb, or a per-frame pattern such as frames_%04d.obj");
  io::require_mesh_export_extension(path, "--export");
  const Triangles F = merged_faces(r.faces, r.frame_positions[0].rows(), objects);
  for (size_t f = 0; f < r.frame_positions.size(); ++f)
    io::write_mesh(io::format_frame_path(path, int(f)), merged_frame(r, objects, f), F);
  return "wrote " + std::to_string(r.frame_positions.size()) + " meshes " + path + merged_note(r);
}

std::string export_result(const SimulationResult& r, const std::string& path) {
  const std::string line = export_frames(r, path);
  return r.incomplete ? line + " [INCOMPLETE result: the run stopped early]" : line;
}

void render_result(const SimulationResult& r, const std::string& path, int num_frames) {
  require(!r.frame_positions.empty(), path, ": the simulation has no frames to render");
  const std::vector<geometry::PrimitiveMesh> objects = object_display_meshes(r);
  std::vector<geometry::PrimitiveMesh> shown;
  for (const auto& m : objects) shown.push_back(geometry::split_sharp_edges(m.vertices, m.faces));
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
    for (size_t o = 0; o < shown.size(); ++o)
      fr.solids.push_back({posed(shown[o].vertices, r.objects[o].poses[size_t(f)]), shown[o].faces, kObjectColor,
                           r.objects[o].shape != "plane"});
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
