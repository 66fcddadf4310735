#include "tools/Metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "base/Format.h"
#include "output/Recorders.h"
#include "tools/Compare.h"
#include "run/RunPipeline.h"
#include "output/Writers.h"

namespace crumble {

namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

std::optional<double> summary_number(const Json& s, const std::string& key) {
  if (!s.is_object() || !s.contains(key) || !s[key].is_number()) return std::nullopt;
  const double v = s[key].get<double>();
  if (!std::isfinite(v)) return std::nullopt;
  return v;
}

// A metric that is one summary.json figure.
template <const char* Key>
std::optional<double> from_summary(const RunOutputs& r, const std::string&) {
  return summary_number(r.summary, Key);
}

constexpr char kCrushingForce[] = "crushing_force_N";
constexpr char kStrength[] = "characteristic_strength_Pa";
constexpr char kCrushingStress[] = "crushing_stress_Pa";
constexpr char kGrainsFinal[] = "grains_final";
constexpr char kEvents[] = "breakage_events";
constexpr char kD50[] = "psd_d50_final_m";
constexpr char kFines[] = "fines_fraction_final";
constexpr char kVoidFinal[] = "void_ratio_final";
constexpr char kFractal[] = "fractal_dimension_final";
constexpr char kNcl[] = "ncl_loglog_slope";
constexpr char kCircularity[] = "mean_circularity_final";
constexpr char kSphericity[] = "mean_sphericity_final";
constexpr char kProductD50[] = "product_d50_m";
constexpr char kCompressionIndex[] = "ncl_compression_index";
constexpr char kRelativeBreakage[] = "relative_breakage_final";
constexpr char kK0[] = "k0_final";
constexpr char kUniformity[] = "psd_uniformity_final";

std::size_t column(const std::vector<std::string>& header, const std::string& name) {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return i;
  return header.size();
}

// The platen stress of the first events.csv row that is a breakage (it has children or
// removed fines; an analysis that left the grain whole has neither, as EventsWriter counts).
std::optional<double> first_breakage_stress(const RunOutputs& r, const std::string&) {
  if (r.events.empty()) return std::nullopt;
  const auto& h = r.events[0];
  const std::size_t st = column(h, "platen_stress_Pa"), ch = column(h, "children"), rm = column(h, "removed_volume_m3");
  if (st == h.size() || ch == h.size() || rm == h.size()) return std::nullopt;
  for (std::size_t i = 1; i < r.events.size(); ++i) {
    const auto& row = r.events[i];
    if (row.size() <= std::max({st, ch, rm})) continue;
    if (std::atof(row[ch].c_str()) > 0 || std::atof(row[rm].c_str()) > 0) {
      const double v = std::atof(row[st].c_str());
      if (std::isfinite(v)) return v;
    }
  }
  return std::nullopt;
}

// The children's volumes of the first events.csv row that has children (child_volumes_m3,
// ';'-separated): what a fragment builder made of the first fracture.
std::vector<double> first_children_volumes(const RunOutputs& r) {
  if (r.events.empty()) return {};
  const auto& h = r.events[0];
  const std::size_t ch = column(h, "children"), vol = column(h, "child_volumes_m3");
  if (ch == h.size() || vol == h.size()) return {};
  for (std::size_t i = 1; i < r.events.size(); ++i) {
    const auto& row = r.events[i];
    if (row.size() <= std::max(ch, vol) || !(std::atof(row[ch].c_str()) > 0)) continue;
    std::vector<double> v;
    std::size_t a = 0;
    const std::string& cell = row[vol];
    while (a <= cell.size()) {
      const std::size_t b = std::min(cell.find(';', a), cell.size());
      if (b > a) {
        const double x = std::atof(cell.substr(a, b - a).c_str());
        if (std::isfinite(x) && x > 0) v.push_back(x);
      }
      a = b + 1;
    }
    return v;
  }
  return {};
}

std::optional<double> largest_fragment_volume(const RunOutputs& r, const std::string&) {
  const auto v = first_children_volumes(r);
  if (v.empty()) return std::nullopt;
  return *std::max_element(v.begin(), v.end());
}

std::optional<double> smallest_fragment_volume(const RunOutputs& r, const std::string&) {
  const auto v = first_children_volumes(r);
  if (v.empty()) return std::nullopt;
  return *std::min_element(v.begin(), v.end());
}

// A level written in a metric's name: a finite number >= 0, or NaN.
double parse_level(const std::string& rest) {
  if (rest.empty()) return std::nan("");
  char* end = nullptr;
  const double v = std::strtod(rest.c_str(), &end);
  if (end != rest.c_str() + rest.size() || !std::isfinite(v) || v < 0) return std::nan("");
  return v;
}

// void_ratio_at_stress_<Pa>[_Pa] / void_ratio_at_strain_<value>: the level's value, or NaN
// when NAME is not of the family.
double level_of(const std::string& name, bool& stress) {
  static const std::string s = "void_ratio_at_stress_", e = "void_ratio_at_strain_";
  std::string rest;
  if (name.rfind(s, 0) == 0) {
    stress = true;
    rest = name.substr(s.size());
    if (rest.size() > 3 && rest.compare(rest.size() - 3, 3, "_Pa") == 0) rest.resize(rest.size() - 3);
  } else if (name.rfind(e, 0) == 0) {
    stress = false;
    rest = name.substr(e.size());
  } else {
    return std::nan("");
  }
  return parse_level(rest);
}

// breakage_events_at_stress_<Pa>: the level, or NaN when NAME is not of the family.
constexpr char kEventsAtStress[] = "breakage_events_at_stress_";
double events_level_of(const std::string& name) {
  const std::string p = kEventsAtStress;
  return name.rfind(p, 0) == 0 ? parse_level(name.substr(p.size())) : std::nan("");
}

// The breakage rows of events.csv (children or removed fines) before the first row whose
// platen stress reaches the level; nothing when the run never reached it (summary.json has
// no void ratio there).
std::optional<double> events_at_level(const RunOutputs& r, const std::string& name) {
  const double level = events_level_of(name);
  if (!std::isfinite(level) || !summary_number(r.summary, void_ratio_stress_key(level))) return std::nullopt;
  if (r.events.empty()) return 0.0;
  const auto& h = r.events[0];
  const std::size_t st = column(h, "platen_stress_Pa"), ch = column(h, "children"), rm = column(h, "removed_volume_m3");
  if (st == h.size() || ch == h.size() || rm == h.size()) return std::nullopt;
  double n = 0;
  for (std::size_t i = 1; i < r.events.size(); ++i) {
    const auto& row = r.events[i];
    if (row.size() <= std::max({st, ch, rm})) continue;
    if (std::atof(row[st].c_str()) >= level) break;
    if (std::atof(row[ch].c_str()) > 0 || std::atof(row[rm].c_str()) > 0) ++n;
  }
  return n;
}

std::optional<double> void_ratio_at_level(const RunOutputs& r, const std::string& name) {
  bool stress = true;
  const double level = level_of(name, stress);
  if (!std::isfinite(level)) return std::nullopt;
  return summary_number(r.summary, stress ? void_ratio_stress_key(level) : void_ratio_strain_key(level));
}

Metric level_metric(double level, bool stress) {
  Metric m;
  m.name = stress ? "void_ratio_at_stress_" + fmt_num(level) : "void_ratio_at_strain_" + fmt_num(level);
  m.unit = "1";
  m.description = stress ? "void ratio where the platen stress first reaches " + fmt_num(level) +
                               " Pa (interpolated between the series samples around it)"
                         : "void ratio where the axial strain first reaches " + fmt_num(level) +
                               " (interpolated between the series samples around it)";
  m.value = &void_ratio_at_level;
  return m;
}

}  // namespace

RunOutputs read_run_outputs(const std::string& dir) {
  RunOutputs r;
  {
    std::ifstream in(fs::path(dir) / "summary.json");
    if (in) {
      try {
        r.summary = Json::parse(in);
      } catch (const std::exception&) {
        r.summary = nullptr;
      }
    }
  }
  const fs::path ev = fs::path(dir) / "events.csv";
  std::error_code ec;
  if (fs::exists(ev, ec)) r.events = read_breakage_rows(ev.string());
  return r;
}

const std::vector<Metric>& metrics() {
  static const std::vector<Metric> table = {
      {"crushing_force", "N",
       "single grain: force at which the grain broke (Zhu & Zhao 2019 §4.2; summary crushing_force_N)",
       &from_summary<kCrushingForce>},
      {"characteristic_strength", "Pa", "single grain: crushing force / d² (Zhu & Zhao 2019, Fig. 9)",
       &from_summary<kStrength>},
      {"crushing_stress", "Pa",
       "single grain, stress models: equivalent average stress at failure (Harmon et al. 2020, eqs. 5-10)",
       &from_summary<kCrushingStress>},
      {"first_breakage_stress", "Pa", "platen stress at the first breakage (events.csv)", &first_breakage_stress},
      {"grains_final", "1", "grains in the engine at the end", &from_summary<kGrainsFinal>},
      {"breakage_events", "1", "breakage events", &from_summary<kEvents>},
      {"psd_d50", "m", "mass median size of the final grains (removed fines at size 0)", &from_summary<kD50>},
      {"fines_fraction", "1", "mass fraction of removed fines and grains finer than fines_size_m",
       &from_summary<kFines>},
      {"void_ratio_final", "1", "void ratio at the end", &from_summary<kVoidFinal>},
      {"fractal_dimension", "1", "fractal dimension of the final sizes (Zhu & Zhao 2019 §5)",
       &from_summary<kFractal>},
      {"ncl_slope", "1", "slope of log e against log stress over the upper loading (Zhu & Zhao 2019 §5)",
       &from_summary<kNcl>},
      {"mean_circularity_final", "1", "2D: mean circularity of the final grains (Harmon et al. 2020 §5)",
       &from_summary<kCircularity>},
      {"mean_sphericity_final", "1", "3D: mean sphericity of the final grains", &from_summary<kSphericity>},
      {"largest_fragment_volume", "m3",
       "volume of the largest child of the first breakage (events.csv child_volumes_m3)", &largest_fragment_volume},
      {"smallest_fragment_volume", "m3",
       "volume of the smallest child of the first breakage (events.csv child_volumes_m3)", &smallest_fragment_volume},
      {"product_d50", "m", "jaw crusher: mass median sieve size of the product", &from_summary<kProductD50>},
      {"compression_index", "1", "C_c = -de/dlog10(stress) over the upper loading (e - log stress line)",
       &from_summary<kCompressionIndex>},
      {"relative_breakage", "1", "Hardin (1985) relative breakage B_r of the final PSD against the initial one",
       &from_summary<kRelativeBreakage>},
      {"k0", "1", "lateral stress ratio sigma_h/sigma_v from the side-wall forces at the end",
       &from_summary<kK0>},
      {"psd_uniformity", "1", "uniformity coefficient d60/d10 of the final PSD by mass", &from_summary<kUniformity>},
  };
  return table;
}

Metric find_metric(const std::string& name, const std::string& where) {
  for (const auto& m : metrics())
    if (m.name == name) return m;
  bool stress = true;
  const double level = level_of(name, stress);
  if (std::isfinite(level)) return level_metric(level, stress);
  const double ev = events_level_of(name);
  if (std::isfinite(ev))
    return Metric{kEventsAtStress + fmt_num(ev), "1",
                  "breakage events before the platen stress first reaches " + fmt_num(ev) +
                      " Pa (a level in output.psd_at_stress)",
                  &events_at_level};
  std::string known;
  for (const auto& m : metrics()) known += (known.empty() ? "" : ", ") + m.name + " (" + m.unit + ")";
  throw InputError(where + ": unknown metric '" + name + "'; known: " + known +
                   ", void_ratio_at_stress_<Pa> (e.g. void_ratio_at_stress_1e6) and void_ratio_at_strain_<value> "
                   "(e.g. void_ratio_at_strain_0.05) for a level the scenario reports (output.psd_at_stress, "
                   "output.psd_at_strain), and breakage_events_at_stress_<Pa> for a level in output.psd_at_stress");
}

std::vector<Metric> available_metrics(const RunOutputs& run) {
  std::vector<Metric> out;
  for (const auto& m : metrics())
    if (m.value(run, m.name)) out.push_back(m);
  if (!run.summary.is_object()) return out;
  std::vector<std::pair<std::pair<int, double>, Metric>> levels;
  for (auto it = run.summary.begin(); it != run.summary.end(); ++it) {
    bool stress = true;
    const double level = level_of(it.key(), stress);
    if (std::isfinite(level) && it->is_number()) levels.push_back({{stress ? 0 : 1, level}, level_metric(level, stress)});
  }
  std::sort(levels.begin(), levels.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (auto& l : levels) out.push_back(l.second);
  return out;
}

std::optional<double> relative_error(std::optional<double> value, std::optional<double> reference) {
  if (!value || !reference || *reference == 0) return std::nullopt;
  return std::abs(*value - *reference) / std::abs(*reference);
}

}  // namespace crumble
