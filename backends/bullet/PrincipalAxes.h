// Principal axes of a symmetric 3x3 tensor (cyclic Jacobi rotations) and the rotation
// that takes principal-frame vectors into the original frame. Used by the Bullet adapter:
// Bullet stores a diagonal body inertia, so a grain whose inertia is not diagonal in its
// shape frame becomes a body in its principal frame.
#pragma once
#include "geometry/Vec3.h"

namespace crumble::bullet_detail {

struct PrincipalAxes {
  Vec3 moments;   // eigenvalues
  Mat3 axes;      // columns: unit eigenvectors, right-handed (det = +1)
  Quat rotation;  // the same rotation as a unit quaternion: x_original = rotation.rotate(x_principal)
};

// Throws std::invalid_argument for a non-finite or non-symmetric input.
PrincipalAxes principal_axes(const Mat3& symmetric);

// Unit quaternion of a proper rotation matrix (Shepperd's method).
Quat quat_from_rotation(const Mat3& r);

}  // namespace crumble::bullet_detail
