#include "tools/Compare.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include "base/Format.h"
#include "output/Plots.h"
#include "output/Recorders.h"
#include "run/RunPipeline.h"
#include "run/ThreadCheck.h"
#include "tools/TableCells.h"
#include "output/OutputReference.h"
#include "output/Writers.h"

namespace crumble {

namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  const auto b = s.find_last_not_of(" \t");
  return s.substr(a, b - a + 1);
}

}  // namespace

VaryAxis parse_vary(const std::string& arg) {
  const std::string where = "--vary " + arg;
  const std::string usage = "expected path=value1,value2,... (e.g. engine.type=bullet,lsdem,ode)";
  const auto eq = arg.find('=');
  if (eq == std::string::npos) throw InputError(where + ": no '=': " + usage);
  VaryAxis ax;
  ax.arg = arg;
  ax.path = trim(arg.substr(0, eq));
  if (ax.path.empty()) throw InputError(where + ": empty path: " + usage);
  std::size_t start = 0;
  while (true) {
    const auto dot = ax.path.find('.', start);
    if (ax.path.substr(start, dot == std::string::npos ? std::string::npos : dot - start).empty())
      throw InputError(where + ": empty component in the path '" + ax.path + "': " + usage);
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  const std::string list = arg.substr(eq + 1);
  if (trim(list).empty()) throw InputError(where + ": empty value list: " + usage);
  // Split at commas outside [], {} and "" (a JSON array or object may be one value).
  int depth = 0;
  bool quoted = false;
  std::string cur;
  std::vector<std::string> vals;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const char c = list[i];
    if (quoted) {
      if (c == '\\' && i + 1 < list.size()) {
        cur += c;
        cur += list[++i];
        continue;
      }
      if (c == '"') quoted = false;
    } else if (c == '"') {
      quoted = true;
    } else if (c == '[' || c == '{') {
      ++depth;
    } else if (c == ']' || c == '}') {
      --depth;
    } else if (c == ',' && depth == 0) {
      vals.push_back(trim(cur));
      cur.clear();
      continue;
    }
    cur += c;
  }
  vals.push_back(trim(cur));
  std::set<std::string> seen;
  for (std::size_t i = 0; i < vals.size(); ++i) {
    if (vals[i].empty())
      throw InputError(where + ": value " + std::to_string(i + 1) + " of " + std::to_string(vals.size()) +
                       " is empty: " + usage);
    if (!seen.insert(vals[i]).second)
      throw InputError(where + ": the value '" + vals[i] + "' is given twice (each combination runs once)");
  }
  ax.values = vals;
  return ax;
}

std::vector<std::string> Combination::sets() const {
  std::vector<std::string> s;
  for (const auto& [p, v] : values) s.push_back(p + "=" + v);
  return s;
}

std::string Combination::label() const {
  std::string s;
  for (const auto& [p, v] : values) s += (s.empty() ? "" : ", ") + p + "=" + v;
  return s;
}

std::string sanitise_folder_name(const std::string& s) {
  std::string out;
  for (unsigned char c : s) out += (std::isalnum(c) || c == '.' || c == '_' || c == '=' || c == '+' || c == '-') ? static_cast<char>(c) : '_';
  if (out.size() > 200) out = out.substr(0, 200);
  return out;
}

std::vector<Combination> combinations(const std::vector<VaryAxis>& axes) {
  std::set<std::string> paths;
  for (const auto& a : axes)
    if (!paths.insert(a.path).second)
      throw InputError("--vary " + a.arg + ": the path '" + a.path +
                       "' is varied twice; give all its values in one --vary (path=value1,value2,...)");
  std::vector<Combination> out(1);
  for (const auto& a : axes) {
    std::vector<Combination> next;
    for (const auto& c : out)
      for (const auto& v : a.values) {
        Combination n = c;
        n.values.emplace_back(a.path, v);
        next.push_back(std::move(n));
      }
    out = std::move(next);
  }
  std::map<std::string, std::string> names;
  for (auto& c : out) {
    std::string name;
    for (const auto& [p, v] : c.values) name += (name.empty() ? "" : "__") + sanitise_folder_name(p + "=" + v);
    c.name = name;
    auto [it, fresh] = names.emplace(name, c.label());
    if (!fresh)
      throw InputError("--vary: the combinations " + it->second + " and " + c.label() + " share the folder name '" +
                       name + "'; give values that differ in letters, digits or ._=+-");
  }
  return out;
}

namespace {

std::string fmt(double v, int prec = 4) { return table_number(v, prec); }

double num(const Json& j, const std::string& key) {
  if (j.is_object() && j.contains(key) && j[key].is_number()) return j[key].get<double>();
  return std::nan("");
}

// void_ratio_at_stress_<Pa>_Pa, then void_ratio_at_strain_<value>, each by level.
std::vector<std::string> level_keys(const std::vector<ComparisonRow>& rows, const std::vector<std::string>& expected) {
  std::vector<std::pair<std::pair<int, double>, std::string>> keys;
  std::set<std::string> seen;
  std::vector<std::string> all = expected;
  for (const auto& r : rows) {
    if (!r.summary.is_object()) continue;
    for (auto it = r.summary.begin(); it != r.summary.end(); ++it) all.push_back(it.key());
  }
  {
    for (const auto& k : all) {
      if (k.rfind("void_ratio_at_", 0) != 0 || !seen.insert(k).second) continue;
      const bool stress = k.rfind("void_ratio_at_stress_", 0) == 0;
      const std::string rest = k.substr(stress ? 21 : std::strlen("void_ratio_at_strain_"));
      keys.push_back({{stress ? 0 : 1, std::atof(rest.c_str())}, k});
    }
  }
  std::sort(keys.begin(), keys.end());
  std::vector<std::string> out;
  for (const auto& k : keys) out.push_back(k.second);
  return out;
}

std::string level_title(const std::string& key) {
  if (key.rfind("void_ratio_at_stress_", 0) == 0) {
    const double pa = std::atof(key.substr(21).c_str());
    return "e at " + fmt_num(pa / 1e6) + " MPa";
  }
  return "e at " + fmt_num(100 * std::atof(key.substr(std::strlen("void_ratio_at_strain_")).c_str())) + " % strain";
}

// Figures some scenes report (single grain, open scenes, compression), shown when any row has them.
const std::vector<std::pair<std::string, std::string>> kOptional = {
    {"crushing_force_N", "crushing force N"},
    {"characteristic_strength_Pa", "F/d² MPa"},
    {"crushing_stress_Pa", "crushing stress MPa"},
    {"product_d50_m", "product d50 mm"},
    {"ncl_loglog_slope", "NCL slope"},
    {"relative_breakage_final", "B_r"},
    {"k0_final", "K0"}};

const std::vector<std::string>& kTimeParts = time_breakdown_parts();

}  // namespace

const std::vector<std::string>& time_breakdown_parts() {
  static const std::vector<std::string> parts = {"engine", "contacts", "screening", "analyses",
                                                 "fragments", "guards", "output"};
  return parts;
}

namespace {

using Optional = std::vector<std::pair<std::string, std::string>>;

// The optional figures (kOptional) that some row has.
Optional present_optional(const std::vector<ComparisonRow>& rows) {
  Optional optional;
  for (const auto& o : kOptional)
    for (const auto& r : rows)
      if (std::isfinite(num(r.summary, o.first))) {
        optional.push_back(o);
        break;
      }
  return optional;
}

// Part k of summary.json `time_breakdown_s`, NaN when there is none.
double time_part(const Json& s, const std::string& k) {
  return s.is_object() && s.contains("time_breakdown_s") && s["time_breakdown_s"].is_object()
             ? num(s["time_breakdown_s"], k)
             : std::nan("");
}

std::string str_field(const Json& s, const std::string& k) {
  return s.is_object() && s.contains(k) && s[k].is_string() ? s[k].get<std::string>() : std::string();
}

// comparison.csv: every figure at full precision, SI units, one row per combination.
std::string comparison_csv(const std::vector<VaryAxis>& axes, const std::vector<ComparisonRow>& rows,
                           const std::vector<std::string>& levels, const Optional& optional) {
  std::ostringstream c;
  c << std::setprecision(10);
  // The declared columns (output/OutputReference.cpp), each family expanded.
  c << csv_header("comparison.csv", "", [&](const std::string& family) {
    std::vector<std::string> names;
    if (family == "<path>")
      for (const auto& a : axes) names.push_back(csv_field(a.path));
    if (family == "void_ratio_at_<level>") names = levels;
    if (family == "<figure>")
      for (const auto& o : optional) names.push_back(o.first);
    if (family == "time_<part>_s")
      for (const auto& p : kTimeParts) names.push_back("time_" + p + "_s");
    return names;
  }) << '\n';
  for (const auto& r : rows) {
    const Json& s = r.summary;
    for (const auto& [p, v] : r.combination.values) c << csv_field(v) << ',';
    c << csv_field(r.combination.name) << ',' << r.status << ',' << r.exit_status << ',' << csv_field(r.reason) << ','
      << str_field(s, "engine") << ',' << str_field(s, "breakage") << ',' << str_field(s, "fragments");
    for (const char* k : {"grains_initial", "grains_final", "breakage_events", "void_ratio_initial"})
      c << ',' << fmt(num(s, k), 10);
    for (const auto& k : levels) c << ',' << fmt(num(s, k), 10);
    for (const char* k : {"void_ratio_final", "max_platen_stress_Pa", "psd_d50_final_m", "fines_fraction_final",
                          "fines_size_m"})
      c << ',' << fmt(num(s, k), 10);
    for (const auto& o : optional) c << ',' << fmt(num(s, o.first), 10);
    c << ',' << fmt(num(s, "steps"), 12) << ',' << fmt(num(s, "wall_seconds"), 10);
    for (const auto& p : kTimeParts) c << ',' << fmt(time_part(s, p), 10);
    c << ',' << str_field(s, "packing_hash") << '\n';
  }
  return c.str();
}

// The cells of one row of comparison.md (MPa, mm, %, seconds); a row with a reason gets a
// numbered note.
std::vector<std::string> md_row(const ComparisonRow& r, const std::vector<std::string>& levels, const Optional& optional,
                                std::vector<std::string>& notes) {
  const Json& s = r.summary;
  std::vector<std::string> cell;
  for (const auto& [p, v] : r.combination.values) cell.push_back(v);
  std::string status = r.status;
  if (!r.reason.empty()) {
    notes.push_back(r.combination.label() + ": " + r.status + ": " + r.reason);
    status += " (" + std::to_string(notes.size()) + ")";
  }
  cell.push_back(status);
  const double gi = num(s, "grains_initial"), gf = num(s, "grains_final");
  cell.push_back(std::isfinite(gi) ? fmt(gi, 12) + " → " + fmt(gf, 12) : "");
  cell.push_back(fmt(num(s, "breakage_events"), 12));
  cell.push_back(fmt(num(s, "void_ratio_initial")));
  for (const auto& k : levels) cell.push_back(fmt(num(s, k)));
  cell.push_back(fmt(num(s, "void_ratio_final")));
  cell.push_back(fmt(num(s, "max_platen_stress_Pa") / 1e6));
  cell.push_back(fmt(num(s, "psd_d50_final_m") * 1e3));
  cell.push_back(fmt(num(s, "fines_fraction_final") * 100, 3));
  for (const auto& o : optional) {
    const double v = num(s, o.first);
    const bool pa = o.first.size() > 3 && o.first.compare(o.first.size() - 3, 3, "_Pa") == 0;
    const bool mm = o.first.size() > 2 && o.first.compare(o.first.size() - 2, 2, "_m") == 0;
    cell.push_back(fmt(pa ? v / 1e6 : mm ? v * 1e3 : v));
  }
  cell.push_back(fmt(num(s, "steps"), 12));
  cell.push_back(fmt(num(s, "wall_seconds"), 4));
  for (const auto& p : kTimeParts) cell.push_back(fmt(time_part(s, p), 3));
  return cell;
}

// comparison.md: the same rows for a person.
std::string comparison_md(const std::vector<VaryAxis>& axes, const std::vector<ComparisonRow>& rows,
                          const std::vector<std::string>& levels, const Optional& optional,
                          const std::vector<std::string>& header) {
  std::ostringstream m;
  for (const auto& h : header) m << h << "\n";
  if (!header.empty()) m << "\n";
  std::vector<std::string> cols;
  for (const auto& a : axes) cols.push_back(a.path);
  cols.insert(cols.end(), {"status", "grains", "breakage events", "e0"});
  for (const auto& k : levels) cols.push_back(level_title(k));
  cols.insert(cols.end(), {"e final", "max stress MPa", "d50 mm", "fines %"});
  for (const auto& o : optional) cols.push_back(o.second);
  cols.insert(cols.end(), {"steps", "wall s"});
  for (const auto& p : kTimeParts) cols.push_back(p + " s");
  m << "|";
  for (const auto& h : cols) m << ' ' << h << " |";
  m << "\n|";
  for (std::size_t i = 0; i < cols.size(); ++i) m << "---|";
  m << "\n";
  std::vector<std::string> notes;
  for (const auto& r : rows) {
    m << "|";
    for (const auto& x : md_row(r, levels, optional, notes)) m << ' ' << md_cell(x) << " |";
    m << "\n";
  }
  if (!notes.empty()) {
    m << "\n";
    for (std::size_t i = 0; i < notes.size(); ++i) m << "(" << i + 1 << ") " << notes[i] << "\n";
  }
  m << "\n`e` = void ratio (where the platen stress or axial strain first reaches the level, interpolated between samples; "
       "— = not reached), d50 and fines from the final particle size distribution by mass (fines: removed "
       "fragments and grains finer than `fines_size_m`), `wall s` the run's wall time, then where it went "
       "(summary.json `time_breakdown_s`). Every figure comes from the combination's summary.json; "
       "comparison.csv has them at full precision.\n";
  return m.str();
}

}  // namespace

void write_comparison(const std::string& dir, const std::vector<VaryAxis>& axes, const std::vector<ComparisonRow>& rows,
                      const std::vector<std::string>& expected_levels, const std::vector<std::string>& header) {
  const auto levels = level_keys(rows, expected_levels);
  const Optional optional = present_optional(rows);
  write_file_atomic(dir + "/comparison.csv", comparison_csv(axes, rows, levels, optional));
  write_file_atomic(dir + "/comparison.md", comparison_md(axes, rows, levels, optional, header));
}

namespace {

// The last "crumble: failed: ..." or "crumble: error: ..." line of a log.
std::string reason_from_log(const std::string& log) {
  std::ifstream in(log);
  std::string line, reason;
  while (std::getline(in, line))
    for (const char* p : {"crumble: failed: ", "crumble: error: "})
      if (line.rfind(p, 0) == 0) reason = line.substr(std::strlen(p));
  return reason;
}

// Runs a request in a child process (its stdout and stderr in `log`). A child is a copy of
// this process, so it runs the same pipeline; a crash or a guard stops only that child.
pid_t spawn(const RunRequest& req, const std::string& log) {
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error(std::string("cannot start a run (fork): ") + std::strerror(errno));
  if (pid > 0) return pid;
  // A resumed run's log goes on after what the run printed before.
  const int fd = open(log.c_str(), O_WRONLY | O_CREAT | (req.resume ? O_APPEND : O_TRUNC), 0644);
  if (fd >= 0) {
    dup2(fd, 1);
    dup2(fd, 2);
    close(fd);
  }
  int st = 1;
  try {
    const RunResult r = run_pipeline(req);
    if (r.status == 1) std::cerr << "crumble: failed: " << r.reason << "\n";
    st = r.status;
  } catch (const ConfigError& e) {
    std::cerr << "crumble: error: " << e.what() << "\n";
    st = 2;
  } catch (const InputError& e) {
    std::cerr << "crumble: error: " << e.what() << "\n";
    st = 2;
  } catch (const std::invalid_argument& e) {
    std::cerr << "crumble: error: " << e.what() << "\n";
    st = 2;
  } catch (const std::exception& e) {
    std::cerr << "crumble: failed: " << e.what() << "\n";
    st = 1;
  }
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  _exit(st);
}

std::string status_word(int exit_status) {
  switch (exit_status) {
    case 0: return "ok";
    case 1: return "failed";
    case 2: return "bad input";
    case 130:
    case 143: return "interrupted";
    default: return "crashed";
  }
}

Json read_summary(const fs::path& p) {
  std::ifstream in(p);
  if (!in) return nullptr;
  try {
    return Json::parse(in);
  } catch (const std::exception&) {
    return nullptr;
  }
}

// Files `compare` itself writes in DIR (the run folders are each run's own business).
bool is_compare_output(const std::string& n) {
  for (const char* f : {"comparison.csv", "comparison.md", "packing.json", "sweep.csv", "pareto.md"})
    for (const char* sfx : {"", ".tmp"})
      if (n == std::string(f) + sfx) return true;
  for (const auto& png : plot_file_names())
    if (n == png || n == png + ".tmp") return true;
  return false;
}

void prepare_compare_out(const std::string& out, bool force, const std::vector<std::string>& folders) {
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw InputError("--out " + out + ": exists and is not a directory");
  if (fs::exists(out, ec)) {
    std::vector<std::string> entries;
    for (const auto& e : fs::directory_iterator(out)) entries.push_back(e.path().filename().string());
    std::sort(entries.begin(), entries.end());
    if (!entries.empty() && !force) {
      std::string list;
      for (std::size_t i = 0; i < entries.size() && i < 6; ++i) list += (i ? ", " : "") + entries[i];
      if (entries.size() > 6) list += ", …";
      throw InputError("--out " + out + ": the folder is not empty (" + list +
                       "); a comparison would mix its runs with these. Choose an empty folder, or pass --force to "
                       "remove the files an earlier compare wrote there (only crumble's own) first.");
    }
    if (force) {
      for (const auto& n : entries)
        if (is_compare_output(n)) fs::remove(fs::path(out) / n);
      const fs::path logs = fs::path(out) / "logs";
      for (const auto& f : folders) fs::remove(logs / (f + ".log"), ec);
      if (fs::is_directory(logs, ec) && fs::is_empty(logs, ec)) fs::remove(logs, ec);
    }
  }
  fs::create_directories(fs::path(out) / "logs", ec);
  if (ec) throw InputError("--out " + out + ": cannot create directory: " + ec.message());
}

// --resume: `out` must hold this comparison (its packing.json or a run folder of one of its
// combinations) and no run folder of another.
void check_resume_out(const std::string& out, const std::vector<std::string>& folders) {
  std::error_code ec;
  if (!fs::is_directory(out, ec))
    throw InputError("--out " + out + " --resume: no such folder, nothing to resume; run the comparison without --resume");
  const std::set<std::string> mine(folders.begin(), folders.end());
  bool found = false;
  for (const auto& e : fs::directory_iterator(out)) {
    const std::string n = e.path().filename().string();
    if (n == "packing.json" || mine.count(n)) found = true;
    if (e.is_directory() && !mine.count(n) && fs::exists(e.path() / "effective_scenario.json"))
      throw InputError("--out " + out + " --resume: the folder holds the run '" + n +
                       "', which is none of this comparison's combinations; resume with the --vary options the "
                       "comparison was started with");
  }
  if (!found)
    throw InputError("--out " + out + " --resume: the folder holds no comparison (no packing.json, no run folder of "
                     "these combinations); run it without --resume");
  fs::create_directories(fs::path(out) / "logs", ec);
  if (ec) throw InputError("--out " + out + ": cannot create directory: " + ec.message());
}

// How --resume finds a combination's folder: no run, a run that finished (kept), one that
// stopped with a checkpoint (continued from it), or one that stopped before its first
// checkpoint (started again).
enum class Previous { none, finished, resumable, restart };

Previous previous_run(const fs::path& folder) {
  if (!fs::exists(folder / "effective_scenario.json")) return Previous::none;
  const Json s = read_summary(folder / "summary.json");
  if (s.is_object() && !s.value("interrupted", false)) return Previous::finished;
  return fs::exists(folder / "checkpoint.json") ? Previous::resumable : Previous::restart;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::vector<VaryAxis> vary_axes(const CompareRequest& req) {
  if (req.vary.empty()) throw InputError(req.command + ": give at least one --vary path=value1,value2,...");
  if (req.jobs < 1) throw InputError("--jobs: expected at least 1");
  std::vector<VaryAxis> axes;
  for (const auto& v : req.vary) axes.push_back(parse_vary(v));
  return axes;
}

// A path is either fixed (--set) or varied (--vary), never both.
void check_set_or_varied(const CompareRequest& req, const std::vector<VaryAxis>& axes) {
  for (const auto& a : axes)
    for (const auto& s : req.sets)
      if (s.substr(0, s.find('=')) == a.path)
        throw InputError("--vary " + a.arg + ": '" + a.path + "' is also given by --set " + s +
                         "; a path is either fixed (--set) or varied (--vary)");
}

// With one packing for every combination (`shared`), nothing that builds it may vary.
void check_packing_fixed(const std::vector<VaryAxis>& axes, bool shared) {
  if (shared)
    for (const auto& a : axes)
      for (const char* p : {"packing", "container", "dimension"})
        if (a.path == p || a.path.rfind(std::string(p) + ".", 0) == 0)
          throw InputError("--vary " + a.arg + ": every combination starts from the one packing built from the "
                           "scenario, so '" + a.path + "' cannot vary; fix it with --set, or run one compare per "
                           "packing");
}

// The base: the scenario with --set; it builds the packing that every combination starts from.
RunRequest base_request(const CompareRequest& req) {
  RunRequest base;
  base.scenario = req.scenario;
  base.source_name = req.source_name;
  base.sets = req.sets;
  base.seed = req.seed;
  base.threads = req.threads;
  base.quiet = req.quiet;
  return base;
}

// The void-ratio levels of the base scenario; a --set or scenario problem is reported as
// such, not per combination. Then every combination is checked before anything runs (with
// the scenario's own packing; the shared packing.json holds the same grains).
std::vector<std::string> check_requests(const CompareRequest& req, const RunRequest& base,
                                        const std::vector<Combination>& combos) {
  std::vector<std::string> levels;
  {
    const Scenario sc = build_request(base);
    for (double s : sc.output.psd_at_stress) levels.push_back(void_ratio_stress_key(s));
    for (double s : sc.output.psd_at_strain) levels.push_back(void_ratio_strain_key(s));
  }
  const std::string flag = req.command == "sweep" ? "--param" : "--vary";
  for (const auto& c : combos) {
    RunRequest r = base;
    for (const auto& s : c.sets()) r.sets.push_back(s);
    try {
      build_request(r);
    } catch (const ConfigError& e) {
      throw InputError(flag + ": the combination " + c.label() + " is refused by the scenario: " + e.what());
    } catch (const std::invalid_argument& e) {
      throw InputError(flag + ": the combination " + c.label() + " is refused by the scenario: " + e.what());
    }
  }
  return levels;
}

// The first lines of comparison.md: what was compared, and how.
std::vector<std::string> compare_header(const CompareRequest& req, const Json& base_doc,
                                        const std::vector<VaryAxis>& axes, std::size_t combos) {
  std::vector<std::string> header;
  header.push_back("# crumble " + req.command + ": " + (base_doc.is_object() ? base_doc.value("name", std::string("scenario")) : "") +
                   " (" + req.source_name + ")");
  header.push_back("");
  std::string how = "Varied:";
  for (const auto& a : axes) how += " `" + a.path + "` = " + [&] {
    std::string s;
    for (const auto& v : a.values) s += (s.empty() ? "" : ", ") + v;
    return s;
  }() + ";";
  for (const auto& s : req.sets) how += " `--set " + s + "`;";
  header.push_back(how + " " + std::to_string(combos) + " combinations, " + std::to_string(req.jobs) +
                   " at a time" + (req.threads ? ", " + std::to_string(*req.threads) + (*req.threads == 1 ? " thread" : " threads") + " each" : "") + ".");
  return header;
}

// Waits for the child `pid` and returns its wait status. A stop request (SIGINT/SIGTERM
// sent to this process alone) is forwarded to it once, so that it stops as a run does
// (a settling packing writes its checkpoint and ends) instead of running to its end.
int wait_forwarding_stop(pid_t pid) {
  bool forwarded = false;
  for (;;) {
    int st = 0;
    const pid_t r = waitpid(pid, &st, WNOHANG);
    if (r == pid) return st;
    if (r < 0 && errno != EINTR) return W_EXITCODE(1, 0);  // the child is lost: a failed stage
    if (stop_requested() && !forwarded) {
      kill(pid, received_signal() ? received_signal() : SIGTERM);
      forwarded = true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}

// The packing every combination loads: DIR/packing.json, by its absolute path (as the runs'
// effective scenarios name it).
std::string shared_packing_path(const fs::path& dir) { return fs::absolute(dir / "packing.json").string(); }

// DIR/packing.json as the packing of every combination: its file, hash and header line.
void use_shared_packing(const fs::path& dir, std::optional<std::string>& packing_file, std::string& packing_hash,
                        std::vector<std::string>& header) {
  packing_file = shared_packing_path(dir);
  packing_hash = file_sha256(*packing_file);
  const Json ps = read_summary(dir / "packing" / "summary.json");
  header.push_back("Packing: " + fmt(num(ps, "grains"), 12) + " grains built and settled once by `" +
                   (ps.is_object() ? ps.value("engine", std::string("?")) : std::string("?")) + "` in " +
                   fmt(num(ps, "packing_settle_steps"), 12) + " steps (" + fmt(num(ps, "wall_seconds"), 3) +
                   " s); every combination starts from packing.json, SHA-256 " + packing_hash +
                   ". A combination on another engine first relaxes it on its own engine under the settling stress "
                   "(packing.relax auto; what it did is in its summary.json, relax_*).");
}

// The packing, once, in DIR/packing (each combination loads DIR/packing.json, no settling of
// its own). Returns the stage's exit status; on success sets the packing file and hash and
// adds a line to the header.
int build_shared_packing(const CompareRequest& req, const RunRequest& base, const fs::path& dir,
                         std::optional<std::string>& packing_file, std::string& packing_hash,
                         std::vector<std::string>& header) {
  const fs::path logs = dir / "logs";
  RunRequest p = base;
  p.out = (dir / "packing").string();
  p.force = req.force || req.resume;  // --resume: a packing stage that did not finish starts again
  p.packing_only = true;
  p.quiet = false;
  if (!req.quiet) std::cerr << "crumble: " << req.command << ": building the packing (log " << (logs / "packing.log").string() << ")\n";
  const pid_t pid = spawn(p, (logs / "packing.log").string());
  const int st = wait_forwarding_stop(pid);
  const int code = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
  if (code != 0) {
    const std::string why = reason_from_log((logs / "packing.log").string());
    std::cerr << "crumble: " << req.command << ": the packing stage ended with status " << code
              << (why.empty() ? "" : ": " + why) << " (log " << (logs / "packing.log").string() << ")\n";
    return code;
  }
  fs::copy_file(dir / "packing" / "packing.json", dir / "packing.json", fs::copy_options::overwrite_existing);
  use_shared_packing(dir, packing_file, packing_hash, header);
  return 0;
}

// A finished run's row: its status from the wait status `st`, its peak memory, the reason
// it did not end well (from its log) and its summary.json.
void finish_row(ComparisonRow& row, int st, const struct rusage& ru, const fs::path& dir) {
  row.exit_status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
  row.status = status_word(row.exit_status);
  row.peak_rss_bytes = 1024.0 * static_cast<double>(ru.ru_maxrss);  // Linux: kilobytes
  const std::string log = (dir / "logs" / (row.combination.name + ".log")).string();
  if (row.exit_status != 0) {
    row.reason = WIFSIGNALED(st) ? "the run was killed by signal " + std::to_string(WTERMSIG(st))
                                 : reason_from_log(log);
    if (row.reason.empty()) row.reason = "exit status " + std::to_string(row.exit_status) + " (see " + log + ")";
  }
  row.summary = read_summary(dir / row.combination.name / "summary.json");
  if (row.exit_status == 0 && !row.summary.is_object()) {
    row.status = "failed";
    row.exit_status = 1;
    row.reason = "no summary.json";
  }
}

// The run request of combination i, in its folder DIR/<name>.
RunRequest combination_request(const RunRequest& base, const Combination& c, const fs::path& dir,
                               const std::optional<std::string>& packing_file) {
  RunRequest r = base;
  for (const auto& s : c.sets()) r.sets.push_back(s);
  r.out = (dir / c.name).string();
  r.packing_file = packing_file;
  return r;
}

// Runs combination i in its folder DIR/<name> (log in DIR/logs): continued from its
// checkpoint when `prev` is resumable, else started (over what an unfinished run left).
pid_t start_combination(const CompareRequest& req, const RunRequest& base, const std::vector<Combination>& combos,
                        std::size_t i, const fs::path& dir, const std::optional<std::string>& packing_file,
                        Previous prev) {
  RunRequest r = combination_request(base, combos[i], dir, packing_file);
  r.resume = prev == Previous::resumable;
  r.force = req.force || (req.resume && !r.resume);
  const std::string log = (dir / "logs" / (combos[i].name + ".log")).string();
  if (!req.quiet)
    std::cerr << "crumble: " << req.command << ": [" << i + 1 << "/" << combos.size() << "] " << combos[i].label()
              << (r.resume ? " continued from its checkpoint" : " started") << " (log " << log << ")\n";
  return spawn(r, log);
}

// --resume: the row of a combination whose run finished before, as it ended.
void keep_finished_row(const CompareRequest& req, ComparisonRow& row, const fs::path& dir, std::size_t i,
                       std::size_t n) {
  row.exit_status = 0;
  row.status = status_word(0);
  row.summary = read_summary(dir / row.combination.name / "summary.json");
  if (!req.quiet)
    std::cerr << "crumble: " << req.command << ": [" << i + 1 << "/" << n << "] " << row.combination.label()
              << " finished before: kept (" << (dir / row.combination.name).string() << ")\n";
}

// The combinations, `jobs` at a time; a stop request is forwarded to the running ones.
void run_combinations(const CompareRequest& req, const RunRequest& base, const std::vector<Combination>& combos,
                      const fs::path& dir, const std::optional<std::string>& packing_file,
                      const std::vector<Previous>& prev, std::vector<ComparisonRow>& rows) {
  std::map<pid_t, std::size_t> running;
  std::map<pid_t, std::chrono::steady_clock::time_point> started;
  std::size_t next = 0;
  bool forwarded = false;
  while (next < combos.size() || !running.empty()) {
    while (!stop_requested() && next < combos.size() && static_cast<int>(running.size()) < req.jobs) {
      if (prev[next] == Previous::finished) {
        keep_finished_row(req, rows[next], dir, next, combos.size());
        ++next;
        continue;
      }
      const pid_t pid = start_combination(req, base, combos, next, dir, packing_file, prev[next]);
      running[pid] = next;
      started[pid] = std::chrono::steady_clock::now();
      ++next;
    }
    if (stop_requested() && !forwarded) {
      // SIGTERM sent to compare alone reaches its runs this way (Ctrl-C reaches them all anyway).
      for (const auto& [pid, i] : running) kill(pid, received_signal() ? received_signal() : SIGTERM);
      forwarded = true;
    }
    if (running.empty()) break;
    int st = 0;
    struct rusage ru {};
    const pid_t pid = wait4(-1, &st, WNOHANG, &ru);
    if (pid == 0 || (pid < 0 && errno == EINTR)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      continue;
    }
    if (pid < 0) break;
    auto it = running.find(pid);
    if (it == running.end()) continue;
    ComparisonRow& row = rows[it->second];
    finish_row(row, st, ru, dir);
    if (!req.quiet)
      std::cerr << "crumble: " << req.command << ": " << row.combination.label() << ": " << row.status << " after "
                << fmt(seconds_since(started[pid]), 3) << " s" << (row.reason.empty() ? "" : ": " + row.reason)
                << "\n";
    running.erase(it);
  }
  for (auto& r : rows)
    if (r.exit_status < 0) r.reason = "not started: the comparison was interrupted";
}

// --resume: how each combination's folder was left (all `none` without --resume). A run that
// is kept or continued must have been run with the scenario this request builds for it
// (InputError naming the first difference, before anything runs).
std::vector<Previous> previous_runs(const CompareRequest& req, const RunRequest& base,
                                    const std::vector<Combination>& combos, const fs::path& dir, bool shared_packing) {
  std::vector<Previous> prev(combos.size(), Previous::none);
  if (!req.resume) return prev;
  std::optional<std::string> packing_file;
  if (shared_packing) packing_file = shared_packing_path(dir);
  for (std::size_t i = 0; i < combos.size(); ++i) {
    prev[i] = previous_run(dir / combos[i].name);
    if (prev[i] == Previous::none) continue;
    if (packing_file && !fs::exists(*packing_file))
      throw InputError("--out " + dir.string() + " --resume: " + *packing_file + ", the packing the run " +
                       combos[i].name + " started from, is missing; start the comparison again (--force)");
    check_same_run(combination_request(base, combos[i], dir, packing_file));
  }
  return prev;
}

// The header line of a resumed comparison: what it kept, continued and started.
std::string resume_line(const std::vector<Previous>& prev) {
  long kept = 0, continued = 0;
  for (const Previous p : prev) {
    kept += p == Previous::finished;
    continued += p == Previous::resumable;
  }
  return "Resumed (`--resume`): " + std::to_string(kept) + " run(s) that had finished kept as they were, " +
         std::to_string(continued) + " continued from their checkpoints, " +
         std::to_string(static_cast<long>(prev.size()) - kept - continued) +
         " started; a continued run's wall time is that of its last part (its summary.json resumed_from_step says "
         "where that began).";
}

}  // namespace

int run_compare(const CompareRequest& req) { return compare_runs(req).status; }

// With --jobs N and no --threads the runs share the machine's cores: each gets cores / N
// threads (at least one), so N runs of a scenario's own "threads" do not oversubscribe the
// CPUs (OpenMP threads spin at every barrier while another process holds their CPU).
CompareRequest with_threads_per_job(CompareRequest req) {
  if (!req.threads && req.jobs > 1)
    req.threads = std::max(1, usable_cpus() / req.jobs);
  return req;
}

CompareOutcome compare_runs(const CompareRequest& request) {
  const CompareRequest req = with_threads_per_job(request);
  CompareOutcome outcome;
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<VaryAxis> axes = vary_axes(req);
  const auto combos = combinations(axes);
  check_set_or_varied(req, axes);
  const RunRequest base = base_request(req);
  const Json base_doc = request_document(base);
  const bool shared_packing = base_doc.is_object() && !base_doc.contains("scene");
  check_packing_fixed(axes, shared_packing);
  const std::vector<std::string> levels = check_requests(req, base, combos);
  std::vector<std::string> folders;
  for (const auto& c : combos) folders.push_back(c.name);
  folders.push_back("packing");
  if (req.resume && req.force) throw InputError("--resume and --force exclude each other");
  if (req.resume)
    check_resume_out(req.out, folders);
  else
    prepare_compare_out(req.out, req.force, folders);
  const fs::path dir(req.out);
  const std::vector<Previous> prev = previous_runs(req, base, combos, dir, shared_packing);
  install_stop_signals();
  std::vector<std::string> header = compare_header(req, base_doc, axes, combos.size());
  if (req.resume) header.push_back(resume_line(prev));
  outcome.axes = axes;
  std::optional<std::string> packing_file;
  if (!shared_packing) {
    header.push_back("Packing: the scenario's scene builds it in each combination (same seed, same grains; "
                     "compare packing_hash in comparison.csv).");
  } else if (req.resume && fs::exists(dir / "packing.json") && fs::exists(dir / "packing" / "summary.json")) {
    use_shared_packing(dir, packing_file, outcome.packing_hash, header);
  } else if (const int code = build_shared_packing(req, base, dir, packing_file, outcome.packing_hash, header); code != 0) {
    outcome.status = code == 130 || code == 143 ? code : code == 2 ? 2 : 1;
    return outcome;
  }
  std::vector<ComparisonRow> rows(combos.size());
  for (std::size_t i = 0; i < combos.size(); ++i) rows[i].combination = combos[i];
  run_combinations(req, base, combos, dir, packing_file, prev, rows);
  header.push_back(std::string(req.resume ? "Wall time of this resumed part of the comparison: "
                                          : "Wall time of the whole comparison: ") +
                   fmt(seconds_since(t0), 4) + " s.");
  write_comparison(dir.string(), axes, rows, levels, header);
  if (!req.quiet)
    std::cerr << "crumble: " << req.command << ": " << combos.size() << " combinations in " << fmt(seconds_since(t0), 4)
              << " s; table in " << (dir / "comparison.md").string() << "\n";
  outcome.rows = rows;
  if (stop_requested()) {
    outcome.status = interrupted_status();
    return outcome;
  }
  for (const auto& r : rows)
    if (r.exit_status != 0) {
      outcome.status = r.exit_status == 130 || r.exit_status == 143 ? r.exit_status : 1;
      return outcome;
    }
  return outcome;
}

}  // namespace crumble
