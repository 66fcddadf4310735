// Which grains are worth a breakage analysis. The rule is Zhu & Zhao's (2019, §3.1, §5):
// a size limit, a force threshold, a minimum number of contacts and balance of forces and
// moments. Each breakage model chooses its defaults (BreakageModel::default_screening);
// the struct's own defaults switch every rule off but the contact count.
#pragma once
#include <span>
#include <string_view>
#include <utility>
#include <vector>

#include "core/Contact.h"
#include "core/Grain.h"
#include "core/Options.h"

namespace crumble {

struct ScreeningSettings {
  double min_diameter = 0;                 // m: smaller grains are never analysed
  bool force_threshold = true;             // require max |F| >= the model's threshold_force(grain)
  double max_unbalanced_force_ratio = 0;   // <= 0 disables
  double max_unbalanced_moment_ratio = 0;  // <= 0 disables
  // Count the contacts' couples (Contact::torque: rolling resistance) in the unbalanced
  // moment. false: the moments of the contact forces only (Zhu & Zhao's default, see
  // zhu_zhao_screening; a grain held by rolling resistance then reads as turning).
  bool moment_couples = true;
  int min_contacts = 1;
  // Skip rule (crumble's, not Zhu & Zhao's): a grain that passes the rules above but whose
  // last analysis left it whole is not analysed again while the force of every contact
  // partner on it (summed per partner, body frame) differs from that analysis's by at most
  // this fraction of the analysis's largest partner force. A deterministic analysis of an
  // unchanged load gives the same verdict; the tolerance bounds the change it may miss
  // (the largest force may grow by this fraction; a new partner may bring up to it; a force
  // of the largest magnitude may turn by about this many radians). <= 0: analyse at every check.
  double skip_intact_tolerance = 0;
};

// The options of the "screening" object declared in a table (the rest is read by the
// scenario factory): skip_intact_tolerance, whose default is the breakage model's.
const OptionTable& screening_options();

// Zhu & Zhao 2019, §5: crushing limit 0.3 mm, unbalanced-force ratio <= 0.02,
// unbalanced-moment ratio <= 0.2 (of the contact forces' moments only: moment_couples
// false), at least two contacts, force threshold on.
ScreeningSettings zhu_zhao_screening();

struct ScreeningResult {
  bool selected = false;
  const char* reason = "";  // why not: too_small, few_contacts, below_threshold, unbalanced_force, ...
  double max_force = 0;
  double unbalanced_force_ratio = 0;
  double unbalanced_moment_ratio = 0;
};

// Grain checks per screening outcome, over a run (summary.json screening_<reason>; a
// checkpoint keeps them): which rule turned grains away, and how many it let through.
struct ScreeningCounts {
  long too_small = 0, few_contacts = 0, below_threshold = 0, unbalanced_force = 0, unbalanced_moment = 0;
  long selected = 0;  // passed every rule (the skip rule may still spare the analysis)
  void add(const ScreeningResult& r);
  // (reason, count) in the order of the rules.
  std::vector<std::pair<const char*, long>> items() const;
  long* find(std::string_view reason);
};

// `contacts` are the contacts on `g` (force on g). Zhu & Zhao 2019 §5: unbalanced force ratio =
// |Σ F| / mean |F|; unbalanced moment ratio = |Σ (x − x_fix) × F + Σ τ| / mean |x − x_fix|·|F|
// about the point of the largest force (the zone a peridynamic analysis fixes) — the paper
// says "average magnitude of moment"; see Screening.cpp for why the lever-arm form. τ are the
// contacts' couples (Contact::torque, rolling resistance): a grain that rolling resistance
// holds still is not in motion, and leaving them out flagged most loaded grains of a packing
// as moving (docs/validation.md, "The unbalanced-moment filter"). Gravity
// is left out: at the forces that break grains it is < 1e-4 of them. `threshold_force` (N)
// is the model's screening force for g (BreakageModel::threshold_force).
ScreeningResult screen(const Grain& g, std::span<const Contact> contacts, const ScreeningSettings& s,
                       double threshold_force = 0);

// The key of a contact's partner in Grain::intact_load: the other grain's id, or -1 - wall.
inline GrainId partner_key(const Contact& c) { return c.is_wall() ? -1 - static_cast<GrainId>(c.wall) : c.b; }

// The load on `g` (contacts: forces on g, world frame) per partner, summed over each partner's
// contact points and turned into g's body frame, in increasing partner order.
std::vector<PartnerForce> partner_forces(const Grain& g, std::span<const Contact> contacts);

// max over partners |F_now − F_then| / max over partners |F_then| (a partner missing on one
// side counts with zero force); infinity when `then` is empty or carries no force.
double load_change(std::span<const PartnerForce> then, std::span<const PartnerForce> now);

// The skip rule: true when g's last analysis left it whole and its load `now` (partner_forces)
// changed by at most s.skip_intact_tolerance since (load_change). False when the rule is off.
bool skip_analysis(const Grain& g, std::span<const PartnerForce> now, const ScreeningSettings& s);

// The contacts on each grain, in the order of `grains`: a grain–grain contact appears on
// both grains, on b with a and b swapped and the normal and force reversed (the force on b).
// Contacts naming a grain not in `grains` are skipped.
std::vector<std::vector<Contact>> contacts_by_grain(std::span<const Grain> grains, std::span<const Contact> contacts);

}  // namespace crumble
