#include "sflsh/sim/energies/skin_contact.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>

#include "sflsh/core/error.hpp"
#include "sflsh/geometry/aabb.hpp"
#include "sflsh/geometry/point_grid.hpp"
#include "sflsh/geometry/triangle_closest_point.hpp"

namespace sflsh {
namespace {

/// How far ahead of the last step's motion the broad phase looks: a pair
/// approaching at the speed of its last step closes m_a + m_b over the next
/// one; the rest (and the margin) covers its acceleration.
constexpr double kMotionFactor = 1.5;

struct PairCache : TermCache {
  std::vector<SkinContactTerm::Pair> pairs;
  // The vertices the pairs use, per skin, and each vertex's place in that list
  // (−1: unused): an evaluation poses each of them once.
  std::vector<int> used[2];
  std::vector<int> slot[2];
  // Scratch of compute(): one sample's row nᵀ(J_a − J_b) over the local DoFs.
  VecX row;
  std::vector<int> touched;
  std::vector<char> mark;
};

SkinContactTerm::Skin make_skin(const Avatar& avatar, int max_handles) {
  SkinContactTerm::Skin s;
  s.vertices = PosedPoints::at_surface(avatar).with_truncated_rows(max_handles);
  s.rest = avatar.surface_rest;
  s.faces = avatar.surface_faces;
  s.vertex_faces.assign(s.rest.rows(), {});
  s.vertex_neighbours.assign(s.rest.rows(), {});
  for (int f = 0; f < int(s.faces.rows()); ++f)
    for (int c = 0; c < 3; ++c) {
      s.vertex_faces[s.faces(f, c)].push_back(f);
      s.max_edge = std::max(s.max_edge, (s.rest.row(s.faces(f, c)) - s.rest.row(s.faces(f, (c + 1) % 3))).norm());
      s.vertex_neighbours[s.faces(f, c)].push_back(s.faces(f, (c + 1) % 3));
      s.vertex_neighbours[s.faces(f, (c + 1) % 3)].push_back(s.faces(f, c));
    }
  for (auto& n : s.vertex_neighbours) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  return s;
}

Vec3 face_point(const Points& x, const Triangles& faces, int f, const Vec3& l) {
  return l[0] * x.row(faces(f, 0)).transpose() + l[1] * x.row(faces(f, 1)).transpose() +
         l[2] * x.row(faces(f, 2)).transpose();
}

Vec3 face_normal(const Points& x, const Triangles& faces, int f) {
  const Vec3 a = x.row(faces(f, 0)).transpose(), b = x.row(faces(f, 1)).transpose(), c = x.row(faces(f, 2)).transpose();
  const Vec3 n = (b - a).cross(c - a);
  const double len = n.norm();
  return len > 0 ? Vec3(n / len) : Vec3::Zero();
}

/// The point of skin `to` (posed at x_to) closest to x among the faces around
/// its vertex w and w's neighbours (where a smooth skin's closest point lies
/// when w is x's nearest vertex), and the normal of a pair there: the face's
/// where the point is inside it, else (an edge or a corner) the direction
/// from it to x, signed by the side of the faces that share the point (the
/// sum of their normals: one face's alone is ambiguous where x lies in its
/// plane), so that normalᵀ(x − y) is the signed distance. `faces` is scratch.
struct SkinPoint {
  int face = -1;
  Vec3 mu = Vec3::Zero();
  Vec3 normal = Vec3::Zero();
  double distance = std::numeric_limits<double>::infinity();
};
SkinPoint closest_skin_point(const Vec3& x, const SkinContactTerm::Skin& to, const Points& x_to, int w,
                             std::vector<int>& faces) {
  faces.assign(to.vertex_faces[w].begin(), to.vertex_faces[w].end());
  for (int u : to.vertex_neighbours[w]) faces.insert(faces.end(), to.vertex_faces[u].begin(), to.vertex_faces[u].end());
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  auto closest_on = [&](int g, const Vec3& y) {  // barycentric coordinates of face g's point closest to y
    return geometry::closest_point_on_triangle(y, x_to.row(to.faces(g, 0)).transpose(),
                                               x_to.row(to.faces(g, 1)).transpose(), x_to.row(to.faces(g, 2)).transpose());
  };
  SkinPoint p;
  for (int g : faces) {
    const Vec3 mu = closest_on(g, x);
    const double d = (x - face_point(x_to, to.faces, g, mu)).norm();
    if (d < p.distance) {
      p.distance = d;
      p.face = g;
      p.mu = mu;
    }
  }
  if (p.face < 0) return p;
  const Vec3 offset = x - face_point(x_to, to.faces, p.face, p.mu);
  p.normal = face_normal(x_to, to.faces, p.face);
  if ((p.mu.array() <= 0).any() && p.distance > 1e-9) {
    Vec3 side = Vec3::Zero();  // the faces at the closest point: those as close (to round-off)
    const Vec3 y = x - offset;
    for (int g : faces)
      if ((y - face_point(x_to, to.faces, g, closest_on(g, y))).norm() <= 1e-9 * (1.0 + p.distance))
        side += face_normal(x_to, to.faces, g);
    p.normal = (side.dot(offset) < 0 ? -1.0 : 1.0) * offset / p.distance;
  }
  return p;
}

}  // namespace

SkinContactTerm::SkinContactTerm(const Avatar& a, const Avatar& b, const SkinContactOptions& o) : options_(o) {
  check_contact_sampling(o.pressure_stiffness, o.spacing, "skin contact");
  require(std::isfinite(o.margin) && o.margin >= 0, "skin contact: margin ", o.margin, " m, expected >= 0");
  require(std::isfinite(o.max_depth) && o.max_depth > 0, "skin contact: max depth ", o.max_depth, " m, expected > 0");
  require(a.surface_faces.rows() > 0 && b.surface_faces.rows() > 0, "skin contact: an avatar has no skin faces");
  skins_[0] = make_skin(a, o.max_handles);
  skins_[1] = make_skin(b, o.max_handles);
}

/// World positions of the vertices the pairs use (row k: used[side][k]) at q[0], q[1].
std::array<Points, 2> SkinContactTerm::posed_vertices(const TermCache& cache, const Configuration* const q[2]) const {
  const auto& c = static_cast<const PairCache&>(cache);
  std::array<Points, 2> x;
  for (int side = 0; side < 2; ++side) {
    x[side].resize(c.used[side].size(), 3);
    for (size_t k = 0; k < c.used[side].size(); ++k)
      x[side].row(k) = skins_[side].vertices.world_point(c.used[side][k], *q[side]).transpose();
  }
  return x;
}

double SkinContactTerm::gap(const Pair& p, const TermCache& cache, const std::array<Points, 2>& x) const {
  const auto& c = static_cast<const PairCache&>(cache);
  const int from = p.side, to = 1 - p.side;
  Vec3 a = Vec3::Zero(), b = Vec3::Zero();
  for (int i = 0; i < 3; ++i) {
    a += p.lambda[i] * x[from].row(c.slot[from][skins_[from].faces(p.face, i)]).transpose();
    b += p.mu[i] * x[to].row(c.slot[to][skins_[to].faces(p.other_face, i)]).transpose();
  }
  return p.normal.dot(a - b);
}

std::unique_ptr<TermCache> SkinContactTerm::make_cache() const { return std::make_unique<PairCache>(); }

void SkinContactTerm::collect_pairs(int side, const Skin& from, const Points& x_from, const VecX& m_from,
                                    const Skin& to, const Points& x_to, const VecX& m_to,
                                    std::vector<Pair>& out) const {
  // Reach of a vertex v of this skin: the margin plus twice its own motion
  // over the last step and twice the fastest of the other skin's.
  const double fastest_to = m_to.size() ? m_to.maxCoeff() : 0.0;
  auto reach = [&](double m) { return options_.margin + kMotionFactor * (m + fastest_to); };
  const double slack = to.max_edge;  // a surface point is within an edge of one of its face's vertices
  const double max_reach = reach(m_from.size() ? m_from.maxCoeff() : 0.0) + slack;
  const geometry::Aabb near_from = geometry::Aabb::of_points(x_from).inflated(max_reach);
  std::vector<int> to_index;
  for (int w = 0; w < int(x_to.rows()); ++w)
    if (near_from.contains(x_to.row(w).transpose())) to_index.push_back(w);
  if (to_index.empty()) return;
  Points to_near(to_index.size(), 3);
  for (size_t i = 0; i < to_index.size(); ++i) to_near.row(i) = x_to.row(to_index[i]);
  const geometry::PointGrid grid(to_near, 0.02);
  const geometry::Aabb near_to = geometry::Aabb::of_points(to_near);
  // A coarse grid (cells of the largest reach) rules out most far vertices in a few lookups.
  const geometry::PointGrid coarse(to_near, std::max(max_reach, 0.02));

  // This skin's faces with a vertex within reach of the other skin's nearest
  // vertex (margin plus kMotionFactor times the motion of both, plus an edge).
  std::vector<char> candidate(from.faces.rows(), 0);
  VecX nearest_to = VecX::Constant(x_from.rows(), std::numeric_limits<double>::infinity());
  for (int v = 0; v < int(x_from.rows()); ++v) {
    const Vec3 x = x_from.row(v).transpose();
    const double r = reach(m_from[v]) + slack;
    const geometry::Aabb box = geometry::Aabb(x, x).inflated(r);
    if (!near_to.intersects(box) || !coarse.occupied(box)) continue;
    const int w = grid.nearest(x, r, &nearest_to[v]);
    if (w < 0 || nearest_to[v] > options_.margin + kMotionFactor * (m_from[v] + m_to[to_index[w]]) + slack) continue;
    for (int f : from.vertex_faces[v]) candidate[f] = 1;
  }

  // Each candidate face's samples against the closest point of the other skin.
  std::vector<SkinFaceSample> samples;
  std::vector<int> faces_near;
  for (int f = 0; f < int(from.faces.rows()); ++f) {
    if (!candidate[f]) continue;
    // A sample lies within an edge of its face's vertices, so its nearest
    // vertex of the other skin is within that of theirs.
    double m_sample = 0, nearest = std::numeric_limits<double>::infinity();
    for (int c = 0; c < 3; ++c) {
      m_sample = std::max(m_sample, m_from[from.faces(f, c)]);
      nearest = std::min(nearest, nearest_to[from.faces(f, c)]);
    }
    samples.clear();
    append_face_samples(from.rest, from.faces, f, options_.spacing, samples);
    for (const SkinFaceSample& s : samples) {
      const Vec3 x = face_point(x_from, from.faces, f, s.lambda);
      // The nearest vertex of the other skin, and the faces around it and its
      // neighbours: the closest point of a smooth skin lies on one of them.
      const int w_near = grid.nearest(x, nearest + from.max_edge);
      if (w_near < 0) continue;
      const int w = to_index[w_near];
      const SkinPoint closest = closest_skin_point(x, to, x_to, w, faces_near);
      if (closest.face < 0) continue;
      Pair p;
      p.other_face = closest.face;
      p.mu = closest.mu;
      p.normal = closest.normal;
      double m_other = 0;
      for (int c = 0; c < 3; ++c) m_other = std::max(m_other, m_to[to.faces(p.other_face, c)]);
      // Surfaces that face the same way (coplanar neighbours, a sample on the
      // far side) do not touch.
      const Vec3 face_n = face_normal(x_to, to.faces, p.other_face);
      const Vec3 offset = x - face_point(x_to, to.faces, p.other_face, p.mu);
      if (face_normal(x_from, from.faces, f).dot(face_n) > 0) continue;
      const double gap = p.normal.dot(offset);
      if (gap > options_.margin + kMotionFactor * (m_sample + m_other) || gap < -options_.max_depth) continue;
      p.side = side;
      p.face = f;
      p.lambda = s.lambda;
      p.area = s.area;
      out.push_back(p);
    }
  }
}

void SkinContactTerm::begin_step(const StepContext& ctx) const {
  auto& c = static_cast<PairCache&>(*ctx.cache);
  c.pairs.clear();
  for (int side = 0; side < 2; ++side) c.used[side].clear();
  require(ctx.bound.size() == 2u, name(), ": bound to ", ctx.bound.size(), " bodies, expected 2");
  Points x[2];
  VecX motion[2];
  for (int k = 0; k < 2; ++k) {
    const BoundBody& b = ctx.bound[k];
    x[k] = skins_[k].vertices.world(*b.q_prev);
    motion[k] = VecX::Zero(x[k].rows());
    if (b.q_prev2 && b.q_prev2->bones.size() == b.q_prev->bones.size())
      motion[k] = (x[k] - skins_[k].vertices.world(*b.q_prev2)).rowwise().norm();
  }
  const double reach = options_.margin + kMotionFactor * (motion[0].maxCoeff() + motion[1].maxCoeff()) +
                       std::max(skins_[0].max_edge, skins_[1].max_edge);
  if (!geometry::Aabb::of_points(x[0]).inflated(reach).intersects(geometry::Aabb::of_points(x[1]))) return;
  collect_pairs(0, skins_[0], x[0], motion[0], skins_[1], x[1], motion[1], c.pairs);
  collect_pairs(1, skins_[1], x[1], motion[1], skins_[0], x[0], motion[0], c.pairs);
  for (int side = 0; side < 2; ++side) c.slot[side].assign(skins_[side].vertices.size(), -1);
  auto use = [&](int side, int vertex) {
    if (c.slot[side][vertex] >= 0) return;
    c.slot[side][vertex] = int(c.used[side].size());
    c.used[side].push_back(vertex);
  };
  for (const Pair& p : c.pairs)
    for (int i = 0; i < 3; ++i) {
      use(p.side, skins_[p.side].faces(p.face, i));
      use(1 - p.side, skins_[1 - p.side].faces(p.other_face, i));
    }
}

bool SkinContactTerm::active(const StepContext& ctx) const {
  return !static_cast<PairCache&>(*ctx.cache).pairs.empty();
}

double SkinContactTerm::compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const {
  auto& c = static_cast<PairCache&>(*ctx.cache);
  const Configuration* qs[2] = {&q, ctx.bound[1].q};
  const std::array<Points, 2> x = posed_vertices(c, qs);
  const DofLayout* layouts[2] = {&ctx.bound[0].layout, &ctx.bound[1].layout};
  const double half_kappa = 0.5 * options_.pressure_stiffness;
  const int n_local = layouts[1]->end();
  const bool derivatives = grad || hess;
  if (derivatives && c.row.size() != n_local) {
    c.row = VecX::Zero(n_local);
    c.mark.assign(n_local, 0);
  }
  Eigen::Matrix<double, 3, Eigen::Dynamic> J;
  std::vector<int> cols;
  double E = 0;
  for (const Pair& p : c.pairs) {
    const int from = p.side;
    const double g = gap(p, c, x);
    if (!(g < 0)) continue;
    const double k = half_kappa * p.area;
    E += 0.5 * k * g * g;
    if (!derivatives) continue;
    // row = nᵀ (∂x/∂δ − ∂y/∂δ), over the DoFs the six vertices touch.
    c.touched.clear();
    for (int side = 0; side < 2; ++side) {
      const Skin& s = skins_[side];
      const int face = side == from ? p.face : p.other_face;
      const Vec3& bary = side == from ? p.lambda : p.mu;
      const double sign = side == from ? 1.0 : -1.0;
      for (int i = 0; i < 3; ++i) {
        if (bary[i] == 0) continue;
        s.vertices.local_jacobian(s.faces(face, i), *qs[side], *layouts[side], J, cols);
        for (int col = 0; col < int(cols.size()); ++col) {
          const int d = cols[col];
          if (!c.mark[d]) {
            c.mark[d] = 1;
            c.touched.push_back(d);
          }
          c.row[d] += sign * bary[i] * p.normal.dot(J.col(col));
        }
      }
    }
    for (int a : c.touched) {
      if (grad) (*grad)[a] += k * g * c.row[a];
      if (hess)
        for (int b : c.touched) (*hess)(a, b) += k * c.row[a] * c.row[b];
    }
    for (int a : c.touched) {
      c.row[a] = 0;
      c.mark[a] = 0;
    }
  }
  return E;
}

std::vector<TermQuantity> SkinContactTerm::report(const StepContext& ctx, const Configuration& q) const {
  const auto& c = static_cast<PairCache&>(*ctx.cache);
  const Configuration* qs[2] = {&q, ctx.bound[1].q};
  const std::array<Points, 2> x = posed_vertices(c, qs);
  const double half_kappa = 0.5 * options_.pressure_stiffness;
  Vec3 force = Vec3::Zero();
  int active = 0;
  double worst_plane = 0, area = 0, weight = 0;
  Vec3 point = Vec3::Zero();
  std::vector<std::pair<int, Vec3>> touching;  // (side, sample point) of the pairs with g < 0
  for (const Pair& p : c.pairs) {
    const int from = p.side;
    const double g = gap(p, c, x);
    if (!(g < 0)) continue;
    // On the sample's body: −κ/2 a g n; a is that body on side 0, the other one on side 1.
    const Vec3 on_sample = -half_kappa * p.area * g * p.normal;
    force += from == 0 ? on_sample : Vec3(-on_sample);
    ++active;
    worst_plane = std::max(worst_plane, -g);
    area += 0.5 * p.area;
    Vec3 sample = Vec3::Zero();
    for (int i = 0; i < 3; ++i) sample += p.lambda[i] * x[from].row(c.slot[from][skins_[from].faces(p.face, i)]).transpose();
    point += on_sample.norm() * sample;
    weight += on_sample.norm();
    touching.emplace_back(from, sample);
  }
  // The penetration: each touching sample's depth behind the other skin at q,
  // its closest point found afresh. The penalty's gap is measured to the
  // plane of the closest point at time t (header comment), which a sample
  // that slides over a curved part within the step (a swinging foot) can be
  // far behind while it is outside the skin: that gap is reported apart.
  double worst = 0;
  std::array<Points, 2> skin_at_q;
  std::array<std::unique_ptr<geometry::PointGrid>, 2> grid;
  std::vector<int> scratch;
  for (const auto& [from, sample] : touching) {
    const int to = 1 - from;
    if (!grid[to]) {
      skin_at_q[to] = skins_[to].vertices.world(*qs[to]);
      grid[to] = std::make_unique<geometry::PointGrid>(skin_at_q[to], 0.02);
    }
    const int w = grid[to]->nearest(sample, options_.max_depth + skins_[to].max_edge);
    if (w < 0) continue;  // no skin within reach: not behind it
    const SkinPoint y = closest_skin_point(sample, skins_[to], skin_at_q[to], w, scratch);
    if (y.face >= 0) worst = std::max(worst, -y.normal.dot(sample - face_point(skin_at_q[to], skins_[to].faces, y.face, y.mu)));
  }
  std::vector<TermQuantity> out = {{"force", "N", force},
                                   {"active_samples", "", VecX::Constant(1, active)},
                                   {"max_penetration", "m", VecX::Constant(1, worst)},
                                   {"contact_area", "m^2", VecX::Constant(1, area)},
                                   {"max_plane_gap", "m", VecX::Constant(1, worst_plane)}};
  // Where the pressure acts: the samples' mean, weighted by their force (only while in contact).
  if (weight > 0) out.push_back({"contact_point", "m", point / weight});
  return out;
}

}  // namespace sflsh
