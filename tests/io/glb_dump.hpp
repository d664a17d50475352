#pragma once
// The parts of a .glb that tests check, read by tests/io/glb_dump.py (Python's
// json + struct: a reader independent of the C++ writer).
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace sflsh::test {

struct GlbDump {
  struct Node {
    int mesh = -1;
    std::vector<double> translation, rotation;  ///< empty when the node has none; rotation x y z w
    std::string name;
  };
  struct Channel {
    int node = -1;
    std::string path, interpolation;
    int num_keys = 0;
    std::vector<double> times;
    std::vector<std::vector<double>> values;  ///< per key (translation: 3, rotation: x y z w)
  };
  std::vector<int> scene_nodes;
  std::vector<Node> nodes;
  std::vector<int> mesh_material, mesh_vertices;
  std::vector<bool> material_double_sided;
  std::vector<std::vector<double>> material_color;
  std::vector<Channel> channels;
  /// The channel of `node` animating `path`, or nullptr.
  const Channel* channel(int node, const std::string& path) const {
    for (const Channel& c : channels)
      if (c.node == node && c.path == path) return &c;
    return nullptr;
  }
};

/// Reads `glb` with glb_dump.py; fails the test (and returns an empty dump) if the script fails.
inline GlbDump dump_glb(const std::string& glb) {
  std::string out;
  const int rc = run_command("/usr/bin/python3 " + source_dir() + "/tests/io/glb_dump.py " + glb, &out);
  GlbDump d;
  EXPECT_EQ(rc, 0) << out;
  if (rc != 0) return d;
  std::istringstream lines(out);
  std::string line;
  auto numbers_until_bar = [](std::istringstream& is) {
    std::vector<double> v;
    std::string tok;
    while (is >> tok && tok != "|") v.push_back(std::stod(tok));
    return v;
  };
  while (std::getline(lines, line)) {
    std::istringstream is(line);
    std::string kind;
    is >> kind;
    if (kind == "scene") {
      int n;
      while (is >> n) d.scene_nodes.push_back(n);
    } else if (kind == "node") {
      GlbDump::Node n;
      int index;
      is >> index >> n.mesh;
      n.translation = numbers_until_bar(is);
      n.rotation = numbers_until_bar(is);
      is >> std::ws;
      std::getline(is, n.name);
      d.nodes.push_back(n);
    } else if (kind == "mesh") {
      int index, material, count;
      is >> index >> material >> count;
      d.mesh_material.push_back(material);
      d.mesh_vertices.push_back(count);
    } else if (kind == "material") {
      int index, two_sided;
      is >> index >> two_sided;
      d.material_double_sided.push_back(two_sided != 0);
      std::vector<double> c(4);
      for (double& x : c) is >> x;
      d.material_color.push_back(c);
    } else if (kind == "channel") {
      GlbDump::Channel c;
      is >> c.node >> c.path >> c.num_keys >> c.interpolation;
      d.channels.push_back(c);
    } else if (kind == "key") {
      double t, x;
      is >> t;
      std::vector<double> v;
      while (is >> x) v.push_back(x);
      d.channels.back().times.push_back(t);
      d.channels.back().values.push_back(v);
    }
  }
  return d;
}

}  // namespace sflsh::test
