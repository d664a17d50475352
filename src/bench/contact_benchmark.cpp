#include "sflsh/bench/contact_benchmark.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>

#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/percentile.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/geometry/primitive_sdfs.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/io/line_plot_svg.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "sflsh/reference/full_fem.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sflsh/sim/soft_tissue_terms.hpp"
#include "bench/step_median.hpp"

namespace sflsh {
namespace {

const char* const kObject = "ball";

/// The belly contact point and the skin vertices near it.
struct Site {
  Vec3 point = Vec3::Zero();          ///< unposed = world (rest pose), m
  Vec3 outward = Vec3::UnitZ();       ///< the body faces +z
};

/// A kinematic sphere moving along the site's normal: gap(t) is the signed
/// distance (m) of its surface from the site's point along the outward normal.
struct Scene {
  std::string name;
  double radius = 0, dt = 0;
  int steps = 0;
  std::function<double(double)> gap;
  std::string site = "belly";  ///< belly | thigh (left, front) | calf (left, back)
  Vec3 centre(const Site& s, double t) const { return s.point + s.outward * (radius + gap(t)); }
};

/// One run: the skin's soft displacement and what the step reported, per step.
struct Trace {
  std::vector<Points> u;            // #V by 3 per step (m)
  std::vector<double> ms;           // step time
  std::vector<bool> contact;        // some sample penetrates at the end of the step
  double contact_ms = 0;            // time in the contact term (reduced) or contact evaluation (full)
  double sample_iterations = 0;     // Σ active samples × Newton iterations over contact steps
  int max_active = 0;
  double peak_force = 0;            // N
  std::vector<double> force;        // |contact force| per step (N)
  int unconverged = 0;              // full FEM: steps that stopped before the gradient tolerance
  int max_patch_nodes = 0;          // reduced: largest patch
};

bool simulated_vertex(const Avatar& a, int v) {
  if (a.node_role.size() == 0) return true;
  for (int c = 0; c < 4; ++c)
    if (a.node_role[a.tet.elements(a.surface_tet[v], c)] == int(NodeRole::Simulated)) return true;
  return false;
}

Site belly_site(const Avatar& a) {
  require(a.joints_rest.rows() == 24, "bench-contact: the avatar has ", a.joints_rest.rows(), " joints, expected 24");
  const double y0 = a.joints_rest(0, 1), y1 = a.joints_rest(6, 1);
  const Vec3 mid(0, 0.5 * (y0 + y1), 0);
  int best = -1;
  double best_z = 0, best_off = 0;
  for (int v = 0; v < int(a.surface_rest.rows()); ++v) {
    const Vec3 x = a.surface_rest.row(v).transpose();
    if (std::abs(x.x()) >= 0.05 || x.y() < std::min(y0, y1) || x.y() > std::max(y0, y1) || !simulated_vertex(a, v))
      continue;
    // Front-most; among vertices within 1 mm of that, the nearest to the mid line.
    const double off = std::hypot(x.x(), x.y() - mid.y());
    if (best < 0 || x.z() > best_z + 1e-3 || (x.z() > best_z - 1e-3 && off < best_off)) {
      best = v;
      best_z = x.z();
      best_off = off;
    }
  }
  require(best >= 0, "bench-contact: no simulated skin vertex with |x| < 5 cm between the pelvis and spine2 heights");
  Site s;
  s.point = a.surface_rest.row(best).transpose();
  return s;
}

/// The front-most (front) or back-most skin vertex of a limb segment from
/// joint `lo` to joint `hi`, between the fractions s0 and s1 of its height and
/// within `reach` (m, in x) of its axis, whose tet has a Simulated node.
Site limb_site(const Avatar& a, int lo, int hi, double s0, double s1, double reach, bool front, const char* what) {
  require(a.joints_rest.rows() == 24, "bench-contact: the avatar has ", a.joints_rest.rows(), " joints, expected 24");
  const Vec3 p0 = a.joints_rest.row(lo).transpose(), p1 = a.joints_rest.row(hi).transpose();
  int best = -1;
  double best_z = 0;
  for (int v = 0; v < int(a.surface_rest.rows()); ++v) {
    const Vec3 x = a.surface_rest.row(v).transpose();
    const double s = (x.y() - p0.y()) / (p1.y() - p0.y());
    if (s < s0 || s > s1 || std::abs(x.x() - (p0.x() + s * (p1.x() - p0.x()))) > reach || !simulated_vertex(a, v))
      continue;
    const double z = front ? x.z() : -x.z();  // the body faces +z
    if (best < 0 || z > best_z) best = v, best_z = z;
  }
  require(best >= 0, "bench-contact: no simulated skin vertex on ", what);
  Site site;
  site.point = a.surface_rest.row(best).transpose();
  site.outward = front ? Vec3::UnitZ() : Vec3(-Vec3::UnitZ());
  return site;
}

Site thigh_site(const Avatar& a) { return limb_site(a, 4, 1, 0.4, 0.6, 0.04, true, "the front of the left thigh"); }
Site calf_site(const Avatar& a) { return limb_site(a, 7, 4, 0.5, 0.7, 0.03, false, "the back of the left calf"); }

std::vector<Scene> make_scenes(const ContactBenchSettings& o) {
  require(o.pressed_radius > 0 && o.impact_radius > 0 && o.impact_speed > 0 && o.pressed_depth > 0 &&
              o.impact_depth > 0 && o.pressed_dt > 0 && o.impact_dt > 0 && o.newton_iters >= 1,
          "bench-contact: radii, depths, speed, time steps and Newton iterations must be positive");
  check_contact_sampling(o.pressure_stiffness, o.spacing, "bench-contact");
  std::vector<Scene> scenes;
  {
    const double ramp = o.quick ? 0.25 : 0.5, total = o.quick ? 0.35 : 1.0, start = 0.01, depth = o.pressed_depth;
    Scene s{"pressed", o.pressed_radius, o.pressed_dt, int(std::lround(total / o.pressed_dt)), nullptr};
    s.gap = [=](double t) { return start - (start + depth) * std::min(std::max(t, 0.0) / ramp, 1.0); };
    scenes.push_back(s);
  }
  {
    const double start = 0.02, depth = o.impact_depth, v = o.impact_speed, turn = (start + depth) / v;
    const double total = o.quick ? 0.1 : 0.3;
    Scene s{"impact", o.impact_radius, o.impact_dt, int(std::lround(total / o.impact_dt)), nullptr};
    s.gap = [=](double t) { return t < turn ? start - v * t : -depth + v * (t - turn); };
    scenes.push_back(s);
  }
  require(o.probe_radius > 0 && o.probe_depth > 0 && o.probe_dt > 0, "bench-contact: probe radius, depth and dt must be positive");
  // "probe": the 2 cm probe on the thigh; "probe-SITE[-1cm]": the probe (or a
  // 1 cm one) on the belly, thigh or calf.
  for (const char* site : {"thigh", "belly", "calf"})
    for (bool small : {false, true}) {
      const double start = 0.002, depth = o.probe_depth, ramp = o.quick ? 0.5 : 1.5, total = ramp + (o.quick ? 0.1 : 0.25);
      const std::string name = std::string(site) == "thigh" && !small ? "probe"
                                                                       : std::string("probe-") + site + (small ? "-1cm" : "");
      Scene s{name, small ? 0.01 : o.probe_radius, o.probe_dt, int(std::lround(total / o.probe_dt)), nullptr, site};
      s.gap = [=](double t) { return start - (start + depth) * std::min(std::max(t, 0.0) / ramp, 1.0); };
      scenes.push_back(s);
    }
  return scenes;
}

Isometry translation(const Vec3& c) {
  Isometry T = Isometry::Identity();
  T.translation() = c;
  return T;
}

Trace run_full(std::shared_ptr<const Avatar> avatar, const Scene& sc, const Site& site, const ContactBenchSettings& o) {
  FullFemOptions fo;
  fo.h = sc.dt;
  fo.gravity = Vec3::Zero();
  fo.gradient_tolerance = 1e-6;  // as `sflsh bench`'s reference: far below the errors reported
  FullFem fem(avatar, fo);
  // The same contact as the reduced solver's: the skin's faces, pressure stiffness κ.
  FullFemObstacle ob;
  ob.name = kObject;
  ob.field = std::make_shared<geometry::SphereSdf>(sc.radius);
  ob.pressure_stiffness = o.pressure_stiffness;
  ob.spacing = o.spacing;
  fem.add_obstacle(ob);
  Trace tr;
  Progress p("bench-contact: full FEM, " + sc.name, sc.steps);
  for (int i = 1; i <= sc.steps; ++i) {
    const double cpu0 = thread_cpu_ms();
    const FullFemReport rep = fem.step(identity_bones(), {translation(sc.centre(site, i * sc.dt))});
    const double cpu_ms = thread_cpu_ms() - cpu0;
    require(fem.displacement().allFinite(), "bench-contact: the full-FEM ", sc.name, " run became non-finite at step ", i);
    tr.u.push_back(fem.soft_displacement());
    tr.ms.push_back(o.cpu_time ? cpu_ms : rep.ms_total);
    const FullFemContact& c = rep.contacts.at(0);
    tr.contact.push_back(c.active_samples > 0);
    tr.contact_ms += rep.ms_contact;
    if (!rep.converged) ++tr.unconverged;
    tr.max_active = std::max(tr.max_active, c.active_samples);
    tr.peak_force = std::max(tr.peak_force, c.force.norm());
    tr.force.push_back(c.force.norm());
    p.update(i);
  }
  p.finish();
  if (tr.unconverged > 0)
    log_info("bench-contact: full FEM, " + sc.name + ": " + std::to_string(tr.unconverged) + " of " +
             std::to_string(sc.steps) + " steps stopped before the gradient tolerance");
  return tr;
}

Trace run_reduced(std::shared_ptr<const Avatar> avatar, const Scene& sc, const Site& site, const ContactBenchSettings& o,
                  bool with_object) {
  ModelOptions mo;
  mo.h = sc.dt;
  mo.gravity = Vec3::Zero();
  mo.newton.iterations = o.newton_iters;
  mo.newton.line_search = o.newton_iters > 1;
  mo.newton.nonlinearity_tolerance = o.nonlinearity_tolerance;
  mo.parallel_groups = false;
  ModelBuilder mb(mo);
  const int body = mb.add_body({"avatar", avatar, false});
  SoftTissueOptions so;
  so.mean_dilatation = o.mean_dilatation;
  add_soft_tissue_terms(mb, body, so);
  if (with_object) {
    ContactPatchOptions co;
    co.pressure_stiffness = o.pressure_stiffness;
    co.spacing = o.spacing;
    co.patch = o.patch;
    co.patch_radius = o.patch_radius;
    co.max_patch_nodes = o.max_patch_nodes;
    co.subspace_mean_dilatation = o.mean_dilatation;
    mb.add_term(std::make_shared<const ContactPatchTerm>(kObject, *avatar, std::make_shared<geometry::SphereSdf>(sc.radius),
                                                         Isometry::Identity(), false, co),
                {body});
  }
  Simulator sim(mb.build());
  const std::string term = std::string("contact:") + kObject;
  Trace tr;
  Progress p("bench-contact: reduced K=" + std::to_string(avatar->num_handles()) + ", " + sc.name +
                 (with_object ? "" : " without the ball"),
             sc.steps);
  StepInputs in;
  in.bodies.push_back({identity_bones(), {}});
  for (int i = 1; i <= sc.steps; ++i) {
    const double t = i * sc.dt;
    WorldFrame& f = in.frames[kObject];
    f.pose = translation(sc.centre(site, t));
    f.linear_velocity = (sc.centre(site, t) - sc.centre(site, t - sc.dt)) / sc.dt;
    const double cpu0 = thread_cpu_ms();
    const StepReport rep = sim.step(in);
    const double cpu_ms = thread_cpu_ms() - cpu0;
    require(sim.state().z.allFinite(), "bench-contact: the reduced ", sc.name, " run became non-finite at step ", i);
    tr.u.push_back(sim.soft_displacement() + patch_surface_displacement(*avatar, rep));
    tr.ms.push_back(o.cpu_time ? cpu_ms : rep.ms_total);
    int active = 0;
    double force = 0;
    for (const TermQuantityReport& q : rep.quantities)
      if (q.term == term && q.name == "active_samples") active = int(q.value.at(0));
      else if (q.term == term && q.name == "patch_nodes") tr.max_patch_nodes = std::max(tr.max_patch_nodes, int(q.value.at(0)));
      else if (q.term == term && q.name == "force") force = Vec3(q.value.at(0), q.value.at(1), q.value.at(2)).norm();
    tr.peak_force = std::max(tr.peak_force, force);
    tr.force.push_back(force);
    tr.contact.push_back(active > 0);
    tr.max_active = std::max(tr.max_active, active);
    if (active > 0) {
      for (const TermEnergy& e : rep.energies)
        if (e.name == term) tr.contact_ms += e.ms;
      tr.sample_iterations += double(active) * rep.iterations;
    }
    p.update(i);
  }
  p.finish();
  return tr;
}

/// Peak inward displacement (m) over the steps of the vertices within `reach` of the site.
double peak_dent(const Trace& tr, const Avatar& a, const Site& site, double reach) {
  double dent = 0;
  for (int v = 0; v < int(a.surface_rest.rows()); ++v) {
    if ((a.surface_rest.row(v).transpose() - site.point).norm() > reach) continue;
    for (const Points& u : tr.u) dent = std::max(dent, -u.row(v).dot(site.outward.transpose()));
  }
  return dent;
}

/// The force (N) where the depth curve first reaches `depth` (m), linearly
/// interpolated between steps; NaN when it never does.
double force_at_depth(const std::vector<double>& depth_mm, const std::vector<double>& force, double depth) {
  for (size_t i = 1; i < depth_mm.size() && i < force.size(); ++i)
    if (depth_mm[i] >= 1e3 * depth && depth_mm[i - 1] < 1e3 * depth) {
      const double w = (1e3 * depth - depth_mm[i - 1]) / (depth_mm[i] - depth_mm[i - 1]);
      return force[i - 1] + w * (force[i] - force[i - 1]);
    }
  return std::nan("");
}

/// RMS over the loading ramp's steps at 2–10 mm depth of (F_red − F_full) / F_full; NaN without such steps.
double loading_force_rms_error(const std::vector<double>& depth_mm, const std::vector<double>& full,
                               const std::vector<double>& reduced) {
  double sum = 0;
  int n = 0;
  for (size_t i = 0; i < depth_mm.size() && i < full.size() && i < reduced.size(); ++i) {
    if (i > 0 && depth_mm[i] <= depth_mm[i - 1]) break;  // the ramp ends
    if (depth_mm[i] < 2.0 || depth_mm[i] > 10.0 || !(full[i] > 0)) continue;
    sum += std::pow((reduced[i] - full[i]) / full[i], 2);
    ++n;
  }
  return n > 0 ? std::sqrt(sum / n) : std::nan("");
}

double relative_error(const Trace& tr, const Trace& ref) {
  double diff2 = 0, ref2 = 0;
  for (size_t f = 0; f < std::min(tr.u.size(), ref.u.size()); ++f) {
    diff2 += (tr.u[f] - ref.u[f]).squaredNorm();
    ref2 += ref.u[f].squaredNorm();
  }
  return ref2 > 0 ? std::sqrt(diff2 / ref2) : 0;
}

}  // namespace

std::vector<ContactBenchRow> run_contact_scenes(const std::vector<std::shared_ptr<const Avatar>>& avatars,
                                                const ContactBenchSettings& settings) {
  require(!avatars.empty(), "bench-contact: no avatars");
  const Avatar& base = *avatars[0];
  for (const auto& a : avatars)
    require(a->tet.num_nodes() == base.tet.num_nodes() && a->tet.num_elements() == base.tet.num_elements() &&
                a->surface_rest.rows() == base.surface_rest.rows(),
            "bench-contact: the avatars do not share the tet mesh and skin (", a->tet.num_nodes(), " vs ",
            base.tet.num_nodes(), " nodes)");
  const Site belly = belly_site(base), thigh = thigh_site(base), calf = calf_site(base);
  log_info("bench-contact: belly point (" + std::to_string(belly.point.x()) + ", " + std::to_string(belly.point.y()) +
           ", " + std::to_string(belly.point.z()) + ") m, thigh point (" + std::to_string(thigh.point.x()) + ", " +
           std::to_string(thigh.point.y()) + ", " + std::to_string(thigh.point.z()) + ") m");
  std::vector<ContactBenchRow> rows;
  for (const std::string& name : settings.scenes) {
    bool known = false;
    for (const Scene& sc : make_scenes(settings)) known = known || sc.name == name;
    require(known, "bench-contact: unknown scene '", name,
            "' (scenes: pressed, impact, probe, probe-thigh-1cm, probe-belly, probe-belly-1cm, probe-calf, probe-calf-1cm)");
  }
  for (const Scene& sc : make_scenes(settings)) {
    if (!settings.scenes.empty() &&
        std::find(settings.scenes.begin(), settings.scenes.end(), sc.name) == settings.scenes.end())
      continue;
    const Site& site = sc.site == "thigh" ? thigh : sc.site == "calf" ? calf : belly;
    const Trace ref = run_full(avatars[0], sc, site, settings);
    const double reach = 1.5 * sc.radius;
    const double dent_ref = peak_dent(ref, base, site, reach);
    for (const auto& a : avatars) {
      const Trace with = run_reduced(a, sc, site, settings, true);
      const Trace without = run_reduced(a, sc, site, settings, false);
      ContactBenchRow r;
      r.scene = sc.name;
      r.handles = a->num_handles();
      r.dt = sc.dt;
      r.steps = sc.steps;
      r.rel_err = relative_error(with, ref);
      r.dent_full_mm = 1e3 * dent_ref;
      r.dent_reduced_mm = 1e3 * peak_dent(with, *a, site, reach);
      r.dent_ratio = dent_ref > 0 ? r.dent_reduced_mm / r.dent_full_mm : 0;
      r.force_full_n = ref.peak_force;
      r.force_reduced_n = with.peak_force;
      r.active_samples = with.max_active;
      r.active_samples_full = ref.max_active;
      r.us_per_sample_iter = with.sample_iterations > 0 ? 1e3 * with.contact_ms / with.sample_iterations : 0;
      r.ms_contact = median_when(with.ms, with.contact);
      r.ms_no_contact = median_when(without.ms, with.contact);
      r.step_ratio = r.ms_no_contact > 0 ? r.ms_contact / r.ms_no_contact : 0;
      r.ms_full = median_when(ref.ms, ref.contact);
      for (int i = 1; i <= sc.steps; ++i) r.curve_depth_mm.push_back(-1e3 * sc.gap(i * sc.dt));
      r.curve_force_full_n = ref.force;
      r.curve_force_reduced_n = with.force;
      r.force_at_depth_full_n = force_at_depth(r.curve_depth_mm, ref.force, settings.probe_report_depth);
      r.force_at_depth_reduced_n = force_at_depth(r.curve_depth_mm, with.force, settings.probe_report_depth);
      r.force_err = std::abs(r.force_at_depth_reduced_n - r.force_at_depth_full_n) / r.force_at_depth_full_n;
      r.force_rms_err = loading_force_rms_error(r.curve_depth_mm, ref.force, with.force);
      r.max_patch_nodes = with.max_patch_nodes;
      rows.push_back(r);
    }
  }
  return rows;
}

std::vector<ContactBenchRow> run_contact_benchmark(const ContactBenchOptions& in) {
  std::vector<int> ks = in.handle_counts;
  if (ks.empty()) ks = in.settings.quick ? std::vector<int>{32} : std::vector<int>{32, 64, 128};
  const BodyModel model = load_body_model(in.model);
  const TemplateVolume tv = cached_template_volume(model, in.precompute);
  std::vector<std::shared_ptr<const Avatar>> avatars;
  for (int K : ks) {
    require(K >= 1, "bench-contact: handle count ", K, ", expected >= 1");
    PrecomputeOptions po = in.precompute;
    po.handles = K;
    log_info("bench-contact: shape stage with K = " + std::to_string(K) + " handles");
    avatars.push_back(std::make_shared<const Avatar>(precompute_shape(tv, model, in.betas, po)));
  }
  return run_contact_scenes(avatars, in.settings);
}

void write_contact_bench_csv(const std::vector<ContactBenchRow>& rows, const std::string& path) {
  io::write_text_file(path, [&](std::ostream& f) {
    f << "scene,handles,dt,steps,rel_err,dent_full_mm,dent_reduced_mm,dent_ratio,force_full_n,force_reduced_n,"
         "active_samples,active_samples_full,us_per_sample_iter,ms_contact,ms_no_contact,step_ratio,ms_full\n";
    char buf[512];
    for (const auto& r : rows) {
      std::snprintf(buf, sizeof buf, "%s,%d,%.6g,%d,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%d,%d,%.4g,%.4g,%.4g,%.4g,%.4g\n",
                    r.scene.c_str(), r.handles, r.dt, r.steps, r.rel_err, r.dent_full_mm, r.dent_reduced_mm,
                    r.dent_ratio, r.force_full_n, r.force_reduced_n, r.active_samples, r.active_samples_full,
                    r.us_per_sample_iter, r.ms_contact, r.ms_no_contact, r.step_ratio, r.ms_full);
      f << buf;
    }
  });
}

void write_probe_curves(const std::vector<ContactBenchRow>& rows, const std::string& csv_path,
                        const std::string& svg_path, double report_depth) {
  std::vector<const ContactBenchRow*> probe;
  for (const auto& r : rows)
    if (r.scene == "probe") probe.push_back(&r);
  require(!probe.empty(), "bench-contact: no probe rows to plot");
  const ContactBenchRow& first = *probe[0];
  io::write_text_file(csv_path, [&](std::ostream& f) {
    f << "depth_mm,full_n";
    for (const auto* r : probe) f << ",K" << r->handles << "_n";
    f << "\n";
    for (size_t i = 0; i < first.curve_depth_mm.size(); ++i) {
      f << first.curve_depth_mm[i] << "," << first.curve_force_full_n.at(i);
      for (const auto* r : probe) f << "," << r->curve_force_reduced_n.at(i);
      f << "\n";
    }
  });
  // The loading ramp only (up to the deepest point), where depth increases.
  size_t n = 0;
  while (n + 1 < first.curve_depth_mm.size() && first.curve_depth_mm[n + 1] > first.curve_depth_mm[n]) ++n;
  auto head = [&](const std::vector<double>& v) { return std::vector<double>(v.begin(), v.begin() + long(n + 1)); };
  std::vector<io::PlotSeries> series;
  series.push_back({"full FEM", head(first.curve_depth_mm), head(first.curve_force_full_n), "#444444", true});
  int c = 0;
  for (const auto* r : probe) {
    char label[96];
    std::snprintf(label, sizeof label, "K = %d (%+.0f%% at %.0f mm)", r->handles, 100.0 * (r->force_at_depth_reduced_n / r->force_at_depth_full_n - 1.0), 1e3 * report_depth);
    series.push_back({label, head(first.curve_depth_mm), head(r->curve_force_reduced_n), io::plot_color(c++), false});
  }
  io::write_line_plot_svg(svg_path, "Probe (2 cm sphere) pressed into the thigh: force against depth",
                          "kinematic depth below the undeformed skin (mm)", "contact force (N)", series);
}

void write_contact_bench_markdown(const std::vector<ContactBenchRow>& rows, const std::string& path,
                                  const std::string& heading) {
  io::write_text_file(path, [&](std::ostream& f) { write_contact_bench_markdown(rows, heading, f); });
}

void write_contact_bench_markdown(const std::vector<ContactBenchRow>& rows, const std::string& heading,
                                  std::ostream& f) {
  f << heading << "\n\n| scene | K | dt (s) | rel_err | dent full (mm) | dent reduced (mm) | dent ratio | peak force "
                  "full / reduced (N) | active samples full / reduced | µs / sample / iter | ms/step contact | ms/step no contact "
                  "| ratio | full FEM ms/step |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  char buf[512];
  for (const auto& r : rows) {
    std::snprintf(buf, sizeof buf,
                  "| %s | %d | 1/%.0f | %.3f | %.2f | %.2f | %.3f | %.1f / %.1f | %d / %d | %.3f | %.3g | %.3g | %.2f | "
                  "%.3g |\n",
                  r.scene.c_str(), r.handles, 1.0 / r.dt, r.rel_err, r.dent_full_mm, r.dent_reduced_mm, r.dent_ratio,
                  r.force_full_n, r.force_reduced_n, r.active_samples_full, r.active_samples, r.us_per_sample_iter,
                  r.ms_contact, r.ms_no_contact, r.step_ratio, r.ms_full);
    f << buf;
  }
  bool header = false;
  for (const auto& r : rows) {
    if (r.scene.rfind("probe", 0) != 0) continue;
    if (!header)
      f << "\nProbes: force at 10 mm depth (first crossing on the loading ramp), the RMS of the relative force "
           "error over the loading curve at 2–10 mm, the dent, and the largest patch:\n\n| scene | K | full FEM (N) | "
           "reduced (N) | error at 10 mm | RMS error 2–10 mm | dent full / reduced (mm) | patch nodes |\n"
           "|---|---|---|---|---|---|---|---|\n";
    header = true;
    std::snprintf(buf, sizeof buf, "| %s | %d | %.2f | %.2f | %.0f %% | %.0f %% | %.2f / %.2f | %d |\n",
                  r.scene.c_str(), r.handles, r.force_at_depth_full_n, r.force_at_depth_reduced_n,
                  100.0 * r.force_err, 100.0 * r.force_rms_err, r.dent_full_mm, r.dent_reduced_mm,
                  r.max_patch_nodes);
    f << buf;
  }
}

}  // namespace sflsh
