#include "sflsh/volume/topology_design.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <iomanip>
#include <mutex>
#include <sstream>
#include <thread>

#include "sflsh/core/error.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/mesh/boundary_caps.hpp"
#include "sflsh/mesh/geometry_set.hpp"
#include "sflsh/mesh/tet_flips.hpp"
#include "sflsh/mesh/tet_quality.hpp"
#include "sflsh/volume/shape_volume.hpp"

namespace sflsh {

std::string TopologyDesignReport::describe() const {
  std::ostringstream os;
  if (shapes.empty()) return "topology design: none (the mesher's tets)";
  double worst_before = 180, worst_after = 180;
  int bad_before = 0, bad_after = 0, inv_before = 0, inv_after = 0;
  for (size_t i = 0; i < shapes.size(); ++i) {
    worst_before = std::min(worst_before, min_dihedral_before[i]);
    worst_after = std::min(worst_after, min_dihedral_after[i]);
    inv_before += inverted_before[i], inv_after += inverted_after[i];
  }
  os << std::fixed << std::setprecision(3) << "topology design over " << shapes.size()
     << " design shapes: node-only shape stage on the mesher's tets min dihedral " << worst_before << " deg ("
     << inv_before << " inverted), on the repaired tets " << worst_after << " deg (" << inv_after << " inverted); "
     << caps_removed_at_corners << " skin caps bad at one of the " << corners_screened
     << " corners removed first; " << rounds << " rounds of repairs: " << caps_removed << " skin caps removed, "
     << flips_2_3 << " 2-3 and "
     << flips_3_2 << " 3-2 flips, " << flips_2_2 << " skin edges flipped (2-2), " << ears_removed
     << " skin ears removed with their apex node; tets " << tets_before << " -> "
     << tets_before - caps_removed_at_corners - caps_removed + flips_2_3 - flips_3_2 - ears_removed << ", nodes " << nodes_before << " -> "
     << nodes_before - ears_removed << "; " << std::setprecision(1) << seconds << " s";
  for (size_t i = 0; i < shapes.size(); ++i) {
    const bool bad = min_dihedral_after[i] < 8.0 || inverted_after[i] > 0;
    bad_before += min_dihedral_before[i] < 8.0 || inverted_before[i] > 0;
    bad_after += bad;
  }
  os << "; design shapes below 8 deg or inverted: " << bad_before << " -> " << bad_after;
  for (size_t i = 0; i < shapes.size(); ++i)
    if (min_dihedral_after[i] < 8.0 || inverted_after[i] > 0)
      os << "\n    " << shapes[i] << ": " << std::setprecision(3) << min_dihedral_before[i] << " -> "
         << min_dihedral_after[i] << " deg, " << inverted_after[i] << " inverted";
  return os.str();
}

std::vector<std::pair<std::string, VecX>> topology_design_shapes(int num_betas, const TopologyDesignOptions& o) {
  std::vector<std::pair<std::string, VecX>> out;
  const int D = std::min(num_betas, o.directions);
  if (D <= 0) return out;
  std::ostringstream r;
  r << o.range;
  out.emplace_back("zero", VecX::Zero(num_betas));
  for (int d = 0; d < D; ++d)
    for (const double sign : {-1.0, 1.0}) {
      VecX b = VecX::Zero(num_betas);
      b[d] = sign * o.range;
      out.emplace_back("beta" + std::to_string(d) + (sign < 0 ? "=-" : "=+") + r.str(), b);
    }
  VecX lo = VecX::Zero(num_betas), alt = VecX::Zero(num_betas);
  for (int d = 0; d < D; ++d) lo[d] = -o.range, alt[d] = d % 2 ? -o.range : o.range;
  out.emplace_back("all -" + r.str(), lo);
  out.emplace_back("all +" + r.str(), -lo);
  if (D > 1) {
    out.emplace_back("alternating +-", alt);
    out.emplace_back("alternating -+", -alt);
  }
  return out;
}

void keep_template_nodes(TemplateVolume& tv, const std::vector<int>& kept) {
  const int N = tv.tet.num_nodes();
  VecXi new_index = VecXi::Constant(N, -1);
  for (size_t i = 0; i < kept.size(); ++i) {
    require(kept[i] >= 0 && kept[i] < N && (i == 0 || kept[i] > kept[i - 1]), "keep_template_nodes: kept node ",
            kept[i], " at ", i, " is not an increasing index below ", N);
    new_index[kept[i]] = int(i);
  }
  const Eigen::Map<const VecXi> k(kept.data(), Eigen::Index(kept.size()));
  for (Eigen::Index t = 0; t < tv.tet.elements.rows(); ++t)
    for (int c = 0; c < 4; ++c) {
      const int n = new_index[tv.tet.elements(t, c)];
      require(n >= 0, "keep_template_nodes: tet ", t, " uses node ", tv.tet.elements(t, c), ", which is not kept");
      tv.tet.elements(t, c) = n;
    }
  auto renumber_list = [&](const VecXi& list) {
    std::vector<int> out;
    for (Eigen::Index i = 0; i < list.size(); ++i)
      if (new_index[list[i]] >= 0) out.push_back(new_index[list[i]]);
    return VecXi(Eigen::Map<const VecXi>(out.data(), Eigen::Index(out.size())));
  };
  tv.outer_nodes = renumber_list(tv.outer_nodes);
  tv.inner_nodes = renumber_list(tv.inner_nodes);
  tv.tet.nodes = Points(tv.tet.nodes(k, Eigen::all));
  tv.node_face = VecXi(tv.node_face(k));
  tv.node_face_bary = Points(tv.node_face_bary(k, Eigen::all));
  tv.node_skeleton_coefficients = MatXr(tv.node_skeleton_coefficients(k, Eigen::all));
  tv.node_depth = VecX(tv.node_depth(k));
  tv.node_residual = Points(tv.node_residual(k, Eigen::all));
  tv.node_segment = VecXi(tv.node_segment(k));
  tv.node_weights = MatXr(tv.node_weights(k, Eigen::all));
  tv.node_role = VecXi(tv.node_role(k));
  for (Points& d : tv.node_shapedirs) d = Points(d(k, Eigen::all));
  if (tv.node_posedirs.size() > 0) {
    MatX p(3 * kept.size(), tv.node_posedirs.cols());
    for (size_t i = 0; i < kept.size(); ++i) p.middleRows(3 * i, 3) = tv.node_posedirs.middleRows(3 * kept[i], 3);
    tv.node_posedirs = std::move(p);
  }
}

namespace {

std::vector<char> skin_flags(const TemplateVolume& tv) {
  std::vector<char> on_skin(size_t(tv.tet.num_nodes()), 0);
  for (Eigen::Index i = 0; i < tv.outer_nodes.size(); ++i) on_skin[size_t(tv.outer_nodes[i])] = 1;
  return on_skin;
}

// Per-tet regions after an operation whose output tet i descends from input tet parent[i].
void follow_regions(TemplateVolume& tv, const std::vector<int>& parent) {
  VecXi r(Eigen::Index(parent.size()));
  for (size_t i = 0; i < parent.size(); ++i) r[Eigen::Index(i)] = tv.tet_region[parent[i]];
  tv.tet_region = std::move(r);
}

// One round of repairs on tv's tets judged at `set`; returns how many were made.
int repair_round(TemplateVolume& tv, const GeometrySet& set, const TopologyDesignOptions& o,
                 TopologyDesignReport& rep, std::vector<int>* kept_nodes) {
  const std::vector<char> on_skin = skin_flags(tv);
  Tets& e = tv.tet.elements;
  std::vector<int> kept, parent;
  int made = 0;
  auto caps = [&] {
    const int removed = remove_bad_boundary_caps(e, set, on_skin, o.floor_deg, &kept).removed;
    follow_regions(tv, kept);
    rep.caps_removed += removed;
    made += removed;
  };
  caps();
  const TetFlipReport flips = flip_bad_tets(e, set, o.flip_target_deg, 4, &parent);
  follow_regions(tv, parent);
  rep.flips_2_3 += flips.flips_2_3, rep.flips_3_2 += flips.flips_3_2;
  made += flips.flips_2_3 + flips.flips_3_2;
  const int flips_2_2 = flip_bad_boundary_edges(e, set, on_skin, o.floor_deg, 4, &parent).flips_2_2;
  follow_regions(tv, parent);
  rep.flips_2_2 += flips_2_2;
  made += flips_2_2;
  caps();
  // Ears: the tets are selected from the current ones, then every per-node field loses the apexes.
  Tets renumbered = e;
  std::vector<int> nodes;
  const int ears = remove_bad_boundary_ears(renumbered, set, on_skin, o.floor_deg, &kept, &nodes).removed;
  if (ears > 0) {
    Tets sel(Eigen::Index(kept.size()), 4);
    for (size_t i = 0; i < kept.size(); ++i) sel.row(Eigen::Index(i)) = e.row(kept[i]);
    e = sel;
    follow_regions(tv, kept);
    keep_template_nodes(tv, nodes);
    *kept_nodes = nodes;
    rep.ears_removed += ears;
    made += ears;
  }
  return made;
}

// Flags (#T) the tets with four skin nodes that are inverted or below `floor_deg` at some corner
// of [-range, range]^D (the first D shape directions, the rest 0). Skin nodes follow the skin
// linearly in β: a skin node is the point of its skin triangle (node_face, node_face_bary) plus
// its residual, at most the bisection precision (place_shape_nodes: depth 1, so the thickness
// map does not move it), and the skin is v_template + Σ β_b shapedirs[b]. So every corner
// costs a few multiply-adds per node, and the 2^D corners cost seconds, where a node placement
// with its optimization costs seconds per shape.
std::vector<char> skin_tets_bad_at_corners(const TemplateVolume& tv, const BodyModel& model, int D, double range,
                                           double floor_deg) {
  const int N = tv.tet.num_nodes(), T = tv.tet.num_elements();
  const std::vector<char> on_skin = skin_flags(tv);
  std::vector<char> bad(static_cast<size_t>(T), 0);
  if (D <= 0) return bad;
  // Per skin node: its position at β = 0 and its D shape directions, (D + 1) x 3 rows.
  std::vector<Eigen::Matrix<double, Eigen::Dynamic, 3>> dirs(static_cast<size_t>(N));
  for (int n = 0; n < N; ++n) {
    if (!on_skin[size_t(n)]) continue;
    auto& m = dirs[size_t(n)];
    m = Eigen::Matrix<double, Eigen::Dynamic, 3>::Zero(D + 1, 3);
    for (int i = 0; i < 3; ++i) {
      const int v = model.faces(tv.node_face[n], i);
      const double w = tv.node_face_bary(n, i);
      m.row(0) += w * model.v_template.row(v);
      for (int b = 0; b < D; ++b) m.row(b + 1) += w * model.shapedirs[size_t(b)].row(v);
    }
    m.row(0) += tv.node_residual.row(n);
  }
  Eigen::VectorXd coef(D + 1);
  for (int t = 0; t < T; ++t) {
    bool all_skin = true;
    for (int c = 0; c < 4; ++c) all_skin = all_skin && on_skin[size_t(tv.tet.elements(t, c))];
    if (!all_skin) continue;
    for (long corner = 0; corner < (1L << D) && !bad[size_t(t)]; ++corner) {
      coef[0] = 1;
      for (int b = 0; b < D; ++b) coef[b + 1] = (corner >> b & 1) ? range : -range;
      Vec3 p[4];
      for (int c = 0; c < 4; ++c) p[c] = (coef.transpose() * dirs[size_t(tv.tet.elements(t, c))]).transpose();
      const TetQuality q = tet_quality(p[0], p[1], p[2], p[3]);
      bad[size_t(t)] = !(q.signed_volume > 0) || q.min_dihedral_deg < floor_deg;
    }
  }
  return bad;
}

}  // namespace

TopologyDesignReport design_template_topology(TemplateVolume& tv, const BodyModel& model,
                                              const TopologyDesignOptions& o) {
  Timer timer;
  TopologyDesignReport rep;
  rep.tets_before = tv.tet.num_elements();
  rep.nodes_before = tv.tet.num_nodes();
  const auto shapes = topology_design_shapes(model.num_betas(), o);
  if (shapes.empty()) return rep;
  require(o.rounds >= 0, "TopologyDesignOptions::rounds = ", o.rounds, ", expected >= 0");
  const int G = int(shapes.size());
  for (const auto& s : shapes) rep.shapes.push_back(s.first);
  rep.min_dihedral_before.assign(size_t(G), 0), rep.min_dihedral_after.assign(size_t(G), 0);
  rep.inverted_before.assign(size_t(G), 0), rep.inverted_after.assign(size_t(G), 0);
  // The shape stage as `sflsh precompute` runs it by default, with this design's floor and target.
  ShapeOptions so;
  so.quality_floor_deg = o.floor_deg;
  so.smoothing.target_deg = o.flip_target_deg;
  const ThicknessMap thickness = ThicknessMap::defaults();
  // Skin caps that some corner of the shape box turns inside out or flattens: removed first
  // (every corner, on the skin's linear placement; see skin_tets_bad_at_corners).
  {
    const int D = std::min(model.num_betas(), o.directions);
    const std::vector<char> bad = skin_tets_bad_at_corners(tv, model, D, o.range, o.floor_deg);
    std::vector<int> kept;
    rep.caps_removed_at_corners =
        remove_bad_boundary_caps(tv.tet.elements, GeometrySet{tv.tet.nodes}, skin_flags(tv), o.floor_deg, &kept, &bad)
            .removed;
    follow_regions(tv, kept);
    rep.corners_screened = D > 0 ? 1L << D : 0;
  }
  // Then rounds of node placement at the design shapes and repairs. A shape whose placement met
  // the floor keeps it: a repair never makes a design shape worse than min(its minimum, the
  // target) at the placement it was judged on, so only the shapes below the floor are placed
  // again on the repaired tets.
  Progress progress("template: topology design (" + std::to_string(G) + " shapes)", long(G) * (o.rounds + 1));
  long step = 0;
  std::vector<Points> placement(static_cast<size_t>(G));
  std::vector<char> redo(static_cast<size_t>(G), 1);
  for (int round = 0;; ++round) {
    // The shapes are independent: placed on all cores (each result depends on its shape alone,
    // so the design does not depend on the thread count).
    std::vector<int> todo;
    for (int g = 0; g < G; ++g)
      if (redo[size_t(g)]) todo.push_back(g);
    std::vector<TetQualityReport> quality(static_cast<size_t>(G));
    std::atomic<size_t> next{0};
    std::exception_ptr failure;
    std::mutex failure_mutex;
    auto work = [&] {
      for (size_t i; (i = next++) < todo.size();) {
        const int g = todo[i];
        try {
          ShapedNodes placed = place_shape_nodes(tv, model, shapes[size_t(g)].second, thickness, so);
          quality[size_t(g)] = placed.report.quality;
          placement[size_t(g)] = std::move(placed.nodes);
        } catch (...) {
          const std::lock_guard<std::mutex> lock(failure_mutex);
          if (!failure) failure = std::current_exception();
        }
      }
    };
    const int threads = std::max(1, std::min<int>(int(todo.size()), int(std::thread::hardware_concurrency())));
    std::vector<std::thread> pool;
    for (int k = 1; k < threads; ++k) pool.emplace_back(work);
    work();
    for (std::thread& t : pool) t.join();
    if (failure) std::rethrow_exception(failure);
    step += long(G);
    progress.update(step);
    int bad = 0;
    for (int g : todo) {
      const TetQualityReport& q = quality[size_t(g)];
      if (round == 0) rep.min_dihedral_before[size_t(g)] = q.min_dihedral_deg, rep.inverted_before[size_t(g)] = q.num_inverted;
      rep.min_dihedral_after[size_t(g)] = q.min_dihedral_deg, rep.inverted_after[size_t(g)] = q.num_inverted;
      redo[size_t(g)] = q.num_inverted > 0 || q.min_dihedral_deg < o.floor_deg;
      bad += redo[size_t(g)];
    }
    if (bad == 0 || round >= o.rounds) break;
    GeometrySet set{tv.tet.nodes};
    for (const Points& x : placement) set.push_back(x);
    std::vector<int> kept_nodes;
    const int made = repair_round(tv, set, o, rep, &kept_nodes);
    if (made == 0) break;
    ++rep.rounds;
    if (!kept_nodes.empty())  // ears removed: the kept placements lose those nodes too
      for (Points& x : placement)
        if (x.rows() > 0) x = Points(x(Eigen::Map<const VecXi>(kept_nodes.data(), Eigen::Index(kept_nodes.size())), Eigen::all));
  }
  progress.finish();
  require(tet_quality_report(tv.tet).num_inverted == 0, "topology design: the template geometry got inverted tets");
  rep.seconds = timer.seconds();
  return rep;
}

}  // namespace sflsh
