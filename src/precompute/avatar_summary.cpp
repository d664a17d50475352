#include "sflsh/precompute/avatar_summary.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "sflsh/basis/handle_placement.hpp"
#include "sflsh/basis/sample_handles.hpp"
#include "sflsh/mesh/tet_quality.hpp"

namespace sflsh {

AvatarSummary summarize_avatar(const Avatar& a) {
  AvatarSummary s;
  s.surface_vertices = int(a.surface_rest.rows());
  s.surface_faces = int(a.surface_faces.rows());
  s.joints = int(a.joints_rest.rows());
  s.tet_nodes = a.tet.num_nodes();
  s.tets = a.tet.num_elements();
  for (Eigen::Index i = 0; i < a.node_role.size(); ++i) {
    const auto r = NodeRole(a.node_role[i]);
    (r == NodeRole::Simulated ? s.simulated_nodes : r == NodeRole::Skinned ? s.skinned_nodes : s.bone_nodes)++;
  }
  s.handles = a.num_handles();
  s.elastic_samples = a.elastic.size();
  s.inertia_samples = a.inertia.size();
  s.regions = int(a.materials.size());
  s.basis_nonzeros = a.W.nonZeros();
  const TetQualityReport q = tet_quality_report(a.tet);
  s.volume_m3 = q.total_volume;
  s.min_tet_volume_m3 = q.min_volume;
  s.min_dihedral_deg = q.min_dihedral_deg;
  for (int t = 0; t < s.tets; ++t) {
    const Vec3 x0 = a.tet.nodes.row(a.tet.elements(t, 0)), x1 = a.tet.nodes.row(a.tet.elements(t, 1)),
               x2 = a.tet.nodes.row(a.tet.elements(t, 2)), x3 = a.tet.nodes.row(a.tet.elements(t, 3));
    s.mass_kg += (x1 - x0).dot((x2 - x0).cross(x3 - x0)) / 6.0 * a.materials[a.tet_region[t]].density;
  }
  s.elastic_volume_m3 = a.elastic.weights.sum();
  s.inertia_volume_m3 = a.inertia.weights.sum();
  for (int i = 0; i < a.inertia.size(); ++i)
    s.inertia_mass_kg += a.inertia.weights[i] * a.materials[a.tet_region[a.inertia.elements[i]]].density;
  VecX row_sums = a.W * VecX::Ones(a.W.cols());
  s.max_partition_error = row_sums.size() ? std::max(0.0, row_sums.maxCoeff() - 1.0) : 0.0;
  if (a.W.nonZeros() > 0) {
    s.min_weight = INFINITY;
    s.max_weight = -INFINITY;
    for (int k = 0; k < a.W.outerSize(); ++k)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, k); it; ++it) {
        s.min_weight = std::min(s.min_weight, it.value());
        s.max_weight = std::max(s.max_weight, it.value());
      }
  }
  if (a.W.rows() == s.tet_nodes && a.node_role.size() == s.tet_nodes) {
    s.elastic_handles = basis::handles_per_sample(a.tet, a.W, a.node_role, a.elastic);
    s.inertia_handles = basis::handles_per_sample(a.tet, a.W, a.node_role, a.inertia);
  }
  s.region_names.clear();
  for (const RegionMaterial& m : a.materials) s.region_names.push_back(m.name);
  if (a.num_handles() > 0 && a.W.rows() == s.tet_nodes && a.tet_region.size() == s.tets) {
    const VecXi node_region = basis::node_regions_from_tets(a.tet, a.tet_region, s.regions);
    s.coverage = basis::basis_coverage(a.W, a.node_role, a.surface_nodes, node_region, s.regions,
                                       basis::nearest_nodes(a.tet.nodes, a.handles));
  }
  s.height_m = a.surface_rest.col(1).maxCoeff() - a.surface_rest.col(1).minCoeff();
  std::ostringstream b;
  for (Eigen::Index i = 0; i < a.betas.size(); ++i) b << (i ? "," : "") << a.betas[i];
  s.betas = b.str();
  s.model_source = a.model_source;
  s.model_hash = a.model_hash;
  return s;
}

std::string AvatarSummary::to_text(const std::string& title) const {
  std::ostringstream o;
  o << std::setprecision(4);
  o << title << "\n"
    << "  body model        " << model_source << " (hash " << model_hash << "), betas [" << betas << "]\n"
    << "  surface           " << surface_vertices << " vertices, " << surface_faces << " faces, height " << height_m << " m\n"
    << "  skeleton          " << joints << " joints\n"
    << "  tet mesh          " << tet_nodes << " nodes (" << simulated_nodes << " simulated, " << skinned_nodes
    << " skinned only, " << bone_nodes << " bone), " << tets << " tets\n"
    << "  tet quality       min dihedral " << min_dihedral_deg << " deg, min volume " << min_tet_volume_m3 << " m^3\n"
    << "  volume / mass     " << volume_m3 << " m^3, " << mass_kg << " kg, " << regions << " material regions\n"
    << "  basis             " << handles << " handles (" << 3 * handles << " reduced DoFs), " << basis_nonzeros
    << " non-zero weights in [" << min_weight << ", " << max_weight << "], max sum excess " << max_partition_error << "\n"
    << "  cubature          elastic " << elastic_samples << " samples (volume " << elastic_volume_m3 << " m^3), inertia "
    << inertia_samples << " samples (volume " << inertia_volume_m3 << " m^3, mass " << inertia_mass_kg << " kg)\n"
    << "  handles/sample    elastic mean " << elastic_handles.mean << ", max " << elastic_handles.max
    << "; inertia mean " << inertia_handles.mean << ", max " << inertia_handles.max << "\n";
  if (coverage.skin_nodes > 0) {
    std::istringstream lines(coverage.describe(region_names));
    for (std::string line; std::getline(lines, line);) o << "  " << line << "\n";
  }
  return o.str();
}

std::string AvatarSummary::to_json() const {
  std::ostringstream o;
  o << std::setprecision(10) << "{\n"
    << "  \"model_source\": \"" << model_source << "\",\n  \"model_hash\": \"" << model_hash << "\",\n"
    << "  \"betas\": [" << betas << "],\n"
    << "  \"surface_vertices\": " << surface_vertices << ",\n  \"surface_faces\": " << surface_faces << ",\n"
    << "  \"joints\": " << joints << ",\n  \"tet_nodes\": " << tet_nodes << ",\n  \"tets\": " << tets << ",\n"
    << "  \"simulated_nodes\": " << simulated_nodes << ",\n  \"skinned_nodes\": " << skinned_nodes << ",\n"
    << "  \"bone_nodes\": " << bone_nodes << ",\n  \"handles\": " << handles << ",\n"
    << "  \"basis_nonzeros\": " << basis_nonzeros << ",\n  \"elastic_samples\": " << elastic_samples << ",\n"
    << "  \"inertia_samples\": " << inertia_samples << ",\n  \"regions\": " << regions << ",\n"
    << "  \"volume_m3\": " << volume_m3 << ",\n  \"mass_kg\": " << mass_kg << ",\n"
    << "  \"min_tet_volume_m3\": " << min_tet_volume_m3 << ",\n  \"min_dihedral_deg\": " << min_dihedral_deg << ",\n"
    << "  \"elastic_volume_m3\": " << elastic_volume_m3 << ",\n  \"inertia_volume_m3\": " << inertia_volume_m3 << ",\n"
    << "  \"inertia_mass_kg\": " << inertia_mass_kg << ",\n  \"max_partition_error\": " << max_partition_error << ",\n"
    << "  \"min_weight\": " << min_weight << ",\n  \"max_weight\": " << max_weight << ",\n"
    << "  \"height_m\": " << height_m << ",\n"
    << "  \"handles_per_elastic_sample\": {\"mean\": " << elastic_handles.mean << ", \"max\": " << elastic_handles.max
    << "},\n  \"handles_per_inertia_sample\": {\"mean\": " << inertia_handles.mean << ", \"max\": "
    << inertia_handles.max << "},\n"
    << "  \"soft_coverage\": {\"threshold\": " << coverage.threshold << ", \"skin_nodes\": " << coverage.skin_nodes
    << ", \"covered\": " << coverage.covered << ", \"share\": " << coverage.share() << ", \"regions\": {";
  bool first = true;
  for (size_t r = 0; r < coverage.regions.size(); ++r) {
    const basis::RegionCoverage& g = coverage.regions[r];
    o << (first ? "" : ", ") << "\"" << (r < region_names.size() ? region_names[r] : std::to_string(r))
      << "\": {\"handles\": " << g.handles << ", \"skin_nodes\": " << g.skin_nodes << ", \"covered\": " << g.covered
      << "}";
    first = false;
  }
  o << "}}\n}\n";
  return o.str();
}

}  // namespace sflsh
