// Maximum principal stress, in compression and in tension (Harmon et al. 2020, eqs. 7–8):
// σ_C = min(σ_p) breaks when −σ_C >= σ_C^max, σ_T = max(σ_p) when σ_T >= σ_T^max.
// Table 2: σ_C^max = 40 MPa, σ_T^max = 0.4 MPa.
#include "breakage/stress/Criterion.h"

namespace crumble::stress {
namespace {

class MaxPrincipal final : public Criterion {
 public:
  // The compressive magnitude (eq. 7); the tensile limit is checked in fails().
  double equivalent_stress(const Principal& s) const override { return s[2] < 0 ? -s[2] : 0.0; }
  bool fails(const Principal& s, const StrengthState& st) const override {
    return equivalent_stress(s) >= st.get(kStrength) || s[0] >= st.get(kTensileStrength);
  }
};

}  // namespace

CriterionEntry max_principal_criterion() {
  return {"max_principal",
          "largest compressive (-min) or tensile (max) principal stress against two strengths (Harmon et al. 2020, "
          "eqs. 7-8)",
          40e6, 0.4e6, [] { return std::make_unique<MaxPrincipal>(); }};
}

}  // namespace crumble::stress
