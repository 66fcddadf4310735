#pragma once
#include <vector>

#include "geometry/TriMesh.h"

namespace crumble {

// 3D convex hull of a point cloud as a closed, outward-oriented triangle mesh whose
// vertices are the hull's extreme points (points on a face or an edge of the hull are
// dropped where the hull without them still holds them). Every input point lies inside
// the result within 1e-9 of the cloud's size. Throws std::invalid_argument for fewer than 4
// points, a non-finite point or a (nearly) flat cloud; no other valid cloud makes it fail.
TriMesh convex_hull(const std::vector<Vec3>& points);

// The sign of the orientation determinant ((b − a) × (c − a)) · (p − a), exactly: +1 when p
// lies above the plane of the triangle (a, b, c) on the side its counter-clockwise normal
// points to, −1 below, 0 on it. Exact for finite inputs whose products neither overflow nor
// underflow (adaptive floating-point expansions, Shewchuk 1997).
int orientation(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p);

// The vertices of the convex polyhedron `convex` (a convex_hull() result) moved so that
// every face plane lies `distance` further inside — what engines with a collision margin
// need (the hull of these points, inflated by `distance`, is the original surface up to
// rounded edges). Each vertex takes the least-squares displacement over the planes of its
// incident faces, which is exact where three faces meet and close for the nearly
// symmetric vertices of round meshes (the vertex count stays the same). When that puts
// any vertex outside `convex` itself (acute vertices of thin fragments: the least-squares
// point can land far outside the solid), the result is the exact inset instead, the
// vertices of ∩ {n_j·x <= h_j − distance} (their count differs). Every returned point is
// inside `convex` (n_j·x <= h_j): the inflated hull sticks out by at most `distance`. Throws
// std::invalid_argument when `distance` is negative or not smaller than the distance from
// the centroid to the nearest face plane (convex_inradius_about_centroid).
std::vector<Vec3> inset_convex_vertices(const TriMesh& convex, double distance);

// Distance from the centroid of a closed convex mesh to its nearest face plane.
double convex_inradius_about_centroid(const TriMesh& convex);

}  // namespace crumble
