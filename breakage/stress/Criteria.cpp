// The table of criteria of the stress model: one line per criterion.
#include "breakage/stress/Criterion.h"

namespace crumble::stress {

CriterionEntry max_principal_criterion();  // MaxPrincipal.cpp
CriterionEntry von_mises_criterion();      // VonMises.cpp
CriterionEntry tresca_criterion();         // Tresca.cpp

const std::vector<CriterionEntry>& criteria() {
  static const std::vector<CriterionEntry> table{
      max_principal_criterion(),
      von_mises_criterion(),
      tresca_criterion(),
  };
  return table;
}

const CriterionEntry* find_criterion(const std::string& name) {
  for (const auto& c : criteria())
    if (c.name == name) return &c;
  return nullptr;
}

std::vector<std::string> criterion_names() {
  std::vector<std::string> out;
  for (const auto& c : criteria()) out.push_back(c.name);
  return out;
}

}  // namespace crumble::stress
