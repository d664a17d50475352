#pragma once
// Contact quadrature over the skin's faces (DESIGN.md §7).
//
// A contact penalty sampled at skin vertices depends on the mesh: a one-node
// load has no finite continuum limit, and a small probe touches one or two
// vertices. Here contact is a pressure integrated over the skin's area,
//   E = ∫_skin ½ κ min(φ(x), 0)² dA  ≈  Σ_s ½ κ a_s min(φ(x_s), 0)²,
// with κ the pressure stiffness (N/m³: contact pressure per metre of
// penetration) and samples s on the faces with area weights a_s (m², unposed
// rest area). The force on a patch is then κ × penetration × area, whatever
// the mesh.
//
// Each face is split into n² congruent sub-triangles, n = ⌈longest edge /
// spacing⌉, and carries a sample at each sub-triangle's centroid with weight
// area/n² (the composite centroid rule: exact for an integrand linear over
// each sub-triangle). A sample sits at fixed barycentric coordinates λ of its
// face, so it moves with the skin exactly as the rendered surface does:
// x_s = Σ_i λ_i x_{v_i} over the face's three vertices.
//
// Default spacing 2 mm: a 1 cm-diameter sphere pressed 2 mm into flat skin
// touches a disc of radius √(R d) ≈ 3.2 mm (32 mm²), which then holds ≥ 10
// samples. Samples are made only for the faces near an object (per step), so
// the fine spacing costs nothing where there is no contact.
//
// Default κ = 1e8 N/m³: penetration = pressure / κ, 0.1 mm per 10 kPa of
// contact pressure — small against the dents of soft tissue (Young's moduli
// 1e3–1e5 Pa), and of the order of the former per-vertex default (2e4 N/m at
// ~1.4e-4 m² of skin per vertex on the default body ≈ 1.4e8 N/m³).
#include <string>
#include <vector>

#include "sflsh/core/types.hpp"

namespace sflsh {

constexpr double kDefaultPressureStiffness = 1.0e8;  ///< κ, N/m³
constexpr double kDefaultContactSpacing = 0.002;     ///< m

/// One quadrature point of a skin face.
struct SkinFaceSample {
  int face = 0;
  Vec3 lambda = Vec3::Constant(1.0 / 3.0);  ///< barycentric coordinates on the face's vertices
  double area = 0;                          ///< m², the rest area this sample stands for
};

/// Subdivisions per edge of face `f` (≥ 1) for a sample spacing (m, > 0).
int face_subdivisions(const Points& rest, const Triangles& faces, int f, double spacing);

/// Appends the n² samples of face `f` (rest vertices `rest`) to `out`.
void append_face_samples(const Points& rest, const Triangles& faces, int f, double spacing,
                         std::vector<SkinFaceSample>& out);

/// Throws one line naming `what` unless κ is finite and > 0 and the spacing finite and > 0.
void check_contact_sampling(double pressure_stiffness, double spacing, const std::string& what);

}  // namespace sflsh
