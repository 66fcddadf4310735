// Which grains are worth a breakage analysis. The rule is Zhu & Zhao's (2019, §3.1, §5):
// a size limit, a force threshold, a minimum number of contacts and balance of forces and
// moments. Each breakage model chooses its defaults (BreakageModel::default_screening);
// the struct's own defaults switch every rule off but the contact count.
#pragma once
#include <span>
#include <vector>

#include "core/Contact.h"
#include "core/Grain.h"

namespace crumble {

struct ScreeningSettings {
  double min_diameter = 0;                 // m: smaller grains are never analysed
  bool force_threshold = true;             // require max |F| >= the model's threshold_force(grain)
  double max_unbalanced_force_ratio = 0;   // <= 0 disables
  double max_unbalanced_moment_ratio = 0;  // <= 0 disables
  int min_contacts = 1;
};

// Zhu & Zhao 2019, §5: crushing limit 0.3 mm, unbalanced-force ratio <= 0.02,
// unbalanced-moment ratio <= 0.2, at least two contacts, force threshold on.
ScreeningSettings zhu_zhao_screening();

struct ScreeningResult {
  bool selected = false;
  const char* reason = "";  // why not: too_small, no_contacts, below_threshold, unbalanced_force, ...
  double max_force = 0;
  double unbalanced_force_ratio = 0;
  double unbalanced_moment_ratio = 0;
};

// `contacts` are the contacts on `g` (force on g). Zhu & Zhao 2019 §5: unbalanced force ratio =
// |Σ F| / mean |F|; unbalanced moment ratio = |Σ (x − x_fix) × F| / mean |x − x_fix|·|F|
// about the point of the largest force (the zone a peridynamic analysis fixes) — the paper
// says "average magnitude of moment"; see Screening.cpp for why the lever-arm form. Gravity
// is left out: at the forces that break grains it is < 1e-4 of them. `threshold_force` (N)
// is the model's screening force for g (BreakageModel::threshold_force).
ScreeningResult screen(const Grain& g, std::span<const Contact> contacts, const ScreeningSettings& s,
                       double threshold_force = 0);

// The contacts on each grain, in the order of `grains`: a grain–grain contact appears on
// both grains, on b with a and b swapped and the normal and force reversed (the force on b).
// Contacts naming a grain not in `grains` are skipped.
std::vector<std::vector<Contact>> contacts_by_grain(std::span<const Grain> grains, std::span<const Contact> contacts);

}  // namespace crumble
