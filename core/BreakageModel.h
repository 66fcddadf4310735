// The breakage-model seam. `analyse` is pure and thread-safe: the Simulation calls it for
// several grains at once (one grain per task).
#pragma once
#include <optional>
#include <span>
#include <string>

#include "core/Contact.h"
#include "core/Fracture.h"
#include "core/Grain.h"
#include "core/Rng.h"

namespace crumble {

struct Analysis {
  bool broken = false;
  std::optional<Fracture> fracture;  // set when broken
  std::string outcome;               // short word for events.csv: intact, split, no_load, ...
  double criterion = 0;              // model's measure (stress in Pa, force in N, ...)
  double load = 0;                   // largest contact force considered, N
  // Cost figures (peridynamics fills these; others may leave them 0).
  long points = 0, bonds = 0, steps = 0;
  double wall_ms = 0;
};

class BreakageModel {
 public:
  virtual ~BreakageModel() = default;
  virtual std::string name() const = 0;
  // False for models that never break anything (the Simulation then skips contacts).
  virtual bool active() const { return true; }

  // Strength of a grain of the initial packing (Weibull sampling).
  virtual void assign_strength(Grain& g, const Material& m, Rng& rng) const = 0;
  // Strength of a child from its parent (Weibull size effect).
  virtual void inherit_strength(const Grain& parent, Grain& child, const Material& m, Rng& rng) const = 0;

  // Decide whether `g`, loaded by `contacts` (forces on g, world frame), breaks. The
  // fracture is expressed in g's body frame.
  virtual Analysis analyse(const Grain& g, const Material& m, std::span<const Contact> contacts) const = 0;
};

}  // namespace crumble
