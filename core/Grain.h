#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "geometry/Shape.h"

namespace crumble {

using GrainId = std::int64_t;

struct Material {
  double density = 2650;          // kg/m³
  double young = 100e9;           // Pa
  double poisson = 0.15;
  double friction = 0.5;          // grain–grain Coulomb coefficient
  double wall_friction = 0.0;     // grain–wall
  double rolling_friction = 0.05; // dimensionless (Bullet convention)
  double restitution = 0.0;
};

// Per-grain strength, sampled once by the breakage model and inherited by children with
// the Weibull size effect. The model owns the names and their meaning; each name ends in
// its unit (peridynamics: "gc_J_m2", "threshold_force_N"; stress criteria: "strength_Pa",
// "tensile_strength_Pa"). Checkpoints save and restore every value by name.
struct StrengthState {
  std::map<std::string, double> values;

  bool has(const std::string& name) const { return values.count(name) != 0; }
  // Throws std::out_of_range naming the value when the model never set it.
  double get(const std::string& name) const {
    auto it = values.find(name);
    if (it == values.end()) throw std::out_of_range("grain strength has no value '" + name + "'");
    return it->second;
  }
  double get_or(const std::string& name, double def) const {
    auto it = values.find(name);
    return it == values.end() ? def : it->second;
  }
  void set(const std::string& name, double v) { values[name] = v; }
};

// The force one contact partner exerts on a grain, summed over their contact points, in the
// grain's body frame (N). `partner` is the other grain's id, or -1 - wall index for a wall
// (partner_key in core/Screening.h).
struct PartnerForce {
  GrainId partner = 0;
  Vec3 force;
};

struct Grain {
  GrainId id = -1;
  GrainId parent = -1;
  // The grain of the initial packing this one descends from (itself for generation 0):
  // fragments of one grain start where their parent was and may overlap each other.
  GrainId origin = -1;
  int generation = 0;
  Shape::Ptr shape;
  int material = 0;
  Vec3 position;       // of the centroid (= shape origin), world frame, m
  Quat orientation;    // body → world
  Vec3 velocity;       // m/s
  Vec3 angular_velocity;  // rad/s, world frame
  StrengthState strength;
  // Breakage verdicts in this grain's lineage: how many times the breakage model judged this
  // grain or one of its ancestors broken. A child starts at its parent's count + 1; a grain
  // the model judged broken but the fragment builder could not split (outcome no_split)
  // stays in place and counts one more. So crush_count >= generation, and the difference is
  // the number of unsplit verdicts along the lineage.
  int crush_count = 0;
  // The load of this grain's last breakage analysis when that analysis left it whole, one
  // entry per contact partner in increasing `partner` order; empty when the grain was never
  // analysed or its last verdict was "broken". The skip rule (ScreeningSettings::
  // skip_intact_tolerance) compares the load of a check with it. Children start empty.
  std::vector<PartnerForce> intact_load;

  double mass(double density) const { return density * shape->volume(); }
  Vec3 to_world(const Vec3& local) const { return position + orientation.rotate(local); }
  Vec3 to_local(const Vec3& world) const { return orientation.conjugate().rotate(world - position); }
};

}  // namespace crumble
