#include "scenarios/Fidelity.h"

#include <sstream>

#include "core/Config.h"
#include "scenarios/Methods.h"
#include "scenarios/Sections.h"

namespace crumble {

using Json = nlohmann::json;

const std::vector<std::string>& fidelity_presets() {
  static const std::vector<std::string> p = {"fast", "balanced", "accurate"};
  return p;
}

// Values read off the fronts of docs/speed-accuracy.md ("accurate" is each front's reference or
// the paper's value; "balanced" the cheapest setting within a few per cent of it; "fast" the
// cheapest setting that still gives the figure within ~5–12 %).
const std::vector<FidelityKnob>& fidelity_knobs() {
  static const std::vector<FidelityKnob> t = {
      {"breakage", "peridynamics", "breakage.spacing_fraction", 0.1, 0.08, 0.062,
       "studies/pd_spacing.json: crushing force +4.2 % / +2.1 % / reference, wall 0.11 / 0.25 / 1 of the reference"},
      {"breakage", "peridynamics", "breakage.density_scale", 64, 16, 4,
       "studies/pd_density_scale.json: crushing force within one breakage check (2 %) of x1 at x4, x16 and x64, "
       "wall 0.43 / 0.61 / 1 of x4; x1 gives the same force as x4 at 0.062 for 5x the time"},
      {"breakage", "peridynamics", "schedule.every_stress", 0.4e6, 0.1e6, 0.08e6,
       "studies/pd_schedule.json: crushing force +5.6 % / as 0.025 MPa / Zhu & Zhao 2019 §5, wall 0.36 / 1 / - "
       "of 0.1 MPa"},
      {"engine", "bullet", "engine.solver_iterations", 300, 1000, 3000,
       "studies/bullet_iterations.json: void ratio at 5 MPa -11 % / -0.02 % / reference, wall 0.26 / 0.54 / 1; "
       "30 and fewer iterations fail the overlap guard"},
      {"engine", "ode", "engine.solver_iterations", 500, 1000, 3000,
       "studies/ode_iterations.json: void ratio at 5 MPa -9.5 % / -2.9 % / reference, wall 0.27 / 0.37 / 1; "
       "QuickStep has no early exit: 300 iterations give -17 %, 100 -49 %, 30 fail the overlap guard"},
      {"engine", "lsdem", "engine.dt_safety", 0.4, 0.2, 0.05,
       "studies/lsdem_dt_safety.json: void ratio within 5.2 % / 3.1 % / reference, wall 0.31 / 0.34 / 1 (acts "
       "when the scenario's time_step is above the bound)"},
  };
  return t;
}

const Json& fidelity_value(const FidelityKnob& knob, const std::string& preset) {
  if (preset == "fast") return knob.fast;
  if (preset == "balanced") return knob.balanced;
  return knob.accurate;
}

namespace {

// The registry name a section selects: its "type", or `def` when the section or its type is
// absent; empty when the section is malformed (the scenario factory reports that).
std::string selected(const Json& doc, const std::string& section, const std::string& def) {
  if (!doc.contains(section)) return def;
  const Json& s = doc[section];
  if (!s.is_object()) return "";
  if (!s.contains("type")) return def;
  return s["type"].is_string() ? s["type"].get<std::string>() : "";
}

}  // namespace

PresetReport apply_fidelity_report(Json& doc, const PresetReport& method) {
  PresetReport r;
  if (!doc.is_object() || !doc.contains("fidelity")) return r;
  const Json& f = doc["fidelity"];
  std::string known;
  for (const auto& p : fidelity_presets()) known += (known.empty() ? "" : ", ") + p;
  if (!f.is_string())
    throw ConfigError("/fidelity", "expected a string, one of: " + known + " (docs/speed-accuracy.md)");
  const std::string preset = f.get<std::string>();
  bool ok = false;
  for (const auto& p : fidelity_presets()) ok = ok || p == preset;
  if (!ok)
    throw ConfigError("/fidelity", "unknown preset '" + preset + "'; expected one of: " + known +
                                       " (docs/speed-accuracy.md), or leave 'fidelity' out");
  r.name = preset;
  const int dim = doc.contains("dimension") && doc["dimension"].is_number() && doc["dimension"].get<double>() == 2 ? 2 : 3;
  const DefaultImplementations& def = default_implementations(dim);
  const std::string engine = selected(doc, "engine", def.engine);
  const std::string breakage = selected(doc, "breakage", def.breakage);
  const std::string fragments =
      breakage != "none" || doc.contains("fragments") ? selected(doc, "fragments", def.fragments) : "";
  for (const auto& k : fidelity_knobs()) {
    const std::string& active = k.seam == "engine" ? engine : k.seam == "breakage" ? breakage : fragments;
    if (active.empty() || active != k.implementation) continue;
    ++r.governed;
    // Explicit values (and the method's) win; a non-object on the way is the factory's to report.
    if (fill_missing(doc, k.path, fidelity_value(k, preset))) {
      r.set.push_back(k.path + "=" + fidelity_value(k, preset).dump());
      continue;
    }
    bool by_method = false;
    for (const auto& s : method.set) by_method = by_method || s.rfind(k.path + "=", 0) == 0;
    (by_method ? r.left_by_method : r.left).push_back(k.path);
  }
  return r;
}

std::vector<std::string> apply_fidelity(Json& doc) { return apply_fidelity_report(doc, PresetReport{}).set; }

std::string fidelity_text() {
  std::ostringstream o;
  o << "fidelity presets (scenario key \"fidelity\": fast | balanced | accurate; a value the scenario, --set or "
       "the method gives wins; docs/speed-accuracy.md):\n";
  std::string last;
  for (const auto& k : fidelity_knobs()) {
    if (k.implementation != last) o << "  " << k.seam << " " << k.implementation << ":\n";
    last = k.implementation;
    o << "      " << k.path << " = " << k.fast.dump() << " | " << k.balanced.dump() << " | " << k.accurate.dump()
      << "   (" << k.measured << ")\n";
  }
  return o.str();
}

}  // namespace crumble
