#include "core/Screening.h"

#include <algorithm>
#include <limits>
#include <map>
#include <unordered_map>
#include <utility>

namespace crumble {

ScreeningSettings zhu_zhao_screening() {
  ScreeningSettings s;
  s.min_diameter = 0.3e-3;
  s.force_threshold = true;
  s.max_unbalanced_force_ratio = 0.02;
  s.max_unbalanced_moment_ratio = 0.2;
  s.min_contacts = 2;
  // The moment of the contact forces only, without the rolling-resistance couples: what
  // Bullet's manifold points report (normal and friction impulses), so most likely what the
  // paper computed, and what gives its quiet first 3 MPa. It flags grains that rolling
  // resistance holds still as turning: 87 % of the loaded grains at 21 MPa
  // (docs/validation.md, "The unbalanced-moment filter"; moment_couples = true counts them).
  s.moment_couples = false;
  return s;
}

ScreeningResult screen(const Grain& g, std::span<const Contact> contacts, const ScreeningSettings& s,
                       double threshold_force) {
  ScreeningResult r;
  // "Equivalent diameter >= crushing limit" (Zhu & Zhao 2019 §5): a grain of exactly the
  // limit size must pass, but cbrt(6V/π) of a 0.3 mm sphere comes out 8e-20 m below 0.3 mm;
  // compare with a relative tolerance far below any physical size difference.
  if (g.shape->equivalent_diameter() < s.min_diameter * (1.0 - 1e-12)) {
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
  if (s.force_threshold && r.max_force < threshold_force) {
    r.reason = "below_threshold";
    return r;
  }
  r.unbalanced_force_ratio = mean > 0 ? norm(sum) / mean : 0;
  // Moments about the point of fixity (the largest force). The "average magnitude of
  // moment" is taken as the mean of |x − x_fix|·|F| over the other contacts: the moment
  // each force could exert. (With the plain mean of |(x − x_fix) × F|, two nearly collinear
  // forces — a grain between two plates — give a ratio of 2 from round-off alone.)
  const Vec3 fix = contacts[imax].point;
  Vec3 msum;
  double mscale = 0;
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    if (s.moment_couples) msum += contacts[i].torque;  // rolling resistance: a couple, the same about any point
    if (i == imax) continue;
    const Vec3 arm = contacts[i].point - fix;
    msum += cross(arm, contacts[i].force);
    mscale += norm(arm) * norm(contacts[i].force);
  }
  mscale /= static_cast<double>(contacts.size() - 1);
  r.unbalanced_moment_ratio = mscale > 0 ? norm(msum) / mscale : 0;
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

std::vector<std::pair<const char*, long>> ScreeningCounts::items() const {
  return {{"too_small", too_small},         {"few_contacts", few_contacts},
          {"below_threshold", below_threshold}, {"unbalanced_force", unbalanced_force},
          {"unbalanced_moment", unbalanced_moment}, {"selected", selected}};
}

long* ScreeningCounts::find(std::string_view reason) {
  if (reason == "too_small") return &too_small;
  if (reason == "few_contacts") return &few_contacts;
  if (reason == "below_threshold") return &below_threshold;
  if (reason == "unbalanced_force") return &unbalanced_force;
  if (reason == "unbalanced_moment") return &unbalanced_moment;
  if (reason == "selected") return &selected;
  return nullptr;
}

void ScreeningCounts::add(const ScreeningResult& r) {
  if (long* c = find(r.reason)) ++*c;
}

const OptionTable& screening_options() {
  using S = ScreeningSettings;
  static const OptionTable t = [] {
    const double inf = std::numeric_limits<double>::infinity();
    const std::string model = "the breakage model's";
    return OptionTable{
        opt::number("min_diameter", &S::min_diameter, 0, inf, "m", "smaller grains are never analysed")
            .depends(model),
        opt::boolean("force_threshold", &S::force_threshold,
                     "a grain is analysed only when its largest contact force reaches the model's threshold")
            .depends(model),
        opt::number("max_unbalanced_force_ratio", &S::max_unbalanced_force_ratio, -inf, inf, "",
                    "|Σ F| / Σ |F| of the grain's contacts at most this (≤ 0 disables)")
            .depends(model),
        opt::number("max_unbalanced_moment_ratio", &S::max_unbalanced_moment_ratio, -inf, inf, "",
                    "|Σ M| / Σ |M| at most this (≤ 0 disables)")
            .depends(model),
        opt::integer("min_contacts", &S::min_contacts, 1, std::numeric_limits<long>::max(),
                     "fewer contacts: not analysed")
            .depends(model),
        opt::boolean("moment_couples", &S::moment_couples,
                     "the contacts' couples (rolling resistance) count in the unbalanced moment; false: the moments "
                     "of the contact forces only")
            .depends(model),
        opt::number("skip_intact_tolerance", &S::skip_intact_tolerance, 0, 10, "",
                    "a grain whose last analysis left it whole is not analysed again while no contact partner's force "
                    "on it (per partner, body frame) changed by more than this fraction of that analysis's largest "
                    "force; 0 = analyse at every check (not in Zhu & Zhao 2019: docs/performance.md, \"Fewer "
                    "analyses\")")
            .depends("the breakage model's: 0 (off) for every built-in model"),
    };
  }();
  return t;
}

std::vector<PartnerForce> partner_forces(const Grain& g, std::span<const Contact> contacts) {
  std::map<GrainId, Vec3> sum;
  for (const auto& c : contacts) sum[partner_key(c)] += c.force;
  const Quat to_body = g.orientation.normalized().conjugate();
  std::vector<PartnerForce> r;
  r.reserve(sum.size());
  for (const auto& [k, f] : sum) r.push_back({k, to_body.rotate(f)});
  return r;
}

double load_change(std::span<const PartnerForce> then, std::span<const PartnerForce> now) {
  double fmax = 0;
  for (const auto& p : then) fmax = std::max(fmax, norm(p.force));
  if (!(fmax > 0)) return std::numeric_limits<double>::infinity();
  // Both lists are sorted by partner: merge them.
  double change = 0;
  std::size_t i = 0, j = 0;
  while (i < then.size() || j < now.size()) {
    Vec3 d;
    if (j == now.size() || (i < then.size() && then[i].partner < now[j].partner)) {
      d = then[i++].force;  // a partner lost since
    } else if (i == then.size() || now[j].partner < then[i].partner) {
      d = now[j++].force;  // a new partner
    } else {
      d = now[j++].force - then[i++].force;
    }
    change = std::max(change, norm(d));
  }
  const double r = change / fmax;
  return std::isfinite(r) ? r : std::numeric_limits<double>::infinity();
}

bool skip_analysis(const Grain& g, std::span<const PartnerForce> now, const ScreeningSettings& s) {
  if (!(s.skip_intact_tolerance > 0) || g.intact_load.empty()) return false;
  return load_change(g.intact_load, now) <= s.skip_intact_tolerance;
}

std::vector<std::vector<Contact>> contacts_by_grain(std::span<const Grain> grains, std::span<const Contact> contacts) {
  std::unordered_map<GrainId, std::size_t> index;
  for (std::size_t i = 0; i < grains.size(); ++i) index[grains[i].id] = i;
  std::vector<std::vector<Contact>> on(grains.size());
  for (const auto& c : contacts) {
    auto ia = index.find(c.a);
    if (ia != index.end()) on[ia->second].push_back(c);
    if (!c.is_wall()) {
      auto ib = index.find(c.b);
      if (ib != index.end()) {
        Contact r = c;
        std::swap(r.a, r.b);
        r.normal = -c.normal;
        r.force = -c.force;
        r.torque = -c.torque;
        on[ib->second].push_back(r);
      }
    }
  }
  return on;
}

}  // namespace crumble
