#include "output/Writers.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fcntl.h>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <map>
#include <set>
#include <string_view>
#include <sstream>
#include <stdexcept>

#include "core/Measures.h"
#include "base/Format.h"
#include "geometry/LevelSetGrid.h"
#include "geometry/ShapeMetrics.h"
#include "output/OutputReference.h"

namespace crumble {

namespace fs = std::filesystem;
using Json = nlohmann::json;

void write_file_atomic(const std::string& path, const std::string& content) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write '" + tmp + "'");
    out << content;
    out.flush();
    if (!out) throw std::runtime_error("write failed for '" + tmp + "'");
  }
#ifdef RENAME_EXCHANGE
  // An existing file is swapped with the new one, then the old one (now at tmp) removed:
  // readers see the old or the new file, never a part, as with rename. A rename over an
  // existing file makes ext4 (auto_da_alloc) write the new file's data out at once, 0.5-4 ms
  // a file on a loaded machine, and the files rewritten at every snapshot (grains.pvd,
  // scene.pvd) and every level (psd.csv) paid it each time. Without an existing file, or on a
  // file system without the swap: rename.
  std::error_code regular;
  if (fs::is_regular_file(path, regular) &&
      ::renameat2(AT_FDCWD, tmp.c_str(), AT_FDCWD, path.c_str(), RENAME_EXCHANGE) == 0) {
    std::error_code ec;
    fs::remove(tmp, ec);
    return;
  }
#endif
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) throw std::runtime_error("cannot rename '" + tmp + "' to '" + path + "': " + ec.message());
}

namespace {
// One CSV line split at commas (a trailing comma ends with an empty cell).
std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}
}  // namespace

std::vector<std::vector<std::string>> read_csv(const std::string& path) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) rows.push_back(split_csv_line(line));
  return rows;
}

std::vector<std::vector<std::string>> read_breakage_rows(const std::string& events_csv) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(events_csv);
  std::string line;
  if (!std::getline(in, line)) return rows;
  rows.push_back(split_csv_line(line));
  // Columns by name, so the layout may grow.
  std::size_t children = 9, removed = 12;
  for (std::size_t c = 0; c < rows[0].size(); ++c) {
    if (rows[0][c] == "children") children = c;
    if (rows[0][c] == "removed_volume_m3") removed = c;
  }
  // The cell of column k, found by counting commas (no allocation for the intact rows).
  auto cell = [](const std::string& l, std::size_t k) -> std::string_view {
    std::size_t a = 0;
    for (std::size_t i = 0; i < k; ++i) {
      a = l.find(',', a);
      if (a == std::string::npos) return {};
      ++a;
    }
    const std::size_t b = std::min(l.find(',', a), l.size());
    return std::string_view(l).substr(a, b - a);
  };
  auto positive = [](std::string_view v) { return !v.empty() && std::atof(std::string(v).c_str()) > 0; };
  while (std::getline(in, line))
    if (positive(cell(line, children)) || positive(cell(line, removed))) rows.push_back(split_csv_line(line));
  return rows;
}

CsvStream::CsvStream(std::string path, const std::string& header, long keep_until_step) : path_(std::move(path)) {
  std::string kept;
  if (keep_until_step >= 0) {
    // Carry over the rows of the interrupted (or finished) earlier run up to the resume point.
    const std::string from = fs::exists(path_ + ".part") ? path_ + ".part" : path_;
    std::ifstream in(from);
    std::string line;
    int col = -1;
    bool first = true;
    std::ptrdiff_t commas = 0;
    while (std::getline(in, line)) {
      std::stringstream ss(line);
      std::string cell;
      if (first) {
        first = false;
        for (int k = 0; std::getline(ss, cell, ','); ++k)
          if (cell == "step") col = k;
        if (col < 0) throw std::runtime_error("cannot resume '" + from + "': it has no step column");
        commas = std::count(line.begin(), line.end(), ',');
        continue;
      }
      // A run killed while writing leaves a cut last row: a row is kept only whole (as many
      // fields as the header) and with a whole step number at or before the resume point.
      if (std::count(line.begin(), line.end(), ',') != commas) continue;
      for (int k = 0; k <= col && std::getline(ss, cell, ','); ++k) {
      }
      char* end = nullptr;
      const long v = std::strtol(cell.c_str(), &end, 10);
      if (end != cell.c_str() && *end == '\0' && v <= keep_until_step) kept += line + "\n";
    }
  }
  out_.open(path_ + ".part", std::ios::trunc);
  if (!out_) throw std::runtime_error("cannot write '" + path_ + ".part'");
  out_ << std::setprecision(10) << header << "\n" << kept;
  if (keep_until_step >= 0) {
    // The earlier run's finished file now lives on in the .part: a resumed run that stops on a
    // guard (its files stay .part) must not leave it beside, looking complete.
    out_.flush();
    std::error_code ec;
    fs::remove(path_, ec);
  }
}

CsvStream::~CsvStream() {
  // An unfinished run leaves its rows in <file>.part, never a truncated <file>.
  if (!done_) out_.flush();
}

void CsvStream::finish() {
  if (done_) return;
  out_.close();
  std::error_code ec;
  fs::rename(path_ + ".part", path_, ec);
  if (ec) throw std::runtime_error("cannot rename '" + path_ + ".part': " + ec.message());
  done_ = true;
}

namespace {
void check_finite(double v, const char* what) {
  if (!std::isfinite(v)) throw std::runtime_error(std::string("refusing to write a non-finite ") + what);
}
}  // namespace

SeriesWriter::SeriesWriter(const std::string& dir, long resume_step)
    : csv_(dir + "/series.csv", csv_header("series.csv"), resume_step),
      last_step_(resume_step) {}

double current_k0(const Simulation& sim, const RunState& s) {
  const Container& c = sim.container();
  const int dim = sim.context().dimension;
  if (c.open || !(c.lx > 0) || (dim == 3 && !(c.ly > 0))) return std::nan("");
  const Engine& e = sim.engine();
  SideWallForces f;
  f.x_min = e.wall_force(kWallXMin);
  f.x_max = e.wall_force(kWallXMax);
  if (dim == 3) {
    f.y_min = e.wall_force(kWallYMin);
    f.y_max = e.wall_force(kWallYMax);
  }
  return lateral_stress_ratio(lateral_stress(f, c.lx, c.ly, s.platen_height, dim), s.platen_stress);
}

void SeriesWriter::on_sample(const Simulation& sim, const RunState& s) {
  if (s.step == last_step_) return;
  last_step_ = s.step;
  for (double v : {s.time, s.platen_stress, s.axial_strain, s.void_ratio, s.platen_force, s.floor_force})
    check_finite(v, "value in series.csv");
  csv_.row() << s.time << ',' << s.step << ',' << s.dt << ',' << s.platen_stress << ',' << s.target_stress << ','
             << s.axial_strain << ',' << s.void_ratio << ',' << s.grains << ',' << s.breakage_events << ','
             << s.analyses << ',' << s.platen_height << ',' << s.platen_force << ',' << s.floor_force << ',';
  const double k0 = current_k0(sim, s);
  if (std::isfinite(k0)) {  // never NaN in a file: an undefined K0 is an empty cell
    csv_.row() << k0;
    last_k0_ = k0;
  }
  csv_.row() << '\n';
  csv_.row().flush();  // a killed run keeps every row written so far
}

void SeriesWriter::on_finish(const Simulation&, const RunState&, RunSummary& sum) {
  csv_.finish();
  if (std::isfinite(last_k0_)) sum.extra["k0_final"] = last_k0_;
}

namespace {
// The common columns, then the model's figures (the family `<figure>`).
std::string events_header(const std::vector<std::string>& figures) {
  return csv_header("events.csv", "", [&figures](const std::string&) { return figures; });
}
}  // namespace

EventsWriter::EventsWriter(const std::string& dir, std::vector<std::string> figure_names, long resume_step,
                           bool intact)
    : dir_(dir),
      figures_(std::move(figure_names)),
      csv_(dir + "/events.csv", events_header(figures_), resume_step),
      intact_(intact) {}

void EventsWriter::write_figures(const BreakageAnalysis& a) {
  // Columns follow the declared names; a figure the model did not set this time is empty.
  for (const auto& name : figures_) {
    csv_.row() << ',';
    for (const auto& [k, v] : a.figures)
      if (k == name) {
        check_finite(v, "figure in events.csv");
        csv_.row() << v;
        break;
      }
  }
  csv_.row() << '\n';
}

void EventsWriter::flush_pending() {
  if (!has_pending_) return;
  const auto& r = pending_;
  csv_.row() << r.time << ',' << r.step << ',' << r.platen_stress << ',' << r.grain << ',' << r.diameter << ',' << r.generation << ','
             << r.analysis.wall_ms << ',' << r.analysis.outcome << ',' << r.analysis.load << ",0,,,0,";
  write_figures(r.analysis);
  has_pending_ = false;
}

void EventsWriter::on_sample(const Simulation&, const RunState&) {
  flush_pending();
  csv_.row().flush();
}

void EventsWriter::on_analysis(const Simulation&, const AnalysisRecord& r) {
  flush_pending();
  if (!intact_) return;  // a breakage still gets its row (on_breakage)
  pending_ = r;
  has_pending_ = true;
}

void EventsWriter::on_breakage(const Simulation&, const BreakageEvent& e) {
  // The breakage follows the analysis of the same grain: write them as one row.
  has_pending_ = false;
  std::ostringstream vols, diams;
  vols << std::setprecision(10);
  diams << std::setprecision(10);
  for (std::size_t i = 0; i < e.child_volumes.size(); ++i) {
    vols << (i ? ";" : "") << e.child_volumes[i];
    diams << (i ? ";" : "") << e.child_diameters[i];
  }
  csv_.row() << e.time << ',' << e.step << ',' << e.platen_stress << ',' << e.parent << ',' << e.parent_diameter << ',' << e.generation
             << ',' << e.analysis.wall_ms << ',' << e.analysis.outcome << ',' << e.analysis.load << ','
             << e.children.size() << ',' << vols.str() << ',' << diams.str() << ',' << e.removed_volume << ','
             << e.fragment_method;
  write_figures(e.analysis);
  csv_.row().flush();
}

void EventsWriter::on_finish(const Simulation&, const RunState& s, RunSummary&) {
  flush_pending();
  csv_.finish();
  // From the finished events.csv, so a resumed run counts the events before the resume. A
  // breakage row has children or removed fines (every child can be a fine, leaving no child
  // in the engine); counting children alone dropped those events, and the file disagreed
  // with summary.json.
  const auto rows = read_breakage_rows(dir_ + "/events.csv");
  std::size_t stress_col = 2;
  if (!rows.empty())
    for (std::size_t c = 0; c < rows[0].size(); ++c)
      if (rows[0][c] == "platen_stress_Pa") stress_col = c;
  std::vector<double> stresses;
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (rows[i].size() > stress_col) stresses.push_back(std::atof(rows[i][stress_col].c_str()));
  // Zhu & Zhao 2019 Fig. 12: crushing events per 1 MPa of vertical stress.
  const std::vector<long> per = events_per_increment(stresses, 1e6, s.platen_stress);
  std::ostringstream os;
  os << csv_header("breakage_per_mpa.csv") << '\n';
  for (std::size_t m = 0; m < per.size(); ++m) os << m << ',' << m + 1 << ',' << per[m] << '\n';
  write_file_atomic(dir_ + "/breakage_per_mpa.csv", os.str());
}

PsdWriter::PsdWriter(const std::string& dir, std::vector<double> levels, double resume_stress,
                     std::vector<double> strain_levels, double resume_strain, long resume_step)
    : dir_(dir), levels_(std::move(levels)), strains_(std::move(strain_levels)) {
  std::sort(levels_.begin(), levels_.end());
  std::sort(strains_.begin(), strains_.end());
  if (resume_stress < 0 && resume_step < 0) return;
  // Keep the earlier tables (but its final one) and the sieves they used.
  resumed_ = true;
  const auto rows = read_csv(dir_ + "/psd.csv");
  int step_col = -1;
  if (!rows.empty())
    for (std::size_t c = 0; c < rows[0].size(); ++c)
      if (rows[0][c] == "step") step_col = static_cast<int>(c);
  std::set<std::string> kept;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    // The end-of-run tables ("final" and levels not reached) belong to the earlier run's end.
    if (rows[i].size() < 4 || rows[i][0] == "final" || rows[i][0].find("_not_reached") != std::string::npos) continue;
    // A table written after the checkpoint (by a run killed later) is written again by the
    // resumed run: kept by the step of its sample, as the CSV streams keep their rows.
    if (resume_step >= 0 && step_col >= 0 &&
        (static_cast<int>(rows[i].size()) <= step_col || std::atol(rows[i][step_col].c_str()) > resume_step))
      continue;
    kept.insert(rows[i][0]);
    for (std::size_t k = 0; k < rows[i].size(); ++k) rows_ += (k ? "," : "") + rows[i][k];
    rows_ += '\n';
    d_max_ = std::max(d_max_, std::atof(rows[i][2].c_str()));
  }
  initial_kept_ = kept.count("initial") > 0;
  if (resume_step >= 0 && step_col >= 0) {
    // Levels are tabled in ascending order: the kept tables say which are done.
    while (next_ < levels_.size() && kept.count("level_" + fmt_num(levels_[next_]))) ++next_;
    while (next_strain_ < strains_.size() && kept.count("strain_" + fmt_num(strains_[next_strain_]))) ++next_strain_;
    return;
  }
  // A psd.csv without steps (written before they were recorded): by the stress and strain
  // reached at the checkpoint.
  while (next_ < levels_.size() && levels_[next_] <= resume_stress) ++next_;
  while (next_strain_ < strains_.size() && strains_[next_strain_] <= resume_strain) ++next_strain_;
}

void PsdWriter::on_start(const Simulation& sim, const RunState& s) {
  // The kept initial table holds the initial grains' sieves (all 0 for a scene that starts
  // empty and is fed: a jaw crusher); without it, the grains at the resume give them.
  if (resumed_ && (initial_kept_ || d_max_ > 0)) return;
  for (const auto& g : sim.grains()) d_max_ = std::max(d_max_, g.shape->equivalent_diameter());
  table(sim, s, "initial");
  write();  // on disk before any checkpoint, so a run killed early resumes with it
}

void PsdWriter::write() const {
  write_file_atomic(dir_ + "/psd.csv",
                    csv_header("psd.csv") + "\n" + rows_);
}

void PsdWriter::on_sample(const Simulation& sim, const RunState& s) {
  bool wrote = false;
  const double reached = level_stress(sim.loading().settings().mode, s.platen_stress, s.target_stress);
  for (; next_ < levels_.size() && reached >= levels_[next_]; ++next_, wrote = true)
    table(sim, s, "level_" + fmt_num(levels_[next_]));
  for (; next_strain_ < strains_.size() && s.axial_strain >= strains_[next_strain_]; ++next_strain_, wrote = true)
    table(sim, s, "strain_" + fmt_num(strains_[next_strain_]));
  if (wrote) write();  // each table on disk as soon as it exists
}

void PsdWriter::on_finish(const Simulation& sim, const RunState& s, RunSummary&) {
  // A level the stress never reached (a ramp to loading.max_stress ends a hair below it, or
  // the run stopped early) still gets its table, from the final state, and its label says so
  // and names the stress (strain) of that state.
  // (Ten digits, as the table's columns: a ramp ending a hair below its level reads
  // 4999999.995, not 5e+06.)
  auto reached = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.10g", v);
    return std::string(buf);
  };
  for (; next_ < levels_.size(); ++next_)
    table(sim, s, "level_" + fmt_num(levels_[next_]) + "_not_reached_final_at_" + reached(s.platen_stress) + "_Pa");
  for (; next_strain_ < strains_.size(); ++next_strain_)
    table(sim, s, "strain_" + fmt_num(strains_[next_strain_]) + "_not_reached_final_at_" + reached(s.axial_strain));
  table(sim, s, "final");
  write();
}

void PsdWriter::table(const Simulation& sim, const RunState& s, const std::string& label) {
  // Sieves: geometric series from d_max down by factors of 2^(1/4), 25 sieves; by mass, the
  // removed fines at size 0 (finer than every sieve listed here).
  const std::vector<double> sieves = geometric_sieves(d_max_, 25, std::pow(2.0, 0.25));
  std::vector<double> sizes, masses;
  for (const auto& g : sim.grains()) {
    sizes.push_back(g.shape->equivalent_diameter());
    masses.push_back(g.shape->volume() * sim.context().materials[g.material].density);
  }
  sizes.push_back(0.0);
  masses.push_back(sim.removed_mass());
  const std::vector<double> pass = percent_passing(sizes, masses, sieves);
  std::ostringstream os;
  os << std::setprecision(10);
  // The sieve with every digit: a resumed run takes d_max from the first sieve of the kept
  // tables and must find the same sieves.
  for (std::size_t k = 0; k < sieves.size(); ++k)
    os << label << ',' << s.platen_stress << ',' << std::setprecision(17) << sieves[k] << std::setprecision(10) << ','
       << pass[k] << ',' << s.axial_strain << ',' << s.step << '\n';
  rows_ += os.str();
}

GrainShapeMetrics grain_shape_metrics(const Shape& shape) {
  GrainShapeMetrics m;
  try {
    if (shape.dimension() == 2) {
      const ShapeMetrics2D s = shape_metrics_2d(shape.outline());
      m.circularity = s.circularity;
      m.aspect_ratio = s.aspect_ratio;
      m.sieve_size = s.sieve_size;
    } else {
      const TriMesh& mesh = shape.mesh();
      const ShapeMetrics3D s = shape_metrics_3d(mesh, polyhedron_mass_properties(mesh));
      m.sphericity = s.sphericity;
      m.elongation = s.elongation;
      m.flatness = s.flatness;
    }
  } catch (const std::invalid_argument&) {
    // A degenerate outline or mesh (a sliver): no descriptor, left out of every mean.
  }
  return m;
}

ShapeWriter::ShapeWriter(const std::string& dir, int dimension, long resume_step,
                         std::shared_ptr<ShapeMetricsCache> cache)
    : dim_(dimension),
      csv_(dir + "/shape.csv", csv_header("shape.csv", dimension == 2 ? "2D" : "3D"), resume_step),
      last_step_(resume_step),
      cache_(cache ? std::move(cache) : std::make_shared<ShapeMetricsCache>()) {}

const GrainShapeMetrics& ShapeMetricsCache::get(const Shape::Ptr& shape) {
  auto it = now_.find(shape.get());
  if (it != now_.end()) return it->second.second;
  auto old = cache_.find(shape.get());
  if (old != cache_.end()) return now_.emplace(shape.get(), std::move(old->second)).first->second.second;
  ++computed_;
  return now_.emplace(shape.get(), std::make_pair(shape, grain_shape_metrics(*shape))).first->second.second;
}

void ShapeMetricsCache::sweep() {
  cache_ = std::move(now_);  // shapes no longer in use are released
  now_.clear();
}

void ShapeWriter::on_sample(const Simulation& sim, const RunState& s) {
  if (s.step == last_step_) return;
  last_step_ = s.step;
  double sum[3] = {0, 0, 0};
  long n[3] = {0, 0, 0};
  for (const auto& g : sim.grains()) {
    const GrainShapeMetrics& m = cache_->get(g.shape);
    const double v[3] = {dim_ == 2 ? m.circularity : m.sphericity, dim_ == 2 ? m.aspect_ratio : m.elongation,
                         dim_ == 2 ? m.sieve_size : m.flatness};
    for (int k = 0; k < 3; ++k)
      if (std::isfinite(v[k])) {
        sum[k] += v[k];
        ++n[k];
      }
  }
  cache_->sweep();
  // No grain with a descriptor (none left in the engine): the row is left out, never NaN.
  if (n[0] == 0 || n[1] == 0 || n[2] == 0) return;
  last_means_ = {sum[0] / n[0], sum[1] / n[1], sum[2] / n[2]};
  for (double v : {s.time, s.axial_strain, s.platen_stress}) check_finite(v, "value in shape.csv");
  csv_.row() << s.time << ',' << s.step << ',' << s.axial_strain << ',' << s.platen_stress << ',' << s.grains << ','
             << last_means_[0] << ',' << last_means_[1] << ',' << last_means_[2] << '\n';
  csv_.row().flush();
}

void ShapeWriter::on_finish(const Simulation&, const RunState&, RunSummary& sum) {
  csv_.finish();
  if (last_means_.empty()) return;
  if (dim_ == 2) {
    sum.extra["mean_circularity_final"] = last_means_[0];
    sum.extra["mean_aspect_ratio_final"] = last_means_[1];
  } else {
    sum.extra["mean_sphericity_final"] = last_means_[0];
    sum.extra["mean_zingg_ei_final"] = last_means_[1];
    sum.extra["mean_zingg_fi_final"] = last_means_[2];
  }
}

Json summary_json(const RunSummary& s, const std::string& scenario, const std::string& engine,
                  const std::string& breakage, const std::string& fragments, std::uint64_t seed, int threads) {
  Json j;
  j["scenario"] = scenario;
  j["engine"] = engine;
  j["breakage"] = breakage;
  j["fragments"] = fragments;
  j["seed"] = seed;
  j["threads"] = threads;
  // RunSummary's own fields, by the keys that declare them (output/OutputReference.cpp).
  // A nested key (`time_breakdown_s.engine`) by its path.
  for (const auto& k : summary_keys()) {
    if (!k.value) continue;
    std::string path = "/" + k.name;
    std::replace(path.begin(), path.end(), '.', '/');
    j[Json::json_pointer(path)] = k.value(s);
  }
  if (s.interrupted) j["interrupted"] = true;
  // `output` by writer (Observer::name()): the parts sum to `output`.
  j["time_breakdown_s"]["output_by_writer"] = Json::object();
  for (const auto& [name, seconds] : s.timings.output_by_writer) j["time_breakdown_s"]["output_by_writer"][name] = seconds;
  for (const auto& [k, v] : s.extra) j[k] = v;
  for (const auto& [k, v] : s.extra_arrays) j[k] = v;
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it->is_number_float() && !std::isfinite(it->get<double>()))
      throw std::runtime_error("summary value '" + it.key() + "' is not finite");
  return j;
}

ProductWriter::ProductWriter(const std::string& dir, std::map<std::string, double> figures)
    : dir_(dir), figures_(std::move(figures)) {}

void ProductWriter::on_finish(const Simulation& sim, const RunState&, RunSummary& sum) {
  const auto& product = sim.product();
  const double fines = sum.mass_removed;  // removed inside the scene: finer than every sieve
  std::vector<double> sizes, masses;
  double smin = std::numeric_limits<double>::infinity(), smax = 0;
  for (const auto& p : product) {
    sizes.push_back(p.sieve);
    masses.push_back(p.mass);
    smin = std::min(smin, p.sieve);
    smax = std::max(smax, p.sieve);
  }
  const double total = sim.product_mass() + fines;
  std::ostringstream os;
  os << std::setprecision(10) << csv_header("product_psd.csv") << '\n';
  if (!product.empty()) {
    // Sieves: the series 1 mm · 2^(k/2) (a √2 series, as laboratory sieves) spanning the product.
    const int k0 = static_cast<int>(std::floor(2 * std::log2(smin / 1e-3))) - 1;
    const int k1 = static_cast<int>(std::ceil(2 * std::log2(smax / 1e-3))) + 1;
    std::vector<double> sieves;
    for (int k = k0; k <= k1; ++k) sieves.push_back(1e-3 * std::pow(2.0, k / 2.0));
    std::vector<double> all_sizes = sizes, all_masses = masses;
    all_sizes.push_back(0.0);  // fines removed inside the scene pass every sieve
    all_masses.push_back(fines);
    const std::vector<double> pass = percent_passing(all_sizes, all_masses, sieves);
    for (std::size_t k = 0; k < sieves.size(); ++k) os << sieves[k] << ',' << pass[k] << ',' << pass[k] / 100 * total << '\n';
  }
  write_file_atomic(dir_ + "/product_psd.csv", os.str());
  std::ostringstream pr;
  pr << std::setprecision(10) << csv_header("product.csv") << '\n';
  for (const auto& p : product)
    pr << p.time << ',' << p.id << ',' << p.origin << ',' << p.generation << ',' << p.diameter << ',' << p.sieve << ','
       << p.mass << '\n';
  write_file_atomic(dir_ + "/product.csv", pr.str());
  for (const auto& [k, v] : figures_) sum.extra[k] = v;
  sum.extra["product_psd_mass_kg"] = total;
  if (!product.empty()) {
    // d50 of the product PSD (fines at size 0).
    if (fines > 0) {
      sizes.push_back(0.0);
      masses.push_back(fines);
    }
    sum.extra["product_d50_m"] = mass_quantile(sizes, masses, 0.5);
    sum.extra["product_sieve_min_m"] = smin;
    sum.extra["product_sieve_max_m"] = smax;
  }
}

}  // namespace crumble
