#include "core/Guards.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_map>

namespace crumble {

namespace {

std::string where(const GuardContext& at) {
  std::ostringstream os;
  os << "at step " << at.step << " (" << at.phase << ", t = " << at.time << " s, platen stress " << at.platen_stress
     << " Pa, dt = " << at.dt << " s)";
  return os.str();
}

[[noreturn]] void fail(const GuardContext& at, const std::string& what) {
  throw PhysicsGuardError("physical guard failed " + where(at) + ": " + what + ". " + at.advice +
                          " (Guards: simulation.guards; see docs/scenarios.md.)");
}

}  // namespace

void check_stress_carried(const GuardSettings& s, const GuardContext& at, double commanded_stress) {
  if (!s.enabled || !(commanded_stress > 0) || at.platen_stress >= 0.5 * commanded_stress) return;
  std::ostringstream os;
  os << "at the end of the stress ramp the packing carries " << at.platen_stress << " Pa of the " << commanded_stress
     << " Pa the platen is driven with: the platen met (almost) no resistance and is falling through the packing. "
        "Lengthen loading.ramp_time (or add loading.hold_time)";
  fail(at, os.str());
}

void check_scalar_invariants(const GuardSettings& s, const GuardContext& at, double platen_height, double void_ratio,
                             double platen_force) {
  if (!std::isfinite(platen_height) || !std::isfinite(platen_force) || !std::isfinite(void_ratio))
    fail(at, "the engine state became non-finite (platen height " + std::to_string(platen_height) + " m, force " +
                 std::to_string(platen_force) + " N)");
  if (!s.enabled) return;
  std::ostringstream os;
  if (!(platen_height > 0)) {
    os << "the platen is at " << platen_height << " m, at or below the floor";
    fail(at, os.str());
  }
  if (!at.open && !(void_ratio > 0)) {
    os << "the void ratio is " << void_ratio << " (<= 0): the grains overlap more than their own volume";
    fail(at, os.str());
  }
}

double kinetic_energy(std::span<const Grain> grains, std::span<const Material> materials, int dimension) {
  double ke = 0;
  for (const auto& g : grains) {
    const double rho = materials[static_cast<std::size_t>(g.material)].density;
    const MassProperties& mp = g.shape->mass_properties();
    ke += 0.5 * rho * mp.volume * dot(g.velocity, g.velocity);
    const Vec3 wb = g.orientation.conjugate().rotate(g.angular_velocity);
    if (dimension == 2) {
      ke += 0.5 * rho * mp.inertia(2, 2) * wb.z * wb.z;
    } else {
      ke += 0.5 * rho * dot(wb, mp.inertia * wb);
    }
  }
  return ke;
}

namespace {

// An open scene's grain outside the domain other than through its bottom. A grain below the
// bottom, or below the discharge level, is leaving through the discharge and one above
// eject_above was thrown out (Container): the Simulation takes it out at its next sample step,
// and the check after the last step comes before that.
void check_in_domain(const GuardContext& at, const Container& box, int dimension, const Grain& g) {
  const int up = dimension == 3 ? 2 : 1;
  if (g.position[up] < box.discharge_level || g.position[up] > box.eject_above) return;
  if (!box.beside_domain(g.position, dimension) && g.position[up] <= box.domain.hi[up]) return;
  std::ostringstream os;
  os << "grain " << g.id << " (d = " << g.shape->equivalent_diameter() << " m) has its centroid at ("
     << g.position.x << ", " << g.position.y;
  if (dimension == 3) os << ", " << g.position.z;
  os << ") m, outside the scene's domain (" << box.domain.lo.x << " .. " << box.domain.hi.x << ", "
     << box.domain.lo.y << " .. " << box.domain.hi.y;
  if (dimension == 3) os << ", " << box.domain.lo.z << " .. " << box.domain.hi.z;
  os << " m) other than through its bottom (the discharge): it has passed through a moving wall or was thrown out";
  fail(at, os.str());
}

// A grain outside the closed container: a tiny one is noted in r.escaped_small, any other
// fails.
void check_in_container(const GuardSettings& s, const GuardContext& at, const Container& box, int dimension,
                        double platen_height, const Grain& g, GuardReading& r) {
  const double up = dimension == 2 ? g.position.y : g.position.z;
  const bool out_x = g.position.x < 0 || g.position.x > box.lx;
  const bool out_y = dimension == 3 && (g.position.y < 0 || g.position.y > box.ly);
  if (!(out_x || out_y || up < 0 || up > platen_height)) return;
  if (g.shape->equivalent_diameter() < s.small_grain_fraction * at.reference_diameter) {
    r.escaped_small.push_back(g.id);
    return;
  }
  std::ostringstream os;
  os << "grain " << g.id << " (d = " << g.shape->equivalent_diameter() << " m) has its centroid at (" << g.position.x
     << ", " << g.position.y;
  if (dimension == 3) os << ", " << g.position.z;
  os << ") m, outside the container (lx " << box.lx;
  if (dimension == 3) os << ", ly " << box.ly;
  os << ", floor 0, platen " << platen_height << " m): it has passed through a wall";
  fail(at, os.str());
}

// Contact c overlaps by more than max_overlap_fraction of d, the smaller diameter.
[[noreturn]] void fail_overlap(const GuardSettings& s, const GuardContext& at, const Contact& c, const Grain& ga,
                               double d) {
  static const char* const kWallNames[] = {"floor", "platen", "x = 0 wall", "x = lx wall", "y = 0 wall", "y = ly wall"};
  std::ostringstream os;
  os << "grain " << c.a << " (d = " << ga.shape->equivalent_diameter() << " m";
  if (ga.generation > 0) os << ", generation " << ga.generation << ", a fragment of grain " << ga.parent;
  os << ") overlaps ";
  if (c.is_wall())
    os << "wall " << c.wall << (c.wall >= 0 && c.wall < 6 ? std::string(" (") + kWallNames[c.wall] + ")" : std::string());
  else
    os << "grain " << c.b;
  os << " by " << c.overlap << " m, " << c.overlap / d << " of the smaller diameter (limit "
     << s.max_overlap_fraction << ", simulation.guards.max_overlap_fraction)";
  // Deeper than the grain itself while its centroid is inside the container (checked
  // above): no position of the grain gives that; the engine's contact is wrong.
  if (c.is_wall() && s.containment && c.overlap > d)
    os << "; an overlap deeper than the grain's own diameter with its centroid inside the container is no "
          "position the grain can have: the engine reported a wrong contact depth for this shape (e.g. "
          "a thin fragment's hull)";
  fail(at, os.str());
}

void check_overlaps(const GuardSettings& s, const GuardContext& at, std::span<const Contact> contacts,
                    const std::unordered_map<GrainId, const Grain*>& by_id, GuardReading& r) {
  for (const auto& c : contacts) {
    if (!(c.overlap > 0)) continue;
    auto ia = by_id.find(c.a);
    if (ia == by_id.end()) continue;
    double d = ia->second->shape->equivalent_diameter();
    if (!c.is_wall()) {
      auto ib = by_id.find(c.b);
      if (ib == by_id.end()) continue;
      // Fragments of one grain are born overlapping where the fragment builder grew or
      // hulled them (Zhu & Zhao 2019 §3.2): the engine separates them; not a failure.
      if (ia->second->origin >= 0 && ia->second->origin == ib->second->origin) continue;
      d = std::min(d, ib->second->shape->equivalent_diameter());
    }
    if (d < s.small_grain_fraction * at.reference_diameter) {
      if (c.overlap > s.max_overlap_fraction * d) ++r.small_grain_overlaps;
      continue;
    }
    r.max_overlap_fraction = std::max(r.max_overlap_fraction, c.overlap / d);
    if (c.overlap > s.max_overlap_fraction * d) fail_overlap(s, at, c, *ia->second, d);
  }
}

void check_energy(const GuardSettings& s, const GuardContext& at, std::span<const Grain> grains,
                  std::span<const Material> materials, int dimension, GuardReading& r) {
  const double ke = kinetic_energy(grains, materials, dimension) + at.added_kinetic_energy;
  r.energy_ratio = at.energy_budget > 0 ? ke / at.energy_budget : 0;
  if (!std::isfinite(ke) || ke > s.energy_factor * at.energy_budget) {
    std::ostringstream os;
    os << "the grains' kinetic energy " << ke << " J";
    if (at.added_kinetic_energy > 0) os << " (" << at.added_kinetic_energy << " J of it in the mass added for the stable step)";
    os << " exceeds " << s.energy_factor
       << " times the energy that can have entered the system (" << at.energy_budget
       << " J: initial kinetic energy, platen work, weight over the container height): the integration is unstable";
    fail(at, os.str());
  }
}

}  // namespace

GuardReading check_invariants(const GuardSettings& s, const GuardContext& at, const Container& box, int dimension,
                              double platen_height, std::span<const Grain> grains,
                              std::span<const Material> materials, std::span<const Contact> contacts) {
  GuardReading r;
  if (!s.enabled) return r;
  std::unordered_map<GrainId, const Grain*> by_id;
  by_id.reserve(grains.size());
  for (const auto& g : grains) {
    by_id[g.id] = &g;
    if (!std::isfinite(g.position.x) || !std::isfinite(g.position.y) || !std::isfinite(g.position.z) ||
        !std::isfinite(g.velocity.x) || !std::isfinite(g.velocity.y) || !std::isfinite(g.velocity.z))
      fail(at, "grain " + std::to_string(g.id) + " has a non-finite position or velocity");
    if (!s.containment) continue;
    if (box.open)
      check_in_domain(at, box, dimension, g);
    else
      check_in_container(s, at, box, dimension, platen_height, g, r);
  }
  if (s.max_overlap_fraction > 0) check_overlaps(s, at, contacts, by_id, r);
  if (s.energy_factor > 0) check_energy(s, at, grains, materials, dimension, r);
  return r;
}

}  // namespace crumble
