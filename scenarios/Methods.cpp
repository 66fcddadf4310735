#include "scenarios/Methods.h"

#include <sstream>
#include <stdexcept>

#include "core/Config.h"

namespace crumble {

using Json = nlohmann::json;

namespace {

bool valid_path(const std::string& path) {
  if (path.empty() || path.front() == '.' || path.back() == '.') return false;
  return path.find("..") == std::string::npos;
}

// Zhu & Zhao 2019: Bullet with mass scaling and a fixed 2000 solver sweeps, peridynamics,
// alpha-shape fragments, the stress-level time steps, a check every 0.08 MPa, and the
// screening of §5 (crushing limit, force threshold, unbalanced ratios).
Method zhu_zhao_2019() {
  const Json steps = Json::array({{{"below_stress", 10e6}, {"dt", 8e-5}},
                                  {{"below_stress", 24e6}, {"dt", 6e-5}},
                                  {{"below_stress", 1e300}, {"dt", 5e-5}}});
  return {"zhu_zhao_2019",
          "Zhu & Zhao 2019: Bullet + peridynamics + alpha-shape fragments",
          {{"engine.type", "bullet", "Zhu & Zhao 2019 §2.2"},
           {"engine.mass_scale", 70, "Zhu & Zhao 2019 §5"},
           {"engine.solver_iterations", 2000, "Zhu & Zhao 2019 §2.2"},
           {"engine.solver_tolerance", 0.0, "Zhu & Zhao 2019 §2.2: every sweep, no early exit"},
           {"breakage.type", "peridynamics", "Zhu & Zhao 2019 §2.1"},
           {"fragments.type", "alpha_shape", "Zhu & Zhao 2019 §3.2"},
           {"time_step", steps, "Zhu & Zhao 2019 §5: 8e-5 / 6e-5 / 5e-5 s below 10 / 24 MPa / above"},
           {"schedule.every_stress", 0.08e6, "Zhu & Zhao 2019 §5"},
           {"screening.min_diameter", 0.3e-3, "Zhu & Zhao 2019 §5: crushing limit"},
           {"screening.force_threshold", true, "Zhu & Zhao 2019 §5, eqs. 12/14"},
           {"screening.max_unbalanced_force_ratio", 0.02, "Zhu & Zhao 2019 §5"},
           {"screening.max_unbalanced_moment_ratio", 0.2, "Zhu & Zhao 2019 §5"}}};
}

// Harmon et al. 2020: level-set DEM (its time step is the engine's stable step, Δt ∝
// √(m_min/k_n), Appendix), the average-stress criteria, level-set splitting; every grain with
// contacts is analysed, no force or balance filter.
Method harmon_2020() {
  return {"harmon_2020",
          "Harmon et al. 2020: level-set DEM + average-stress criterion + level-set splitting",
          {{"engine.type", "lsdem", "Harmon et al. 2020 §2"},
           {"breakage.type", "stress", "Harmon et al. 2020 §3.1, eqs. 5–13"},
           {"fragments.type", "level_set", "Harmon et al. 2020 §3.2, eqs. 14–17"},
           {"schedule.every_steps", 100,
            "crumble's: the paper checks every step; every 100 steps is the stress model's own schedule"},
           {"screening.min_diameter", 0.0, "Harmon et al. 2020 §3: no crushing limit (fines leave by "
                                         "simulation.fines_diameter)"},
           {"screening.force_threshold", false, "Harmon et al. 2020 §3.1: the criterion alone decides"},
           {"screening.max_unbalanced_force_ratio", 0.0, "Harmon et al. 2020 §3.1: no balance filter"},
           {"screening.max_unbalanced_moment_ratio", 0.0, "Harmon et al. 2020 §3.1: no balance filter"}}};
}

}  // namespace

void MethodTable::add(Method m) {
  if (m.name.empty()) throw std::invalid_argument("a method needs a name");
  if (find(m.name)) throw std::invalid_argument("method '" + m.name + "' is registered twice");
  for (const auto& s : m.settings)
    if (!valid_path(s.path))
      throw std::invalid_argument("method '" + m.name + "': '" + s.path + "' is not a dotted scenario path");
  entries_.push_back(std::move(m));
}

const Method* MethodTable::find(const std::string& name) const {
  for (const auto& m : entries_)
    if (m.name == name) return &m;
  return nullptr;
}

std::string MethodTable::names() const {
  std::string s;
  for (const auto& m : entries_) s += (s.empty() ? "" : ", ") + m.name;
  return s;
}

MethodTable& methods() {
  static MethodTable t = [] {
    MethodTable t;
    t.add(zhu_zhao_2019());
    t.add(harmon_2020());
    return t;
  }();
  return t;
}

bool fill_missing(Json& doc, const std::string& path, const Json& value) {
  Json* node = &doc;
  std::size_t a = 0;
  while (true) {
    const std::size_t b = path.find('.', a);
    const std::string key = path.substr(a, b == std::string::npos ? std::string::npos : b - a);
    if (!node->is_object()) return false;
    if (b == std::string::npos) {
      if (node->contains(key)) return false;
      (*node)[key] = value;
      return true;
    }
    if (!node->contains(key)) (*node)[key] = Json::object();
    if (!(*node)[key].is_object()) return false;
    node = &(*node)[key];
    a = b + 1;
  }
}

PresetReport apply_method(Json& doc) {
  PresetReport r;
  if (!doc.is_object() || !doc.contains("method")) return r;
  const Json& v = doc["method"];
  const std::string known = methods().names();
  if (!v.is_string()) throw ConfigError("/method", "expected a string, one of: " + known + " (crumble list)");
  const Method* m = methods().find(v.get<std::string>());
  if (!m)
    throw ConfigError("/method", "unknown method '" + v.get<std::string>() + "'; expected one of: " + known +
                                     " (crumble list), or leave 'method' out");
  r.name = m->name;
  for (const auto& s : m->settings) {
    ++r.governed;
    if (fill_missing(doc, s.path, s.value)) r.set.push_back(s.path + "=" + s.value.dump());
    else r.left.push_back(s.path);
  }
  return r;
}

std::string methods_text() {
  std::ostringstream o;
  o << "methods (scenario key \"method\"; a value the scenario or --set gives wins):\n";
  for (const auto& m : methods().entries()) {
    o << "  " << m.name << " — " << m.description << "\n";
    for (const auto& s : m.settings) o << "      " << s.path << " = " << s.value.dump() << "   (" << s.source << ")\n";
  }
  return o.str();
}

}  // namespace crumble
