// Grain shape descriptors (pure functions, no crumble dependency beyond geometry/).
//
// 2D (Harmon et al. 2020 §4–5), from a closed CCW outline polygon:
//   circularity   eq. 23: 4πA / P² (1 for a circle). The paper's words ("the ratio between the
//                 circumference of a circle with the particle's area and the perimeter") give
//                 2√(πA)/P, whose square is eq. 23; we follow the equation (the `true` ratio is
//                 √circularity).
//   aspect ratio  short / long axis of the best-fit ellipse: the ellipse with the same second
//                 moments of area about the centroid, so √(λ_min/λ_max) of the 2×2 central
//                 second-moment tensor (1 for a circle or a square, b/a for an ellipse).
//   sieve size    eq. 21: the diameter along the line through the centroid and the closest
//                 surface point p_min — the chord of that line through the outline (the two
//                 nearest crossings on either side of the centroid).
// 3D, from a closed triangle mesh and the mass properties:
//   sphericity    Wadell's true sphericity π^(1/3)(6V)^(2/3) / S (1 for a sphere).
//   Zingg indices EI = I/L, FI = S/I (Zhu & Zhao 2019 §5, Fig. 18; Zingg 1935) from the
//                 principal dimensions L ≥ I ≥ S by the paper's principal-axis approach: the
//                 grain is turned into the principal axes of its inertia and L, I, S are its
//                 extents along them (a box gives its sides, an ellipsoid its axes). The
//                 equivalent ellipsoid of the inertia (same principal moments) is kept as a
//                 separate function; it gives the same ratios for boxes and ellipsoids only.
//                 Caveat of the paper's approach: a grain with (nearly) equal principal
//                 moments (a sphere, a cube, a regular tetrahedron) has no defined principal
//                 axes, and its extents follow whatever axes the eigen-solver returns (a
//                 sphere is unaffected, a cube can give EI, FI anywhere in ≈ 0.6–1).
#pragma once
#include <array>
#include <vector>

#include "geometry/Shape.h"
#include "geometry/TriMesh.h"
#include "geometry/Vec3.h"

namespace crumble {

struct ShapeMetrics2D {
  double area = 0;          // m²
  double perimeter = 0;     // m
  double circularity = 0;   // eq. 23, in (0, 1]
  double aspect_ratio = 0;  // best-fit ellipse short / long, in (0, 1]
  double sieve_size = 0;    // m, eq. 21 chord
};

struct ShapeMetrics3D {
  double volume = 0;        // m³
  double surface_area = 0;  // m²
  double sphericity = 0;    // Wadell, in (0, 1]
  std::array<double, 3> principal_dimensions{};  // L ≥ I ≥ S: extents along the principal axes, m
  double elongation = 0;    // Zingg EI = I / L
  double flatness = 0;      // Zingg FI = S / I
};

// Harmon et al. 2020 eq. 23.
double circularity(double area, double perimeter);

// √(λ_min/λ_max) of the symmetric 2×2 tensor [[sxx, sxy], [sxy, syy]] of central second
// moments of area (∫x², ∫xy, ∫y² about the centroid).
double aspect_ratio_from_second_moments(double sxx, double syy, double sxy);

// Every 2D metric of a simple closed polygon (x–y; either orientation; z ignored).
// std::invalid_argument for fewer than 3 vertices or zero area.
ShapeMetrics2D shape_metrics_2d(const std::vector<Vec3>& outline);

// Wadell sphericity of a volume and surface area.
double sphericity(double volume, double surface_area);

// Full axes 2a ≥ 2b ≥ 2c of the solid ellipsoid with the same volume-normalised principal
// moments of inertia as `inertia` (about the centroid, per unit density) and volume V.
std::array<double, 3> equivalent_ellipsoid_axes(const Mat3& inertia, double volume);

// Zhu & Zhao 2019 §5: extents L ≥ I ≥ S (m) of the mesh along the principal axes of
// `inertia` (any reference point: extents do not depend on it). std::invalid_argument for
// a mesh without vertices.
std::array<double, 3> principal_extents(const TriMesh& mesh, const Mat3& inertia);

// Zingg (1935) classes on the EI–FI diagram, split at 2/3: "disc" (EI > 2/3, FI < 2/3),
// "spheroid" (both > 2/3; Zhu & Zhao 2019 Fig. 18), "blade" (both < 2/3), "rod" (EI < 2/3,
// FI > 2/3).
const char* zingg_class(double elongation, double flatness);

// Every 3D metric of a closed mesh with its mass properties (per unit density).
ShapeMetrics3D shape_metrics_3d(const TriMesh& mesh, const MassProperties& mp);

// Harmon et al. 2020 §4.2, eq. 21: the sieve size of a grain approximates its minor axis as
// the chord through the centroid along the line to the closest surface point p_min: |p_min|
// plus the distance from the centroid to the surface in the opposite direction. A disk gives
// its diameter, a rectangle its shorter side. p_min among the shape's level-set surface
// nodes (as the paper takes it), the opposite crossing from the signed distance; 2D and 3D.
// (ShapeMetrics2D::sieve_size is the same chord for a bare polygon outline.) A shape whose
// centroid lies outside it (a crescent) has no such chord: its equivalent diameter is used.
double sieve_size(const Shape& s);

}  // namespace crumble
