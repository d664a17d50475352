#pragma once
// The template stage of `sflsh precompute` (seed §2, §4): once per body model,
// at β = 0. Builds the one tet mesh shared by all shapes: the shell between
// the skin and an inner (bone) surface at a medium skin thickness, and
// extends skinning weights and blend shapes into it along the surface ->
// skeleton correspondence.
#include <string>
#include <vector>

#include "sflsh/body/body_model.hpp"
#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"
#include "sflsh/mesh/sliver_repair.hpp"
#include "sflsh/meshing/tetrahedralize.hpp"
#include "sflsh/volume/correspondence.hpp"
#include "sflsh/volume/skeleton_segments.hpp"

namespace sflsh {

// 2: bone-surface/interior nodes relocated by sliver repair.
// 3: the tets repaired once for the whole shape space (topology design): a
//    cache of version 2 holds the mesher's tets and is rebuilt, not reused.
inline constexpr int kTemplateVolumeFormatVersion = 3;

/// The template stage's topology design (volume/topology_design.hpp): the
/// one connectivity every shape uses is repaired for the corners of the shape
/// box (skin caps) and at a set of design shapes (every repair).
struct TopologyDesignOptions {
  /// Design shapes: β = 0; each of the first `directions` shape directions
  /// alone at −range and +range; all of them at −range, all at +range; and
  /// the two alternating corners (+−+−..., −+−+...). The skin caps are also
  /// screened at all 2^directions corners. directions = 0 skips the design
  /// (the mesher's tets are kept).
  int directions = 10;
  double range = 3.0;
  /// A tet inverted or below this (deg) at a design shape is repaired (the
  /// shape stage's quality_floor_deg).
  double floor_deg = 8.0;
  /// 2-3/3-2 flips are tried on tets below this (deg) at a design shape (the
  /// shape stage's smoothing target).
  double flip_target_deg = 10.0;
  /// Rounds of (node placement at the design shapes, repairs), until no
  /// design shape has a tet inverted or below floor_deg or no repair is accepted.
  int rounds = 3;
};

/// What the topology design did.
struct TopologyDesignReport {
  std::vector<std::string> shapes;  ///< design shape names ("zero", "beta3=-3", "all -3", ...)
  /// Per design shape: min dihedral (deg) and inverted tets of the node-only
  /// placement on the mesher's tets (before) and on the repaired tets (after).
  std::vector<double> min_dihedral_before, min_dihedral_after;
  std::vector<int> inverted_before, inverted_after;
  /// Skin caps removed before the rounds because some corner of the shape box
  /// makes them inverted or flat (the skin's placement is linear in β, so all
  /// 2^directions corners are screened); corners_screened = 2^directions.
  int caps_removed_at_corners = 0;
  long corners_screened = 0;
  int caps_removed = 0, ears_removed = 0, flips_2_3 = 0, flips_3_2 = 0, flips_2_2 = 0;
  int rounds = 0;            ///< rounds of repairs made
  int tets_before = 0, nodes_before = 0;
  double seconds = 0;
  std::string describe() const;
};

struct TemplateOptions {
  /// Depth fraction of the inner (bone) surface along skeleton -> skin
  /// (0 = skeleton, 1 = skin): the soft layer is the outer 1 - inner_depth.
  double inner_depth = 0.4;
  CorrespondenceOptions correspondence;
  /// Mesh_3 criteria. With the sizing-field defaults below, the procedural
  /// body gets ~34k tets / 11.8k nodes, min dihedral 8 deg after sliver
  /// repair, skin within 1.9 mm of the tet boundary over the simulated flesh
  /// (2.4 mm at the toe tips, which are Skinned). A size_scale /
  /// distance_scale set here replaces the fields below (it is not part of
  /// the precompute cache key, so leave them empty there).
  TetrahedralizeOptions mesh;
  /// Node relocation of the remaining slivers (bone-surface and interior
  /// nodes only; passes = 0 skips it).
  SliverRepairOptions sliver_repair;
  /// The repairs of the tets, once for all shapes (seed §4).
  TopologyDesignOptions topology;
  /// Nodes whose skinning weights on head/hand/foot joints (is_skinned_joint)
  /// sum to at least this are Skinned.
  double skinned_weight_threshold = 0.5;
  /// Sizing field of the mesh, blended by the head/hand/foot skinning weight
  /// w of the nearest skin point: a factor 1 + (skinned_size_scale - 1) w on
  /// mesh.facet_size / mesh.cell_size, and the facet distance rises towards
  /// skinned_facet_distance (m) there. Those parts only follow skinning, so
  /// they need fewer tets. A size factor of 2 saves little on the procedural
  /// body (the distance bound dominates) but lets facets cut finger tips by
  /// 4 mm, hence 1.
  double skinned_size_scale = 1.0;
  double skinned_facet_distance = 0.00105;
  /// Facet distance (m) on the bone surface, reached over the first 3 mm of
  /// depth below the skin: the bone surface needs no fidelity, and its facets
  /// were about half of all boundary facets. A distance at or below
  /// mesh.facet_distance (e.g. 0) leaves the bound uniform there; the
  /// factors of the two distances multiply where both apply.
  double inner_facet_distance = 0.0035;
};

/// Figures of the template stage.
struct TemplateReport {
  TetrahedralizeReport mesh;  ///< quality figures are after sliver repair
  SliverRepairReport sliver_repair;
  TopologyDesignReport topology;
  double correspondence_s = 0, mesh_s = 0, extension_s = 0, topology_s = 0, total_s = 0;
  /// Max distance of outer-boundary nodes to the skin (m) and max distance
  /// of skin vertices to the tet outer boundary (m).
  double outer_node_to_skin = 0, skin_to_outer_boundary = 0;
  /// skin_to_outer_boundary over the skin vertices that are not Skinned
  /// (skinned_weight_threshold), i.e. over the simulated flesh (m).
  double skin_to_outer_boundary_simulated = 0;
  /// Skin vertices where the two maxima above occur (-1 if none).
  int worst_skin_vertex = -1, worst_simulated_skin_vertex = -1;
  /// Their positions (m) and dominant skinning joints, for the report.
  Vec3 worst_skin_position = Vec3::Zero(), worst_simulated_skin_position = Vec3::Zero();
  int worst_skin_joint = -1, worst_simulated_skin_joint = -1;
  int num_outer_nodes = 0, num_inner_nodes = 0, num_skinned_nodes = 0;
  /// Max |residual| of the node path fit (m; see TemplateVolume::node_residual).
  double max_path_residual = 0;
  std::string describe() const;
};

/// The shape-independent template-stage result. #N nodes, #T tets, #V skin
/// vertices, #J joints (24), #B shape directions.
struct TemplateVolume {
  int format_version = kTemplateVolumeFormatVersion;
  std::string model_hash;  ///< body_model_hash() of the model it was built from
  double inner_depth = 0.4;  ///< TemplateOptions::inner_depth it was built with
  std::vector<BoneSegment> segments;
  SurfaceCorrespondence surface;  ///< skin vertex -> skeleton correspondence (β = 0)

  TetMesh tet;           ///< β = 0 nodes (m) and positively oriented tets
  VecXi outer_nodes;     ///< nodes on the skin
  VecXi inner_nodes;     ///< nodes on the inner (bone) surface
  // Node correspondence: path skeleton point s -> surface point σ, with
  // x = s + depth (σ - s) + residual.
  VecXi node_face;       ///< #N skin triangle of σ
  Points node_face_bary; ///< #N by 3 barycentric coordinates of σ in node_face
  MatXr node_skeleton_coefficients;  ///< #N by #J: s = row · joints
  VecX node_depth;       ///< #N in [0,1]: 0 skeleton side, 1 skin
  Points node_residual;  ///< #N by 3, x - (s + depth (σ - s)) at β = 0 (m)
  VecXi node_segment;    ///< #N bone segment of the node's path (for frames/capsules)
  MatXr node_weights;    ///< #N by #J LBS weights (skin weights of σ, constant along the path)
  /// Shape blend shapes extended into the volume: node_shapedirs[b] (#N by 3)
  /// = (1 - depth) Δs_b + depth Δσ_b (lerp of skeleton-point and skin offsets).
  std::vector<Points> node_shapedirs;
  /// #N*3 by 207 pose blend shapes, depth · posedirs(σ) (zero at the
  /// skeleton); empty when the model has none.
  MatX node_posedirs;
  VecXi node_role;       ///< #N NodeRole (Simulated / Skinned / Bone)
  VecXi tet_region;      ///< #T index into body_region_names()
  TemplateReport report;
};

/// Runs the template stage on `model` (shows progress): correspondence,
/// meshing, node paths and fields, then the topology design
/// (volume/topology_design.hpp), which fixes the tets every shape uses.
/// Throws sflsh::Error if meshing fails or the mesh is invalid (inverted tets).
TemplateVolume build_template_volume(const BodyModel& model, const TemplateOptions& options = {});

/// Cache file (HDF5, group /template, written atomically).
void save_template_volume(const TemplateVolume& tv, const std::string& path);
/// Reads a cache written by save_template_volume; throws naming the file and
/// dataset on a missing/mismatched/corrupt entry or a different format version.
TemplateVolume load_template_volume(const std::string& path);

}  // namespace sflsh
