#pragma once
// The avatar asset: everything precomputed for one body shape, immutable at
// run time (MuJoCo's mjModel role). `sflsh precompute` builds it, the HDF5
// file (asset/avatar_file.hpp) stores it, the simulator reads it.
//
// Spaces: "rest"/"unposed" = shaped body in the model's rest pose (metres,
// Y up); "world" = posed. Soft displacement u lives in the unposed space:
//   x_world(x̄) = Σ_j w_j(x̄) G_j (x̄ + u(x̄) + b_pose(x̄, θ)),   u(x̄) = Σ_k W_k(x̄) z_k,
// with z_k ∈ R^3 the displacement of control handle k (r = 3K reduced DoFs).
#include <string>
#include <vector>

#include <Eigen/Sparse>

#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh {

inline constexpr int kAvatarFormatVersion = 1;

/// Node/tet role in the simulation.
enum class NodeRole : int {
  Simulated = 0,  ///< soft tissue: free soft displacement
  Skinned = 1,    ///< head, hands, feet: skinning only (u = 0, Dirichlet)
  Bone = 2,       ///< on the inner (bone) surface: u = 0 (Dirichlet)
};

/// Cubature: integrals over the volume ≈ Σ_s weights[s] f(point of sample s).
struct Cubature {
  VecXi elements;        ///< #S tet index of each sample
  MatXr barycentric;     ///< #S by 4 barycentric coordinates of the sample in its tet
  VecX weights;          ///< #S weights (m^3: volume each sample stands for)
  int size() const { return int(elements.size()); }
};

/// A capsule carried by a bone (contact proxy), in the unposed space.
struct BoneCapsule {
  int bone;      ///< SMPL joint index whose transform carries it
  Vec3 p0, p1;   ///< segment end points (m, unposed)
  double radius; ///< m
};

/// Per-region material (orthotropic StVK with Fung saturation, see sim/).
struct RegionMaterial {
  std::string name;
  double young_along = 3e4;    ///< Pa, along the bone
  double young_through = 1e4;  ///< Pa, through the thickness
  double young_around = 2e4;   ///< Pa, around the limb
  double poisson = 0.45;
  double fung_c = 2e3;         ///< Pa, saturation scale of exp(2Ψ/c)
  double density = 1000.0;     ///< kg/m^3

  /// Multiplies the three Young's moduli by `factor` (Poisson's ratio, Fung c and
  /// density kept): the stiffness of the region times `factor`.
  void scale_young(double factor) {
    young_along *= factor;
    young_through *= factor;
    young_around *= factor;
  }
  /// What is out of range ("" when nothing is): Young's moduli, Fung c and
  /// density must be > 0, Poisson's ratio in (−1, 0.5); e.g. "poisson = 0.6,
  /// expected in (-1, 0.5)". The one range check of a region's material.
  std::string range_problem() const;
  /// Throws "material 'NAME': <range_problem()>" when out of range.
  void require_in_range() const;
};

struct Avatar {
  // --- meta ---
  int format_version = kAvatarFormatVersion;
  VecX betas;              ///< shape the asset was built for
  std::string model_hash;  ///< body_model_hash() of the source model
  std::string model_source;

  // --- skeleton (unposed, shaped) ---
  Points joints_rest;                 ///< 24 by 3
  std::vector<int> parents;           ///< 24
  std::vector<std::string> joint_names;
  std::vector<BoneCapsule> capsules;

  // --- skin surface (the rendered/exported mesh) ---
  Points surface_rest;        ///< #V by 3, shaped, unposed
  Triangles surface_faces;    ///< #F by 3
  MatXr surface_weights;      ///< #V by 24 LBS weights
  MatX surface_posedirs;      ///< #V*3 by 207 or empty (no pose blend shapes)
  VecXi surface_tet;          ///< #V tet containing (or nearest to) each surface vertex
  MatXr surface_bary;         ///< #V by 4 barycentric coordinates in that tet

  // --- volume ---
  TetMesh tet;                ///< nodes shaped, unposed
  MatXr node_weights;         ///< #N by 24 LBS weights extended into the volume
  VecXi node_role;            ///< #N NodeRole
  VecXi surface_nodes;        ///< tet nodes on the outer surface
  VecXi tet_region;           ///< #T region index into `materials`
  MatXr tet_frames;           ///< #T by 9 row-major local frame (rows: along, through, around)
  std::vector<RegionMaterial> materials;

  // --- reduced basis ---
  Points handles;                               ///< #K by 3 control points (unposed)
  Eigen::SparseMatrix<double, Eigen::RowMajor> W;  ///< #N by #K bounded biharmonic weights

  // --- cubature ---
  Cubature elastic;
  Cubature inertia;

  int num_handles() const { return int(handles.rows()); }
  int num_reduced() const { return 3 * num_handles(); }
};

}  // namespace sflsh
