#include "sflsh/sim/state_file.hpp"

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "sflsh/core/error.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/io/crash_isolation.hpp"

namespace sflsh {
namespace {

MatXr pack_bones(const std::vector<Isometry>& bones) {
  MatXr m(bones.size(), 12);
  for (size_t i = 0; i < bones.size(); ++i) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m(i, 3 * r + c) = bones[i].linear()(r, c);
    for (int c = 0; c < 3; ++c) m(i, 9 + c) = bones[i].translation()(c);
  }
  return m;
}

std::vector<Isometry> unpack_bones(const MatXr& m) {
  std::vector<Isometry> bones(m.rows(), Isometry::Identity());
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) bones[i].linear()(r, c) = m(i, 3 * r + c);
    for (int c = 0; c < 3; ++c) bones[i].translation()(c) = m(i, 9 + c);
  }
  return bones;
}

}  // namespace

void write_state(const std::string& path, const Model& model, const State& state,
                 const std::function<void(io::Hdf5File&)>& more) {
  validate_state(model, state);
  io::Hdf5File f(path, io::Hdf5File::Mode::Write);
  f.write_scalar("/meta/format_version", std::int64_t(kStateFormatVersion));
  f.write_string("/meta/kind", "sflsh state");
  f.write_scalar("/state/time", state.time);
  std::vector<std::string> names;
  for (const Model::Body& b : model.bodies()) names.push_back(b.name);
  f.write_strings("/state/bodies", names);
  for (size_t b = 0; b < state.bodies.size(); ++b) {
    const std::string g = "/state/" + std::to_string(b) + "/";
    const BodyState& s = state.bodies[b];
    f.write_matrix(g + "bones", pack_bones(s.q.bones));
    f.write_matrix(g + "bones_prev", pack_bones(s.q_prev.bones));
    f.write_nd(g + "z", s.q.z.data(), {s.q.z.size()});
    f.write_nd(g + "z_prev", s.q_prev.z.data(), {s.q_prev.z.size()});
  }
  std::vector<std::string> term_names;
  const std::vector<std::unique_ptr<TermCache>> caches = state.carried_caches(&term_names);
  std::vector<int> saved;
  for (size_t j = 0; j < caches.size(); ++j) {
    if (!caches[j]) continue;
    const std::vector<double> values = caches[j]->saved_state();
    if (values.empty()) continue;
    const std::string g = "/state/caches/" + std::to_string(j) + "/";
    f.write_string(g + "name", term_names[j]);
    f.write_nd(g + "values", values.data(), {std::int64_t(values.size())});
    saved.push_back(int(j));
  }
  if (!saved.empty()) f.write_nd("/state/caches/terms", saved.data(), {std::int64_t(saved.size())});
  if (more) more(f);
  f.commit();
}

static State read_state_in_this_process(const std::string& path, const Model& model,
                                        const std::function<void(const io::Hdf5File&)>& more) {
  io::Hdf5File f(path, io::Hdf5File::Mode::Read);
  require(f.has("/meta/kind") && f.read_string("/meta/kind") == "sflsh state", path,
          ": not an sflsh state file (/meta/kind is missing or not \"sflsh state\")");
  const double version = f.read_scalar("/meta/format_version");
  require(version == 1 || version == 2 || version == kStateFormatVersion, path, ": /meta/format_version is ",
          version, ", expected 1 to ", kStateFormatVersion);
  const std::vector<std::string> names = f.read_strings("/state/bodies");
  require(names.size() == model.bodies().size(), path, ": /state/bodies has ", names.size(),
          " bodies, the scene has ", model.bodies().size());
  State s;
  s.time = f.read_scalar("/state/time");
  require(std::isfinite(s.time), path, ": /state/time is not finite");
  for (size_t b = 0; b < names.size(); ++b) {
    const Model::Body& body = model.bodies()[b];
    require(names[b] == body.name, path, ": /state/bodies[", b, "] is '", names[b], "', the scene's body ", b,
            " is '", body.name, "'");
    const std::string g = "/state/" + std::to_string(b) + "/";
    const std::int64_t r = body.layout.num_reduced;
    BodyState st;
    st.q.bones = unpack_bones(f.read_matrix(g + "bones", body.num_bones(), 12));
    st.q_prev.bones = unpack_bones(f.read_matrix(g + "bones_prev", body.num_bones(), 12));
    const std::vector<double> z = f.read_nd(g + "z", {r}), zp = f.read_nd(g + "z_prev", {r});
    st.q.z = Eigen::Map<const VecX>(z.data(), r);
    st.q_prev.z = Eigen::Map<const VecX>(zp.data(), r);
    s.bodies.push_back(std::move(st));
  }
  try {
    validate_state(model, s);
  } catch (const Error& e) {
    fail(path, ": ", e.what());
  }
  if (more) more(f);
  if (!f.has("/state/caches/terms")) return s;
  require(version == kStateFormatVersion, path, ": /meta/format_version is ", version,
          ": its term caches (the contact patch's history) are in an older layout; write the checkpoint again "
          "with this sflsh (sflsh simulate ... --checkpoint)");
  const auto terms = f.read_int_matrix("/state/caches/terms", -1, 1);
  for (Eigen::Index k = 0; k < terms.rows(); ++k) {
    const int j = terms(k, 0);
    require(j >= 0 && j < int(model.terms().size()), path, ": /state/caches/terms[", k, "] is ", j,
            ", the scene has ", model.terms().size(), " terms");
    const std::string g = "/state/caches/" + std::to_string(j) + "/";
    const EnergyTerm& term = *model.terms()[size_t(j)].term;
    const std::string name = f.read_string(g + "name");
    require(name == term.name(), path, ": ", g, "name is '", name, "', the scene's term ", j, " is '", term.name(), "'");
    std::unique_ptr<TermCache> cache = term.make_cache();
    require(cache != nullptr, path, ": ", g, " holds a state for term '", name, "', which keeps none");
    cache->restore_state(f.read_nd(g + "values", {-1}), path + ": " + g + "values");
    s.carry_cache(model, j, std::move(cache));
  }
  return s;
}

State read_state(const std::string& path, const Model& model, const std::function<void(const io::Hdf5File&)>& more) {
  // A file on which libhdf5 itself crashes is refused, not read (io/crash_isolation.hpp).
  return io::read_in_child_first(path, [&] { return read_state_in_this_process(path, model, more); });
}

}  // namespace sflsh
