#pragma once
// The one tet connectivity of all body shapes (seed §4: "all body shapes use
// the same tetrahedral discretization, independent of the shape
// coefficients β"). The shape stage only moves nodes, so whatever a shape
// needs beyond node moves — a skin cap that turns inside out where a shape
// makes a ridge of the skin concave, a sliver between two skin patches, a
// needle skin triangle, a flattened skin ear — is repaired here, once, in the
// template stage, for the whole shape box at once. First the skin caps that
// any corner of [−range, range]^directions turns inside out or flattens are
// removed (skin nodes move linearly with β, so all corners are cheap to
// screen). Then the node-only shape stage (place_shape_nodes) runs at a set of
// design shapes (topology_design_shapes), and the tets
// inverted or below the floor at any of them are repaired (cap removal, 2-3/
// 3-2 flips, boundary 2-2 flips, ear removal; mesh/boundary_caps.hpp,
// mesh/tet_flips.hpp), each repair accepted only if no design shape and not
// the template geometry gets worse (mesh/geometry_set.hpp:
// replacement_accepted). Placement and repairs alternate for a few rounds.
#include <string>
#include <utility>
#include <vector>

#include "sflsh/body/body_model.hpp"
#include "sflsh/volume/template_volume.hpp"

namespace sflsh {

/// The design shapes for a model with `num_betas` shape directions, named:
/// "zero"; "beta<d>=-3" and "beta<d>=+3" for each of the first
/// options.directions directions (range as given); "all -3", "all +3",
/// "alternating +-", "alternating -+" (only the first `directions`
/// components set). Empty when options.directions = 0.
std::vector<std::pair<std::string, VecX>> topology_design_shapes(int num_betas, const TopologyDesignOptions& options);

/// Repairs the tets of `tv` (a template built up to its node fields and
/// regions) for the design shapes of `options` with the default thickness
/// map and shape options, as the module comment says. Removes the apex nodes
/// of removed ears from every per-node field of `tv` (the other nodes keep
/// their order); new tets of a flip take the region of a tet they replace.
/// The template geometry (tv.tet.nodes) never gets an inverted tet or a worse
/// minimum dihedral angle.
TopologyDesignReport design_template_topology(TemplateVolume& tv, const BodyModel& model,
                                              const TopologyDesignOptions& options);

/// Keeps the nodes `kept` (#N', increasing indices into tv's nodes) of every
/// per-node field of `tv` and renumbers the tets and node lists; throws if a
/// tet uses a node that is not kept.
void keep_template_nodes(TemplateVolume& tv, const std::vector<int>& kept);

}  // namespace sflsh
