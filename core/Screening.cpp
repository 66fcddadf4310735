#include "core/Screening.h"

#include <algorithm>

namespace crumble {

ScreeningResult screen(const Grain& g, std::span<const Contact> contacts, const ScreeningSettings& s) {
  ScreeningResult r;
  if (g.shape->equivalent_diameter() < s.min_diameter) {
    r.reason = "too_small";
    return r;
  }
  if (contacts.size() < static_cast<std::size_t>(std::max(1, s.min_contacts))) {
    r.reason = "few_contacts";
    return r;
  }
  Vec3 sum;
  double mean = 0;
  std::size_t imax = 0;
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const double f = norm(contacts[i].force);
    sum += contacts[i].force;
    mean += f;
    if (f > r.max_force) {
      r.max_force = f;
      imax = i;
    }
  }
  mean /= static_cast<double>(contacts.size());
  if (s.force_threshold && r.max_force < g.strength.threshold_force) {
    r.reason = "below_threshold";
    return r;
  }
  r.unbalanced_force_ratio = mean > 0 ? norm(sum) / mean : 0;
  const Vec3 fix = contacts[imax].point;
  Vec3 msum;
  double mmean = 0;
  for (const auto& c : contacts) {
    const Vec3 m = cross(c.point - fix, c.force);
    msum += m;
    mmean += norm(m);
  }
  mmean /= static_cast<double>(contacts.size());
  r.unbalanced_moment_ratio = mmean > 0 ? norm(msum) / mmean : 0;
  if (s.max_unbalanced_force_ratio > 0 && r.unbalanced_force_ratio > s.max_unbalanced_force_ratio) {
    r.reason = "unbalanced_force";
    return r;
  }
  if (s.max_unbalanced_moment_ratio > 0 && r.unbalanced_moment_ratio > s.max_unbalanced_moment_ratio) {
    r.reason = "unbalanced_moment";
    return r;
  }
  r.selected = true;
  r.reason = "selected";
  return r;
}

}  // namespace crumble
