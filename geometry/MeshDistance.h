#pragma once
#include <memory>

#include "geometry/TriMesh.h"

namespace crumble {

// Signed distance to a closed, outward-oriented triangle mesh (negative inside).
// Builds an acceleration structure once; queries are thread-safe.
class MeshDistance {
 public:
  explicit MeshDistance(const TriMesh& mesh);
  ~MeshDistance();
  MeshDistance(MeshDistance&&) noexcept;
  double signed_distance(const Vec3& p) const;
  bool contains(const Vec3& p) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace crumble
