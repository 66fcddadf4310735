// Which grains are worth a breakage analysis (seeds/000 §3.1, §5).
#pragma once
#include <span>
#include <vector>

#include "core/Contact.h"
#include "core/Grain.h"

namespace crumble {

struct ScreeningSettings {
  double min_diameter = 0.3e-3;            // crushing limit, m (seeds/000 §5)
  bool force_threshold = true;             // require max |F| >= grain's threshold_force
  double max_unbalanced_force_ratio = 0.02;   // <= 0 disables
  double max_unbalanced_moment_ratio = 0.2;   // <= 0 disables
  int min_contacts = 2;
};

struct ScreeningResult {
  bool selected = false;
  const char* reason = "";  // why not: too_small, no_contacts, below_threshold, unbalanced_force, ...
  double max_force = 0;
  double unbalanced_force_ratio = 0;
  double unbalanced_moment_ratio = 0;
};

// `contacts` are the contacts on `g` (force on g). seeds/000 §5: unbalanced force ratio =
// |Σ F| / mean |F|; unbalanced moment ratio = |Σ (x − x_fix) × F| / mean |x − x_fix|·|F|
// about the point of the largest force (the zone a peridynamic analysis fixes) — the paper
// says "average magnitude of moment"; see Screening.cpp for why the lever-arm form. Gravity
// is left out: at the forces that break grains it is < 1e-4 of them.
ScreeningResult screen(const Grain& g, std::span<const Contact> contacts, const ScreeningSettings& s);

}  // namespace crumble
