// Tresca (Harmon et al. 2020, eq. 10): the grain breaks when τ = ½ max|σi − σj| reaches
// ½σ^max, i.e. when the Tresca equivalent stress max|σi − σj| = 2τ reaches the strength
// σ^max. Table 2 lists 40 MPa ("max shear stress"); eq. 10 compares it as σ^max.
#include <algorithm>
#include <cmath>

#include "breakage/stress/Criterion.h"

namespace crumble::stress {
namespace {

class Tresca final : public Criterion {
 public:
  double equivalent_stress(const Principal& s) const override {
    return std::max({std::abs(s[0] - s[1]), std::abs(s[1] - s[2]), std::abs(s[2] - s[0])});
  }
};

}  // namespace

CriterionEntry tresca_criterion() {
  return {"tresca", "Tresca: largest principal stress difference 2*tau (Harmon et al. 2020, eq. 10)", 40e6, 0,
          [] { return std::make_unique<Tresca>(); }};
}

}  // namespace crumble::stress
