// The yield criteria of the stress breakage model (Harmon et al. 2020, §3.1). A criterion
// turns the principal values of a grain's average stress into an equivalent stress and
// decides failure against the grain's strength values. Adding one = one small .cpp file
// defining a CriterionEntry + one line in the table of Criteria.cpp.
#pragma once
#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/Grain.h"

namespace crumble::stress {

// Principal stresses, Pa, tension positive (the sign eq. 5 gives with forces on the
// grain), sorted s[0] >= s[1] >= s[2]. 2D (plane stress): the two in-plane values and 0.
using Principal = std::array<double, 3>;

// Names of the per-grain strength values (Grain::strength).
inline constexpr const char* kStrength = "strength_Pa";
inline constexpr const char* kTensileStrength = "tensile_strength_Pa";

class Criterion {
 public:
  virtual ~Criterion() = default;
  // The stress compared with the grain's strength_Pa (Pa, >= 0).
  virtual double equivalent_stress(const Principal& s) const = 0;
  // True when the stress state breaks a grain of these strength values.
  virtual bool fails(const Principal& s, const StrengthState& strength) const {
    return equivalent_stress(s) >= strength.get(kStrength);
  }
};

struct CriterionEntry {
  std::string name;                 // breakage.criterion
  std::string description;          // one line for `crumble list` and errors (cites the paper)
  double default_strength = 0;      // Pa: characteristic strength σ0 of eq. 12 (Table 2)
  double default_tensile_strength = 0;  // Pa; > 0 only for criteria with a tensile limit
  std::function<std::unique_ptr<Criterion>()> make;
};

// The table of criteria (Criteria.cpp), in a fixed order.
const std::vector<CriterionEntry>& criteria();
// nullptr when unknown.
const CriterionEntry* find_criterion(const std::string& name);
std::vector<std::string> criterion_names();

}  // namespace crumble::stress
