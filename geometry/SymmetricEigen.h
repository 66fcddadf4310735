// Eigen-decomposition of symmetric 3x3 and 2x2 tensors (inertia for the Bullet adapter,
// average stress for the stress breakage model) and the rotation that takes
// principal-frame vectors into the original frame.
//
// 3x3: cyclic Jacobi rotations, moved unchanged from the Bullet adapter. Eigen's
// SelfAdjointEigenSolver gives the same tensors to round-off but other body frames for
// non-diagonal inertias, and the crushable-oedometer regression (Bullet + peridynamics)
// then drifts far outside its tolerance (final void ratio 0.93 instead of 1.19): the
// frames are kept bitwise as they were until the references are regenerated on purpose.
#pragma once
#include "geometry/Vec3.h"

namespace crumble {

struct PrincipalAxes {
  Vec3 moments;   // eigenvalues, in the order of the axes (not sorted)
  Mat3 axes;      // columns: unit eigenvectors, right-handed (det = +1)
  Quat rotation;  // the same rotation as a unit quaternion: x_original = rotation.rotate(x_principal)
};

// Throws std::invalid_argument for a non-finite or non-symmetric input (off-diagonal
// entries differing by more than 1e-10 of the largest entry).
PrincipalAxes principal_axes(const Mat3& symmetric);

// Eigenvalues (ascending) and unit eigenvectors of the symmetric 2x2 tensor
// [[xx, xy], [xy, yy]]: closed form, exact for a diagonal input. Throws
// std::invalid_argument for a non-finite input.
struct PrincipalAxes2 {
  double values[2] = {0, 0};
  Vec3 vectors[2];  // in the x–y plane (z = 0)
};
PrincipalAxes2 principal_axes_2d(double xx, double xy, double yy);

// Unit quaternion of a proper rotation matrix (Shepperd's method).
Quat quat_from_rotation(const Mat3& r);

}  // namespace crumble
