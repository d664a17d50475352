#pragma once
// The geometric part of the shape stage of `sflsh precompute` (seed §4): the
// template tet mesh moved to shape β, the spatially varying skin thickness,
// and the avatar's geometric fields (surface embedding, regions, materials,
// local frames, capsules). It only moves nodes: every shape keeps the
// template's tets (seed §4: one tetrahedral discretization for all shapes);
// the topological repairs a shape would need are made once, for the whole
// shape space, by the template stage (volume/topology_design.hpp).
#include "sflsh/asset/avatar.hpp"
#include "sflsh/body/body_model.hpp"
#include "sflsh/mesh/interior_smoothing.hpp"
#include "sflsh/mesh/tet_quality.hpp"
#include "sflsh/volume/template_volume.hpp"
#include "sflsh/volume/thickness_map.hpp"

namespace sflsh {

struct ShapeOptions {
  /// Smallest depth fraction a node may reach when the soft layer is
  /// thickened (keeps the bone surface off the skeleton).
  double min_depth = 0.1;
  /// Jacobi smoothing iterations of the per-node thickness scale over the
  /// tet graph, so region borders blend instead of stepping.
  int scale_smoothing_iterations = 10;
  /// Capsule radius = this percentile of the skin-node thicknesses of a bone.
  double capsule_percentile = 0.5;
  /// Rounds of relaxing the thickness scale towards 1 around inverted tets
  /// (halved each round, set to 1 in the last) before giving up.
  int max_relax_rounds = 6;
  /// The thickness map may not push a tet's smallest dihedral angle below
  /// this (deg) or below its value at thickness scale 1, whichever is lower
  /// (a floor, not a target: changing the layer thickness alters every
  /// tet's angles a little).
  double min_dihedral_deg = 2.0;
  /// The shaped mesh is optimized (below) only if some tet's smallest
  /// dihedral angle is below this (deg), also where the template itself is
  /// below it; otherwise the nodes stay exactly where the shape and thickness
  /// map put them.
  double quality_floor_deg = 8.0;
  /// Optimization of the placed mesh (after the thickness map): interior
  /// nodes move freely, bone-surface nodes slide across their paths (in the
  /// plane orthogonal to skeleton point -> skin point), skin nodes stay, until
  /// no tet is below smoothing.target_deg or no move helps. passes = 0 skips it
  /// and also the untangling and skin sliding below (the bare placement).
  InteriorSmoothingOptions smoothing;
  /// If tets stay below quality_floor_deg after that (tets with all four nodes on the
  /// skin, where the shape flattened the skin), a second round also lets the
  /// skin nodes of the remaining bad tets slide along the shaped skin (each
  /// candidate projected onto it, so they stay exactly on the skin), at most
  /// this fraction of their shortest edge. 0 skips the round.
  double skin_slide_fraction = 0.3;
  /// Rounds of untangling where the node paths fold (before the optimization):
  /// the displacement from the template of the nodes off the skin around the
  /// inverted tets is replaced by its harmonic extension, over a region
  /// growing by two rings per round. 0 skips it.
  int untangle_rounds = 6;
  /// If tets still stay below quality_floor_deg (mostly ears of the skin: a
  /// skin node in a single tet, which only moving along the skin can raise),
  /// a last round lets the skin nodes of the bad tets slide this fraction of
  /// their shortest edge from where they are. 0 skips it.
  double final_skin_slide_fraction = 1.0;
};

struct ShapeReport {
  TetQualityReport quality;
  double max_embedding_distance = 0;  ///< m, skin vertices outside the tet mesh
  int num_embedded_outside = 0;
  /// Nodes whose thickness scale was relaxed towards 1 to avoid inverted tets.
  int num_relaxed_nodes = 0;
  /// Nodes off the skin whose displacement was made harmonic to untangle folds
  /// (summed over the rounds).
  int untangled_nodes = 0;
  /// The interior/bone-surface node optimization (quality before/after it),
  /// the second round with skin nodes sliding and the last, wider one
  /// (passes = 0 if not run).
  InteriorSmoothingReport smoothing, skin_smoothing, wide_skin_smoothing;
  /// Whether the shaped skin (the body model's surface at these betas)
  /// self-intersects: 1 or 0, tested (CGAL) only when the shaped mesh has an
  /// inverted tet or one below quality_floor_deg; −1 when not tested. A
  /// self-intersecting skin bounds no valid solid, so no mesh on it can be good.
  int skin_self_intersects = -1;
  double seconds = 0;
  std::string describe() const;
};

struct ShapedVolume {
  /// Fields filled: betas, model_hash, model_source, joints_rest, parents,
  /// joint_names, capsules, surface_* (rest, faces, weights, posedirs, tet,
  /// bary), tet, node_weights, node_role, surface_nodes, tet_region,
  /// tet_frames, materials. Basis and cubature are left empty.
  Avatar avatar;
  VecX node_depth;       ///< #N depth fraction after the thickness map
  VecX node_thickness_scale;  ///< #N smoothed thickness scale applied
  ShapeReport report;
};

/// The node placement of the shape stage alone (what shape_volume does
/// before it fills the avatar's fields): #N = the template's nodes.
struct ShapedNodes {
  Points nodes;               ///< #N by 3, shaped, unposed (m)
  VecX node_depth;            ///< #N depth fraction after the thickness map
  VecX node_thickness_scale;  ///< #N smoothed thickness scale applied
  Points node_skeleton;       ///< #N by 3 skeleton point of each node's path at β (m)
  Points v_shaped;            ///< #V by 3 the model's skin at β (m)
  Points joints;              ///< #J by 3 joints at β (m)
  /// quality (inverted tets counted, not thrown), relaxation, untangling and
  /// smoothing figures, seconds; the embedding and self-intersection fields unset.
  ShapeReport report;
};

/// Moves the template's nodes to shape `betas` as shape_volume does
/// (placement along the paths, thickness map, untangling, interior
/// optimization, skin sliding); the tets are tv.tet.elements throughout.
/// Unlike shape_volume it does not throw when tets stay inverted (the
/// template stage measures candidate shapes with it).
ShapedNodes place_shape_nodes(const TemplateVolume& tv, const BodyModel& model, const VecX& betas,
                              const ThicknessMap& thickness = ThicknessMap::defaults(),
                              const ShapeOptions& options = {});
/// Shape stage (geometry) for shape `betas` (missing entries 0). Nodes
/// follow the correspondence path: x = s(β) + d' (σ(β) - s(β)) + ρ(β), with
/// s the skeleton point (from the shaped joints), σ the skin point,
/// d' = 1 - k (1 - d) the depth with the soft layer scaled by k (thickness
/// map, limited so d' >= min_depth) and ρ the template residual carried in
/// the frame of the path (rotated with σ - s and scaled by its length). A
/// uniformly scaled body therefore gives the uniformly scaled mesh, and with
/// k = 1 the nodes are template nodes + Σ β_b node_shapedirs[b] up to the
/// residual's change. Where the thickened layer would invert tets, k is
/// relaxed towards 1 locally (ShapeReport::num_relaxed_nodes); likewise
/// where it would flatten tets (ShapeOptions::min_dihedral_deg). Then the
/// interior nodes and the bone-surface nodes (sliding across their paths) are
/// moved to raise the smallest dihedral angle (ShapeOptions::smoothing); the
/// skin nodes stay on the shaped skin (they only slide along it, for tets the
/// interior moves leave below the floor). The avatar's tets are tv's
/// (avatar.tet.elements == tv.tet.elements, avatar.tet_region == tv.tet_region)
/// for every β. Throws if tets stay inverted (then the shape itself folds the
/// mesh) or `tv` was built from another model.
ShapedVolume shape_volume(const TemplateVolume& tv, const BodyModel& model, const VecX& betas,
                          const ThicknessMap& thickness = ThicknessMap::defaults(), const ShapeOptions& options = {});

/// Local material frames per tet, #T by 9 row-major 3x3 with rows: along the
/// bone (segment direction), through the thickness (skeleton -> tissue,
/// orthogonalised), around (along × through). `node_skeleton` #N by 3.
MatXr tet_frames(const TetMesh& tet, const Points& node_skeleton, const VecXi& node_segment,
                 const std::vector<BoneSegment>& segments, const std::vector<int>& parents, const Points& joints);

/// One capsule per bone segment fitted to its flesh: the segment, radius =
/// `percentile` of the distances skin node -> skeleton point over the skin
/// nodes on that segment. Segments with fewer than 8 such nodes or shorter
/// than 1 cm get none.
std::vector<BoneCapsule> fit_bone_capsules(const Points& nodes, const Points& node_skeleton, const VecXi& skin_nodes,
                                           const VecXi& node_segment, const std::vector<BoneSegment>& segments,
                                           const std::vector<int>& parents, const Points& joints, double percentile);

}  // namespace sflsh
