// von Mises (Harmon et al. 2020, eq. 9): σ_V = √(½[(σ1−σ2)² + (σ2−σ3)² + (σ3−σ1)²]);
// Table 2: σ_Vmax = 35 MPa.
#include <cmath>

#include "breakage/stress/Criterion.h"

namespace crumble::stress {
namespace {

class VonMises final : public Criterion {
 public:
  double equivalent_stress(const Principal& s) const override {
    const double a = s[0] - s[1], b = s[1] - s[2], c = s[2] - s[0];
    return std::sqrt(0.5 * (a * a + b * b + c * c));
  }
};

}  // namespace

CriterionEntry von_mises_criterion() {
  return {"von_mises", "von Mises equivalent stress (Harmon et al. 2020, eq. 9)", 35e6, 0,
          [] { return std::make_unique<VonMises>(); }};
}

}  // namespace crumble::stress
