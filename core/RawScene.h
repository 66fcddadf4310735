// A snapshot of rigid grains in a box, in SI units, for the adapter-overhead benchmark
// (`crumble bench engine`): each rigid-body backend can rebuild the same bodies directly
// through its library's own API (no crumble adapter in the loop) and step them, so the
// adapter's per-step cost can be compared with the raw library's on identical bodies.
#pragma once
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "geometry/TriMesh.h"

namespace crumble {

struct RawBody {
  TriMesh hull;            // convex hull (outward triangles), body frame, relative to the centre of mass (m)
  double mass = 0;         // kg (physical; the scene's mass_scale multiplies it)
  Mat3 inertia;            // about the centre of mass, body frame (kg m²)
  Vec3 com;                // world (m)
  Quat orientation;        // body → world
  Vec3 velocity, angular_velocity;
  double diameter = 0;      // the grain's equivalent diameter (m): its collision margin is a fraction of it
  double friction = 0.5;
  double rolling_friction = 0;
};

struct RawScene {
  std::vector<RawBody> bodies;
  double lx = 0, ly = 0;      // box: floor z = 0, walls x = 0, lx, y = 0, ly
  double platen_z = 0;        // a static lid at this height
  double wall_friction = 0;
  Vec3 gravity{0, 0, -9.81};
  double dt = 1e-5;
  int solver_iterations = 100;
  double erp = 0.003;
  double length_scale = 1;    // internal units per metre, as the adapter chose it
  double mass_scale = 1;
  double margin_fraction = 0.01;  // Bullet collision margin, fraction of the body size
  int contacts_per_pair = 1;      // ODE: most points per dCollide call
};

// The same bodies inside a library's own world, stepped by `dt` with the library's API only.
// The benchmark steps it alternately with the adapter, so both see the same machine load.
class RawWorld {
 public:
  virtual ~RawWorld() = default;
  virtual void step() = 0;
  // Touching pairs (grain–grain and grain–wall) in the last step: Bullet's manifolds that
  // carried an impulse, ODE's contact points (one per pair at contacts_per_pair = 1).
  virtual int contact_pairs() const = 0;
  // The world's settings and the last step's contact work under the names the adapter of the
  // same library reports them (Bullet: backends/bullet/BulletWorldReport.h); empty when the
  // baseline does not report them.
  virtual std::map<std::string, double> settings() const { return {}; }
  virtual std::map<std::string, double> contact_work() const { return {}; }
};

}  // namespace crumble
