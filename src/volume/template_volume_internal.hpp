#pragma once
// Internals of the template volume (include/sflsh/volume/template_volume.hpp):
//   template_shell.cpp       — the soft-tissue shell between skin and bone surface, meshed,
//   template_node_paths.cpp  — each node's correspondence path to the skin,
//   template_volume.cpp      — the stages in order, the extended weights, roles, regions,
//   template_volume_file.cpp — the cache file.
#include <vector>

#include "sflsh/volume/surface_query.hpp"
#include "sflsh/volume/template_volume.hpp"

namespace sflsh::template_internal {

/// The meshed shell: which nodes lie on the tet boundary, and the distance (m)
/// within which a boundary node counts as on the skin.
struct ShellMesh {
  std::vector<char> boundary;
  double on_skin_tol = 0;
};

/// Meshes the shell between the skin and the inner (bone) surface into tv.tet
/// (tv.report.mesh, tv.report.sliver_repair); see template_shell.cpp.
ShellMesh mesh_shell(TemplateVolume& tv, const BodyModel& model, const Points& J0, const SurfaceQuery& skin,
                     const VecX& skinned_weight, const TemplateOptions& o);

/// For every node of tv.tet: its skin face, barycentric point, depth, path
/// residual, segment and skeleton coefficients (`outer`: the nodes on the skin).
void correspond_nodes(TemplateVolume& tv, const BodyModel& model, const Points& J0, const SurfaceQuery& skin,
                      const std::vector<char>& outer);

}  // namespace sflsh::template_internal
