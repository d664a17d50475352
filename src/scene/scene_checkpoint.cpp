#include "sflsh/scene/scene_checkpoint.hpp"

#include "sflsh/core/error.hpp"
#include "sflsh/sim/state_file.hpp"

namespace sflsh {

void write_scene_checkpoint(const std::string& path, const Model& model, const State& state,
                            const std::vector<ToolCheckpoint>& tools) {
  write_state(path, model, state, [&](io::Hdf5File& f) {
    if (tools.empty()) return;
    std::vector<std::string> names;
    for (const ToolCheckpoint& t : tools) names.push_back(t.name);
    f.write_strings("/tools/names", names);
    for (size_t i = 0; i < tools.size(); ++i) {
      const std::string g = "/tools/" + std::to_string(i) + "/";
      f.write_scalar(g + "bodies", std::int64_t(tools[i].grasps.size()));
      for (size_t b = 0; b < tools[i].grasps.size(); ++b) {
        const std::vector<Anchor>& held = tools[i].grasps[b];
        if (held.empty()) continue;
        std::vector<int> points;
        MatXr offsets(long(held.size()), 3);
        for (size_t k = 0; k < held.size(); ++k) {
          points.push_back(held[k].point);
          offsets.row(long(k)) = held[k].offset.transpose();
        }
        f.write_nd(g + std::to_string(b) + "/points", points.data(), {std::int64_t(points.size())});
        f.write_matrix(g + std::to_string(b) + "/offsets", offsets);
      }
    }
  });
}

State read_scene_checkpoint(const std::string& path, const Model& model, std::vector<ToolCheckpoint>& tools,
                            const std::vector<int>& skin_vertices) {
  std::vector<ToolCheckpoint> read = tools;
  State s = read_state(path, model, [&](const io::Hdf5File& f) {
    read = tools;
    if (tools.empty()) return;
    require(f.has("/tools/names"), path, ": holds no tools' state (/tools/names), the scene has ", tools.size(),
            " tool(s); write the checkpoint again with this sflsh (sflsh simulate ... --checkpoint)");
    const std::vector<std::string> names = f.read_strings("/tools/names");
    require(names.size() == tools.size(), path, ": /tools/names has ", names.size(), " tools, the scene has ",
            tools.size());
    for (size_t i = 0; i < tools.size(); ++i) {
      require(names[i] == tools[i].name, path, ": /tools/names[", i, "] is '", names[i], "', the scene's tool ", i,
              " is '", tools[i].name, "'");
      const std::string g = "/tools/" + std::to_string(i) + "/";
      const int bodies = f.read_int_scalar(g + "bodies", 0, 1 << 20);
      require(size_t(bodies) == tools[i].grasps.size(), path, ": ", g, "bodies is ", bodies, ", the scene's tool '",
              tools[i].name, "' grasps on ", tools[i].grasps.size());
      for (size_t b = 0; b < size_t(bodies); ++b) {
        std::vector<Anchor>& held = read[i].grasps[b];
        held.clear();
        const std::string gb = g + std::to_string(b) + "/";
        if (!f.has(gb + "points")) continue;
        const auto points = f.read_int_matrix(gb + "points", -1, 1);
        const MatXr offsets = f.read_matrix(gb + "offsets", points.rows(), 3);
        const int n = b < skin_vertices.size() ? skin_vertices[b] : 0;
        for (long k = 0; k < points.rows(); ++k) {
          require(points(k, 0) >= 0 && points(k, 0) < n, path, ": ", gb, "points[", k, "] is ", points(k, 0),
                  ", body ", b, " has ", n, " skin vertices");
          held.push_back({points(k, 0), offsets.row(k).transpose()});
        }
      }
    }
  });
  tools = std::move(read);
  return s;
}

}  // namespace sflsh
