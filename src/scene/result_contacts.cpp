#include "sflsh/scene/result_contacts.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "sflsh/core/error.hpp"

namespace sflsh {
namespace {

std::string contact_group(size_t c) { return "/contacts/" + std::to_string(c); }

}  // namespace

void create_contact_datasets(io::Hdf5File& f, const std::vector<ContactTrack>& contacts) {
  for (size_t c = 0; c < contacts.size(); ++c) {
    const std::string g = contact_group(c);
    f.write_string(g + "/term", contacts[c].term);
    f.write_string(g + "/body", contacts[c].body);
    f.create_appendable(g + "/force", {3});
    f.create_appendable(g + "/point", {3});
    f.create_appendable(g + "/max_penetration", {});
    f.create_appendable(g + "/active_samples", {});
  }
}

void append_contact_frames(io::Hdf5File& f, const std::vector<ContactTrack>& contacts,
                           const std::vector<ContactFrame>& frames, const std::string& at) {
  require(frames.size() == contacts.size(), at, ": ", frames.size(), " contact frames for ", contacts.size(),
          " contacts");
  for (size_t c = 0; c < contacts.size(); ++c) {
    const ContactFrame& cf = frames[c];
    require(cf.force.allFinite() && cf.point.allFinite() && std::isfinite(cf.max_penetration), at, ": contact '",
            contacts[c].term, "' on '", contacts[c].body, "' holds a non-finite value; not written");
    require(cf.active >= 0, at, ": contact '", contacts[c].term, "' has ", cf.active, " active samples");
    const std::string g = contact_group(c);
    const double depth = cf.max_penetration, active = cf.active;
    f.append(g + "/force", cf.force.data());
    f.append(g + "/point", cf.point.data());
    f.append(g + "/max_penetration", &depth);
    f.append(g + "/active_samples", &active);
  }
}

std::vector<ContactTrack> read_contacts(const io::Hdf5File& f, std::int64_t F) {
  std::vector<ContactTrack> out;
  for (size_t c = 0; f.has(contact_group(c)); ++c) {
    const std::string g = contact_group(c);
    ContactTrack t;
    t.term = f.read_string(g + "/term");
    t.body = f.read_string(g + "/body");
    const MatXr force = f.read_matrix(g + "/force", F, 3);
    const MatXr point = f.read_matrix(g + "/point", F, 3);
    const MatXr depth = f.read_matrix(g + "/max_penetration", F, 1);
    const MatXr active = f.read_matrix(g + "/active_samples", F, 1);
    for (std::int64_t i = 0; i < F; ++i) {
      require(depth(i, 0) >= 0, f.path(), ": dataset ", g, "/max_penetration[", i, "] is ", depth(i, 0),
              ", expected >= 0");
      require(active(i, 0) >= 0 && active(i, 0) == std::floor(active(i, 0)) && active(i, 0) < 2e9, f.path(),
              ": dataset ", g, "/active_samples[", i, "] is ", active(i, 0), ", expected a whole number >= 0");
      ContactFrame cf;
      cf.force = force.row(i).transpose();
      cf.point = point.row(i).transpose();
      cf.max_penetration = depth(i, 0);
      cf.active = int(active(i, 0));
      t.frames.push_back(cf);
    }
    out.push_back(std::move(t));
  }
  // A group past a gap (/contacts/0, /contacts/2) is a damaged file, not fewer contacts.
  if (f.has("/contacts"))
    require(!f.has(contact_group(out.size() + 1)), f.path(), ": group ", contact_group(out.size() + 1),
            " follows a missing ", contact_group(out.size()));
  return out;
}

double peak_contact_force(const ContactTrack& t, int* frame) {
  double peak = 0;
  int at = t.frames.empty() ? -1 : 0;
  for (size_t i = 0; i < t.frames.size(); ++i)
    if (const double n = t.frames[i].force.norm(); n > peak) {
      peak = n;
      at = int(i);
    }
  if (frame) *frame = at;
  return peak;
}

std::string describe_contacts(const SimulationResult& r) {
  std::ostringstream o;
  for (const ContactTrack& t : r.contacts) {
    int at = -1;
    const double peak = peak_contact_force(t, &at);
    double depth = 0;
    int active = 0;
    for (const ContactFrame& cf : t.frames) {
      depth = std::max(depth, cf.max_penetration);
      active = std::max(active, cf.active);
    }
    char line[512];
    std::snprintf(line, sizeof line,
                  "contact %s on %s: peak force %.2f N at t = %.3f s, max penetration %.2f mm, up to %d active "
                  "samples\n",
                  t.term.c_str(), t.body.c_str(), peak,
                  at >= 0 && size_t(at) < r.frame_time.size() ? r.frame_time[size_t(at)] : 0.0, depth * 1e3, active);
    o << line;
  }
  return o.str();
}

}  // namespace sflsh
