#include "sflsh/sim/model.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <set>
#include <sstream>

#include "sflsh/core/error.hpp"

namespace sflsh {

int Model::body_index(const std::string& name) const {
  std::string known;
  for (size_t i = 0; i < bodies_.size(); ++i) {
    if (bodies_[i].name == name) return int(i);
    known += (i ? ", " : "") + bodies_[i].name;
  }
  fail("unknown body '", name, "'; the model has: ", known);
}

namespace {

/// Index of `name` in `names`, or −1.
int index_of(const std::vector<std::string>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : int(it - names.begin());
}

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (size_t i = 0; i < names.size(); ++i) s += (i ? ", " : "") + names[i];
  return s.empty() ? "none" : s;
}

}  // namespace

FrameId Model::find_frame(const std::string& name) const { return FrameId{index_of(frame_names_, name)}; }

FrameId Model::frame_id(const std::string& name) const {
  const FrameId id = find_frame(name);
  require(id.valid(), "unknown world frame '", name, "'; the model has: ", joined(frame_names_));
  return id;
}

AnchorSetId Model::anchor_set_id(const std::string& name) const {
  const AnchorSetId id{index_of(anchor_set_names_, name)};
  require(id.valid(), "unknown anchor set '", name, "'; the model has: ", joined(anchor_set_names_));
  return id;
}

std::string Model::describe() const {
  std::ostringstream o;
  o << num_dofs_ << " DoFs in " << blocks_.size() << " blocks\n";
  for (const Body& b : bodies_)
    o << "  body " << b.name << ": " << (b.rigid() ? "rigid object" : b.bones_dynamic ? "bones dynamic" : "bones kinematic")
      << ", DoFs ["
      << b.layout.base << ", " << b.layout.end() << ")\n";
  for (size_t g = 0; g < groups_.size(); ++g) {
    o << "  group " << g << ": DoFs [" << groups_[g].offset << ", " << groups_[g].offset + groups_[g].size
      << "), bodies";
    for (int b : groups_[g].bodies) o << " " << bodies_[b].name;
    o << "\n";
  }
  for (const BoundTerm& t : terms_) {
    o << "  term " << t.term->name() << " on";
    for (int b : t.bodies) o << " " << bodies_[b].name;
    const TermPlacement& p = t.placement;
    o << ": " << p.local_size << " DoFs";
    for (const auto& [off, n] : p.ranges) o << " [" << off << ", " << off + n << ")";
    o << (p.contiguous ? " (in place)" : " (scattered)") << "\n";
  }
  return o.str();
}

int ModelBuilder::add_body(BodySpec spec) {
  if (!spec.avatar) spec.bones_dynamic = true;  // a rigid object (model.hpp)
  for (const BodySpec& s : specs_)
    require(s.name != spec.name, "ModelBuilder::add_body: two bodies are called '", spec.name, "'");
  specs_.push_back(std::move(spec));
  return int(specs_.size()) - 1;
}

const Avatar& ModelBuilder::avatar(int body) const {
  require(body >= 0 && body < int(specs_.size()), "ModelBuilder: body ", body, " does not exist (", specs_.size(),
          " bodies)");
  require(specs_[body].avatar != nullptr, "ModelBuilder: body '", specs_[body].name, "' is a rigid object, not an avatar");
  return *specs_[body].avatar;
}

int ModelBuilder::add_term(std::shared_ptr<const EnergyTerm> term, std::vector<int> bodies) {
  require(term != nullptr, "ModelBuilder::add_term: null term");
  require(!bodies.empty(), "ModelBuilder::add_term: term '", term->name(), "' is bound to no body");
  std::set<int> seen;
  for (int b : bodies) {
    require(b >= 0 && b < int(specs_.size()), "ModelBuilder::add_term: term '", term->name(), "' names body ", b,
            ", but the model has ", specs_.size(), " bodies");
    require(seen.insert(b).second, "ModelBuilder::add_term: term '", term->name(), "' names body ", b, " twice");
  }
  std::vector<FrameId> frames;
  for (const std::string& f : term->input_frames()) frames.push_back(add_frame(f));
  const std::string anchors = term->input_anchor_set();
  term_anchor_sets_.push_back(anchors.empty() ? AnchorSetId{} : add_anchor_set(anchors));
  term_frames_.push_back(std::move(frames));
  terms_.emplace_back(std::move(term), std::move(bodies));
  return int(terms_.size()) - 1;
}

FrameId ModelBuilder::add_frame(const std::string& name) {
  int i = index_of(frame_names_, name);
  if (i < 0) {
    i = int(frame_names_.size());
    frame_names_.push_back(name);
  }
  return FrameId{i};
}

AnchorSetId ModelBuilder::add_anchor_set(const std::string& name) {
  int i = index_of(anchor_set_names_, name);
  if (i < 0) {
    i = int(anchor_set_names_.size());
    anchor_set_names_.push_back(name);
  }
  return AnchorSetId{i};
}

std::shared_ptr<const Model> ModelBuilder::build() const {
  const ModelOptions& o = options_;
  require(o.h > 0 && std::isfinite(o.h), "model: time step h = ", o.h, " s, expected a positive number");
  require(o.gravity.allFinite(), "model: gravity is not finite");
  require(o.newton.iterations >= 1, "model: Newton iterations = ", o.newton.iterations, ", expected >= 1");
  auto m = std::make_shared<Model>();
  m->options_ = o;
  m->frame_names_ = frame_names_;
  m->anchor_set_names_ = anchor_set_names_;
  const int B = int(specs_.size());

  // Groups: connected components of bodies linked by terms (union–find).
  std::vector<int> parent(B);
  for (int b = 0; b < B; ++b) parent[b] = b;
  std::function<int(int)> root = [&](int b) { return parent[b] == b ? b : parent[b] = root(parent[b]); };
  for (const auto& [term, bodies] : terms_)
    for (size_t k = 1; k < bodies.size(); ++k) parent[root(bodies[k])] = root(bodies[0]);
  std::vector<int> group_of(B, -1);
  for (int b = 0; b < B; ++b) {
    const int r = root(b);
    if (group_of[r] < 0) {
      group_of[r] = int(m->groups_.size());
      m->groups_.emplace_back();
    }
    group_of[b] = group_of[r];
    m->groups_[group_of[b]].bodies.push_back(b);
  }

  // Global layout, group by group (each group one interval).
  m->bodies_.resize(B);
  int offset = 0;
  for (Model::Group& g : m->groups_) {
    g.offset = offset;
    for (int b : g.bodies) {
      const BodySpec& s = specs_[b];
      Model::Body& body = m->bodies_[b];
      body.name = s.name;
      body.avatar = s.avatar;
      body.bones_dynamic = s.bones_dynamic;
      DofLayout& l = body.layout;
      l.num_bones = s.avatar ? 24 : 1;
      l.bones_dynamic = s.bones_dynamic;
      l.num_reduced = s.avatar ? s.avatar->num_reduced() : 0;
      l.base = offset;
      // Each bone turns about its own joint: the Newton step's linearization then
      // keeps the stiff joint constraints closed on fast distal motion. A rigid
      // object turns about its centre of mass, its frame's origin.
      if (!s.avatar) {
        l.bone_pivots = Points::Zero(1, 3);
      } else if (s.avatar->joints_rest.rows() == 24) {
        l.bone_pivots = s.avatar->joints_rest;
      }
      if (l.bones_dynamic)
        for (int i = 0; i < l.num_bones; ++i) m->blocks_.push_back({DofBlock::Kind::Bone, b, i, l.bone_offset(i), 6});
      if (l.num_reduced > 0) m->blocks_.push_back({DofBlock::Kind::Soft, b, -1, l.z_offset(), l.num_reduced});
      offset = l.end();
      DofLayout rebased = l;
      rebased.base -= g.offset;
      g.layouts.push_back(std::move(rebased));
    }
    g.size = offset - g.offset;
  }
  m->num_dofs_ = offset;

  for (size_t ti = 0; ti < terms_.size(); ++ti) {
    const auto& [term, bodies] = terms_[ti];
    Model::BoundTerm t;
    t.term = term;
    t.bodies = bodies;
    t.frames = term_frames_[ti];
    t.anchor_set = term_anchor_sets_[ti];
    const BodyBlocks use = term->blocks();
    std::vector<std::pair<int, int>> ranges;
    int local = 0;
    for (int b : bodies) {
      const DofLayout& global = m->bodies_[b].layout;
      DofLayout l = global;
      l.base = local;
      int global_start = global.base;
      if (use == BodyBlocks::Bones) {
        l.num_reduced = 0;
      } else if (use == BodyBlocks::Soft) {
        l.bones_dynamic = false;
        l.bone_pivots.resize(0, 3);
        global_start = global.z_offset();
      }
      if (l.size() > 0) ranges.emplace_back(global_start, l.size());
      local += l.size();
      t.local_layouts.push_back(std::move(l));
    }
    t.placement = TermPlacement::from_ranges(ranges);
    Model::Group& g = m->groups_[group_of[bodies[0]]];
    for (auto& r : ranges) r.first -= g.offset;
    g.terms.push_back(int(m->terms_.size()));
    g.placements.push_back(TermPlacement::from_ranges(std::move(ranges)));
    std::vector<int> slots;
    for (int b : bodies) slots.push_back(int(std::find(g.bodies.begin(), g.bodies.end(), b) - g.bodies.begin()));
    g.slots.push_back(std::move(slots));
    m->terms_.push_back(std::move(t));
  }
  return m;
}

}  // namespace sflsh
