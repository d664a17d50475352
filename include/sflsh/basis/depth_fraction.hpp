#pragma once
// Depth fraction of the soft tissue: a scalar field b over the tet
// mesh that is 0 on the Dirichlet nodes (bone surface, skinned parts) and 1 on
// the skin, harmonic in between:
//   L_ff b_f = −L_fb b_b,   b_b = 0 at Bone/Skinned nodes, 1 at skin nodes,
// with L the P1 stiffness Laplacian and f the Simulated nodes off the skin.
// "Skin" = Simulated nodes on a boundary face of the tet mesh: the only other
// boundary is the bone surface, whose nodes are Bone (Dirichlet).
// By the discrete maximum principle b ∈ [0, 1] when L is an M-matrix; on
// obtuse tets it can overshoot slightly, so b is clamped to [0, 1].
// Used to blend a partition of unity over the flesh to 0 at the bone
// (bounded_biharmonic.hpp, BoneCondition::DepthBlend).
#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh::basis {

/// Simulated nodes (`node_role` #N, NodeRole) that lie on a boundary face of
/// `mesh`, ascending.
VecXi skin_nodes(const TetMesh& mesh, const VecXi& node_role);

/// #N harmonic depth fraction in [0, 1] (dimensionless): 0 at Bone and Skinned
/// nodes and at nodes in no tet, 1 at skin_nodes(), harmonic at the other
/// Simulated nodes. Fails if a Simulated node off the skin is connected to
/// neither a skin node nor a Dirichlet node (its value would be undetermined).
VecX depth_fraction(const TetMesh& mesh, const VecXi& node_role);

}  // namespace sflsh::basis
