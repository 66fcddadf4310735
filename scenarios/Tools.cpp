#include "scenarios/Tools.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <chrono>
#include <cstdlib>
#include <ctime>

#include "crumble_config.h"

#include "backends/lsdem/LsdemEngine.h"
#if CRUMBLE_WITH_BULLET
#include "backends/bullet/BulletEngine.h"
#include "backends/bullet/RawBulletBench.h"
#endif
#if CRUMBLE_WITH_ODE
#include "backends/ode/OdeEngine.h"
#include "backends/ode/RawOdeBench.h"
#endif
#include "core/RawScene.h"
#include "breakage/peridynamics/Peridynamics.h"
#include "core/Analysis.h"
#include "scenarios/Packing.h"
#include "geometry/ConvexHull.h"
#include "geometry/Format.h"
#include "geometry/LevelSetGrid.h"
#include "scenarios/Checkpoint.h"
#include "scenarios/Compare.h"
#include "scenarios/Registry.h"
#include "scenarios/ShapeSpec.h"
#include "scenarios/VtkWriter.h"
#include "scenarios/Stages.h"
#include "scenarios/LayerOutputs.h"
#include "scenarios/Writers.h"

namespace crumble {

using Json = nlohmann::json;

namespace {

// Single-grain crushing (Zhu & Zhao 2019 §4.2): the first breakage gives the crushing force,
// the characteristic strength F/d² and the fragments.
class CrushingRecorder : public Observer {
 public:
  explicit CrushingRecorder(std::string dir) : dir_(std::move(dir)) {}
  void on_start(const Simulation& sim, const RunState&) override {
    if (!sim.grains().empty()) d_ = sim.grains().front().shape->equivalent_diameter();
  }
  void on_sample(const Simulation&, const RunState& s) override { max_force_ = std::max(max_force_, s.platen_force); }
  void on_breakage(const Simulation&, const BreakageEvent& e) override {
    if (done_) return;
    done_ = true;
    // The model's force at failure: peridynamics reports the force reached when the grain
    // split (force_at_split_N); other models fail under the contact forces given, so the
    // largest of them. Stress models also give the equivalent stress at failure.
    const double split = e.analysis.figure("force_at_split_N", 0);
    force_ = split > 0 ? split : e.analysis.load;
    stress_ = e.analysis.figure("equivalent_stress_Pa", -1);
    platen_ = e.platen_stress;
    diam_ = e.child_diameters;
  }
  void on_finish(const Simulation&, const RunState&, RunSummary& sum) override {
    sum.extra["diameter_m"] = d_;
    sum.extra["max_platen_force_N"] = max_force_;
    const LoadDisplacement ld = write_load_displacement_csv(dir_);
    if (!ld.load.empty()) sum.extra["displacement_at_max_force_m"] = ld.displacement_at_peak;
    if (!done_) return;
    sum.extra["crushing_force_N"] = force_;
    if (stress_ >= 0) sum.extra["crushing_stress_Pa"] = stress_;
    sum.extra["characteristic_strength_Pa"] = force_ / (d_ * d_);
    sum.extra["fragment_count"] = static_cast<double>(diam_.size());
    sum.extra_arrays["fragment_diameters_m"] = diam_;
  }

 private:
  std::string dir_;
  double d_ = 0, force_ = 0, platen_ = 0, max_force_ = 0, stress_ = -1;
  bool done_ = false;
  std::vector<double> diam_;
};

// ncl.csv (void ratio and grain count against log stress), and the NCL slope and fractal
// dimension for summary.json. Read from the finished series.csv (the SeriesWriter is
// attached first), so a resumed run covers its whole history.
class CompressionRecorder : public Observer {
 public:
  explicit CompressionRecorder(std::string dir) : dir_(std::move(dir)) {}
  void on_finish(const Simulation& sim, const RunState&, RunSummary& sum) override {
    const auto rows = read_csv(dir_ + "/series.csv");
    for (std::size_t i = 1; i < rows.size(); ++i) {
      if (rows[i].size() < 8) continue;
      stress_.push_back(std::atof(rows[i][3].c_str()));
      e_.push_back(std::atof(rows[i][6].c_str()));
      n_.push_back(static_cast<std::size_t>(std::atol(rows[i][7].c_str())));
    }
    std::ostringstream os;
    os << std::setprecision(10) << "platen_stress_Pa,log10_stress,void_ratio,grains\n";
    for (std::size_t i = 0; i < stress_.size(); ++i)
      if (stress_[i] > 0) os << stress_[i] << ',' << std::log10(stress_[i]) << ',' << e_[i] << ',' << n_[i] << '\n';
    write_file_atomic(dir_ + "/ncl.csv", os.str());
    // Zhu & Zhao 2019 §5: the NCL is about linear in log e – log σ (slope ≈ −0.52 there); fit
    // over the upper part of the loading (σ ≥ 0.3 σ_max), also as e – log σ (C_c).
    const NclFit ncl = fit_ncl_upper(stress_, e_);
    if (std::isfinite(ncl.loglog_slope)) sum.extra["ncl_loglog_slope"] = ncl.loglog_slope;
    if (std::isfinite(ncl.compression_index)) sum.extra["ncl_compression_index"] = ncl.compression_index;
    psd_summary(sum, sim.context().dimension);
    std::vector<double> d;
    for (const auto& g : sim.grains()) d.push_back(g.shape->equivalent_diameter());
    // Only meaningful once grains have broken into a spread of sizes.
    const double D = sum.breakage_events > 0 ? fractal_dimension(d) : std::nan("");
    if (std::isfinite(D)) sum.extra["fractal_dimension_final"] = D;
  }

 private:
  // psd_summary.csv: per table of the finished psd.csv, the fractal dimension read from the
  // PSD by mass and Hardin's relative breakage against the initial table (core/Analysis.h);
  // summary.json relative_breakage_final. From the file, so a resumed run covers its history.
  void psd_summary(RunSummary& sum, int dimension) const {
    struct Table {
      std::string label, stress, strain;
      std::vector<double> sieves, passing;
    };
    std::vector<Table> tables;
    const auto rows = read_csv(dir_ + "/psd.csv");
    for (std::size_t i = 1; i < rows.size(); ++i) {
      if (rows[i].size() < 5) continue;
      if (tables.empty() || tables.back().label != rows[i][0]) tables.push_back({rows[i][0], rows[i][1], rows[i][4], {}, {}});
      tables.back().sieves.push_back(std::atof(rows[i][2].c_str()));
      tables.back().passing.push_back(std::atof(rows[i][3].c_str()));
    }
    const Table* initial = nullptr;
    for (const auto& t : tables)
      if (t.label == "initial") initial = &t;
    std::ostringstream os;
    os << std::setprecision(10)
       << "label,platen_stress_Pa,axial_strain,fractal_dimension_by_mass,relative_breakage,breakage_cutoff_m\n";
    auto cell = [](double v) { return std::isfinite(v) ? fmt_num(v) : std::string(); };  // never NaN in a file
    for (const auto& t : tables) {
      const double D = fractal_dimension_by_mass(t.sieves, t.passing, dimension);
      const double br = initial && initial->sieves == t.sieves
                            ? relative_breakage_sieved(t.sieves, initial->passing, t.passing)
                            : std::nan("");
      os << t.label << ',' << t.stress << ',' << t.strain << ',' << cell(D) << ',' << cell(br) << ','
         << fmt_num(kHardinCutoff) << '\n';
      if (t.label == "final" && std::isfinite(br)) sum.extra["relative_breakage_final"] = br;
    }
    write_file_atomic(dir_ + "/psd_summary.csv", os.str());
  }

  std::string dir_;
  std::vector<double> stress_, e_;
  std::vector<std::size_t> n_;
};

// Figures `crumble compare` tabulates, in summary.json: the void ratio at each reported
// stress or strain level (output.psd_at_stress / psd_at_strain: interpolated between the two
// series samples around the first crossing, core/Analysis.h value_at_level; read from the
// finished series.csv so a resumed run covers its whole history), and d50 and the fines fraction of the final size distribution by mass.
class ReportRecorder : public Observer {
 public:
  ReportRecorder(std::string dir, std::vector<double> stresses, std::vector<double> strains, double fines_size)
      : dir_(std::move(dir)), stresses_(std::move(stresses)), strains_(std::move(strains)), fines_size_(fines_size) {}
  void on_finish(const Simulation& sim, const RunState&, RunSummary& sum) override {
    const auto rows = read_csv(dir_ + "/series.csv");
    std::vector<double> stress, strain, voids;
    for (std::size_t i = 1; i < rows.size(); ++i) {
      if (rows[i].size() < 8) continue;
      stress.push_back(std::atof(rows[i][3].c_str()));
      strain.push_back(std::atof(rows[i][5].c_str()));
      voids.push_back(std::atof(rows[i][6].c_str()));
    }
    for (double s : stresses_) {
      const double e = value_at_level(stress, voids, s);
      if (std::isfinite(e)) sum.extra[void_ratio_stress_key(s)] = e;
    }
    for (double s : strains_) {
      const double e = value_at_level(strain, voids, s);
      if (std::isfinite(e)) sum.extra[void_ratio_strain_key(s)] = e;
    }
    // Final PSD by mass: removed fines count at size 0 (Harmon et al. 2020 §3.4: removed
    // particles stay in the PSD).
    std::vector<double> sizes, masses;
    double fines = sum.mass_removed, total = sum.mass_removed;
    for (const auto& g : sim.grains()) {
      const double d = g.shape->equivalent_diameter();
      const double m = g.shape->volume() * sim.context().materials[g.material].density;
      sizes.push_back(d);
      masses.push_back(m);
      total += m;
      if (d < fines_size_) fines += m;
    }
    if (sum.mass_removed > 0) {
      sizes.push_back(0.0);
      masses.push_back(sum.mass_removed);
    }
    const Gradation g = gradation(sizes, masses);
    if (std::isfinite(g.d50)) sum.extra["psd_d50_final_m"] = g.d50;
    if (std::isfinite(g.d10)) sum.extra["psd_d10_final_m"] = g.d10;
    if (std::isfinite(g.d60)) sum.extra["psd_d60_final_m"] = g.d60;
    if (std::isfinite(g.uniformity)) sum.extra["psd_uniformity_final"] = g.uniformity;
    if (total > 0) sum.extra["fines_fraction_final"] = fines / total;
    sum.extra["fines_size_m"] = fines_size_;
  }

 private:
  std::string dir_;
  std::vector<double> stresses_, strains_;
  double fines_size_;
};

Json mass_json(const MassProperties& mp) {
  Json I = Json::array();
  for (int i = 0; i < 3; ++i) I.push_back({mp.inertia(i, 0), mp.inertia(i, 1), mp.inertia(i, 2)});
  return {{"volume", mp.volume}, {"centroid", {mp.centroid.x, mp.centroid.y, mp.centroid.z}}, {"inertia", I}};
}

double perimeter(const std::vector<Vec3>& poly) {
  double p = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) p += norm(poly[(i + 1) % poly.size()] - poly[i]);
  return p;
}

}  // namespace

void attach_standard_observers(Scenario& sc, const std::string& out, const Json& checkpoint_info) {
  Simulation& sim = *sc.sim;
  const bool resumed = sim.resumed();
  const SimulationState st = sim.saved_state();
  sim.add_observer(std::make_shared<SeriesWriter>(out, resumed ? st.step : -1));
  sim.add_observer(std::make_shared<EventsWriter>(out, sim.model().figure_names(), resumed ? st.step : -1L,
                                                  sc.output.intact_analyses));
  // The strain at the checkpoint, as Simulation::state() computes it.
  const double resume_strain =
      resumed && st.initial_height > 0 ? (st.initial_height - st.platen_position) / st.initial_height : -1.0;
  sim.add_observer(std::make_shared<PsdWriter>(out, sc.output.psd_at_stress, resumed ? st.max_platen_stress : -1.0,
                                               sc.output.psd_at_strain, resume_strain, resumed ? st.step : -1L));
  if (sc.output.shape_metrics)
    sim.add_observer(std::make_shared<ShapeWriter>(out, sim.context().dimension, resumed ? st.step : -1));
  if (sc.output.vtk_every > 0 || sc.output.vtk_final)
    sim.add_observer(std::make_shared<VtkWriter>(
        out, VtkWriter::Settings{sc.output.vtk_every, sc.output.vtk_final, sc.output.vtk_contacts, sc.packing.container.height},
        resumed ? st.step : -1));
  if (sc.output.vtk_analyses) sim.add_observer(std::make_shared<AnalysisVtkWriter>(out, resumed ? st.step : -1));
  sim.add_observer(std::make_shared<StagesWriter>(
      out, sim.loading().settings().mode == "strain_rate" ? StagesWriter::Axis::Strain : StagesWriter::Axis::Stress,
      resumed ? st.step : -1L));
  sim.add_observer(std::make_shared<CompressionRecorder>(out));
  {
    // Fines: finer than the crushing limit (screening.min_diameter, Zhu & Zhao 2019 §5: grains
    // below it are not analysed) or simulation.fines_diameter (removed, Harmon et al. 2020 §3.4).
    const Json& e = sc.effective;
    double fines_size = 0;
    if (e.contains("screening") && e["screening"].is_object() && e["screening"].contains("min_diameter") &&
        e["screening"]["min_diameter"].is_number())
      fines_size = e["screening"]["min_diameter"].get<double>();
    if (e.contains("simulation") && e["simulation"].is_object() && e["simulation"].contains("fines_diameter") &&
        e["simulation"]["fines_diameter"].is_number())
      fines_size = std::max(fines_size, e["simulation"]["fines_diameter"].get<double>());
    sim.add_observer(std::make_shared<ReportRecorder>(out, sc.output.psd_at_stress, sc.output.psd_at_strain, fines_size));
  }
  // Last of the writers: every row of a checkpointed step is on disk before the checkpoint.
  if (sc.output.checkpoint_every > 0 || sc.output.checkpoint_every_s > 0)
    sim.add_observer(std::make_shared<CheckpointWriter>(out, sc.name, sc.output.checkpoint_every,
                                                        sc.output.checkpoint_every_s, checkpoint_info));
  if (sim.grains().size() == 1 && sim.model().active()) sim.add_observer(std::make_shared<CrushingRecorder>(out));
  else sim.add_observer(std::make_shared<LoadDisplacementWriter>(out));
  if (sc.output.psd_layers > 0) sim.add_observer(std::make_shared<LayerPsdWriter>(out, static_cast<int>(sc.output.psd_layers)));
  if (sim.container().open) sim.add_observer(std::make_shared<ProductWriter>(out, sc.packing.scene_figures));
}

Json shape_report(const std::string& spec, const std::string& repr, double spacing, long nodes) {
  std::string text = spec;
  if (!spec.empty() && spec.front() != '{') {
    std::ifstream in(spec);
    if (!in) throw ConfigError("--json", "neither inline JSON nor a readable file: '" + spec + "'");
    std::stringstream ss;
    ss << in.rdbuf();
    text = ss.str();
  }
  Json doc = parse_json_text(text, "--json");
  if (!doc.is_object()) throw ConfigError("--json", "expected a shape object");
  // NaN compares false with everything: without the isfinite test it fell through to the
  // automatic spacing silently.
  if (!std::isfinite(spacing) || spacing < 0)
    throw ConfigError("--spacing", "expected a finite grid spacing > 0 (m), got " + fmt_num(spacing));
  if (nodes < 0) throw ConfigError("--nodes", "must be > 0");
  if (spacing > 0 || nodes > 0) {
    Json& r = doc["resolution"];
    if (spacing > 0) r["level_set_spacing"] = spacing;
    if (nodes > 0) r["surface_nodes"] = nodes;
  }
  Config c(doc);
  const int dim = static_cast<int>(c.integer("dimension", 3, 2, 3));
  Shape::Ptr s = shape_from_config(c, dim);
  c.check_unknown();
  Json j;
  j["shape"] = s->describe();
  j["representation"] = repr;
  j["exact"] = mass_json(s->mass_properties());
  j["equivalent_diameter"] = s->equivalent_diameter();
  if (repr == "level_set") {
    const LevelSetGrid& g = s->level_set();
    Json m = mass_json(g.mass_properties());
    j.update(m);
    const auto n = g.counts();
    j["grid"] = {n[0], n[1], n[2]};
    j["spacing"] = g.spacing();
    j["nodes"] = g.nodes().size();
    double area = 0;
    for (double w : g.node_weights()) area += w;
    j[dim == 2 ? "perimeter" : "surface_area"] = area;
  } else if (dim == 2) {
    const auto& o = s->outline();
    j["volume"] = s->volume();
    j["perimeter"] = perimeter(o);
    j["nodes"] = o.size();
  } else {
    const TriMesh& m = repr == "mesh" ? s->mesh() : s->convex_hull();
    j.update(mass_json(polyhedron_mass_properties(m)));
    j["surface_area"] = surface_area(m);
    j["nodes"] = m.vertices.size();
    j["triangles"] = m.triangles.size();
  }
  // Shape descriptors of the outline (2D) or surface mesh (3D), as shape.csv reports them.
  const GrainShapeMetrics gm = grain_shape_metrics(*s);
  for (const auto& [k, v] : {std::pair<const char*, double>{"circularity", gm.circularity},
                             {"aspect_ratio", gm.aspect_ratio}, {"sieve_size", gm.sieve_size},
                             {"sphericity", gm.sphericity}, {"zingg_ei", gm.elongation}, {"zingg_fi", gm.flatness}})
    if (std::isfinite(v)) j[k] = v;
  return j;
}

namespace {

Json phase_json(const LsdemBenchResult& r) {
  return {{"steps", r.steps},
          {"wall_seconds", r.seconds},
          {"cpu_seconds", r.cpu_seconds},
          {"ms_per_step", r.ms_per_step},
          {"cpu_ms_per_step", r.cpu_ms_per_step},
          {"steps_per_second", r.steps_per_second},
          {"node_queries_per_second", r.node_queries_per_second},
          {"bbox_overlaps_per_step", r.mean_bbox_overlaps},
          {"contact_pairs_per_step", r.mean_contact_pairs},
          {"node_queries_per_step", r.mean_node_queries}};
}


// The loop phase of `bench engine` and `bench lsdem`: the same engine, from where the timed
// adapter steps left it, stepped `steps` times by the simulation's own loop (Simulation::run:
// the state read-out and scalar checks of every step, the guards of every sample; no
// observers, no output). The benchmarks replace the scenario's loading by "none" (platen held
// still, as in the adapter phase), so the two phases step the same scene. Its wall time per step against
// the adapter's is the loop overhead (goal of issue 12: <= 10 % on every engine). The run's
// breakage checks are timed apart (they are the model's work, not the loop's).
Json loop_phase(Simulation& sim, long steps, double dt, double adapter_ms_per_step) {
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  RunSummary s;
  sim.set_time_step(dt);
  try {
    s = sim.run();
  } catch (const std::exception& e) {
    return Json{{"error", e.what()}};
  }
  const double wall = std::chrono::duration<double>(clock::now() - t0).count();
  const Timings& t = s.timings;
  const double breakage = t.contacts + t.screening + t.analyses + t.fragments;
  const double n = static_cast<double>(std::max(1L, s.steps));
  // The adapter again, after the loop, from where the loop left the scene: a scene that
  // slows down or speeds up as it settles falls on both sides of the loop phase alike.
  Engine& eng = sim.engine();
  const auto a0 = clock::now();
  for (long k = 0; k < s.steps; ++k) eng.step(dt);
  const double after_ms = 1e3 * std::chrono::duration<double>(clock::now() - a0).count() / n;
  const double adapter_ms = 0.5 * (adapter_ms_per_step + after_ms);
  Json j;
  j["steps"] = s.steps;
  j["ms_per_step"] = 1e3 * (wall - breakage) / n;
  j["engine_ms_per_step"] = 1e3 * t.engine / n;
  j["loop_ms_per_step"] = 1e3 * t.loop / n;
  j["guards_ms_per_step"] = 1e3 * t.guards / n;
  j["breakage_checks_s"] = breakage;
  j["adapter_after_ms_per_step"] = after_ms;
  j["loop_overhead_vs_adapter"] = adapter_ms > 0 ? 1e3 * (wall - breakage) / n / adapter_ms - 1 : 0.0;
  j["loop_overhead_vs_engine_in_loop"] = t.engine > 0 ? (t.loop + t.guards + t.observers) / t.engine : 0.0;
  if (s.steps < steps) j["note"] = "the scenario's loading ended after " + std::to_string(s.steps) + " steps";
  return j;
}

// `crumble bench lsdem --scenario F`: the loose phase (grains falling) and the settled
// packing of the scenario's scene, each over `steps` steps. YADE 2023.02a on the same scene
// was measured once on this kind of machine (../shared/bench/README.md): ≈ 12 ms/step loose,
// ≈ 82 ms/step settled at ≈ 2500 bounding-box overlaps.
Json bench_lsdem(long steps, int threads, const std::string& file) {
  if (file.empty()) throw ConfigError("--scenario", "bench lsdem needs --scenario (e.g. scenarios/lsdem_discharge.json)");
  BuildOptions opt;
  opt.threads = threads;
  opt.source_name = file;
  Json doc = load_scenario_file(file);
  doc["simulation"]["max_steps"] = steps;  // the loop phase: `steps` steps of Simulation::run,
  doc["loading"] = Json{{"mode", "none"}};  // with the platen held still as in the adapter phase
  Scenario sc = build_scenario(doc, opt);
  auto* eng = dynamic_cast<LsdemEngine*>(&sc.sim->engine());
  if (!eng) throw ConfigError(file + ": /engine/type", "bench lsdem needs an lsdem scenario");
  sc.packing.settle = false;
  build_packing(*sc.sim, sc.packing);
  const double dt = std::min(sc.sim->settings().time_steps.front().dt, eng->max_stable_dt());
  const LsdemBenchResult loose = lsdem_bench_phase(*eng, steps, dt);
  // Let the grains land and come to rest: until the kinetic energy per grain is below
  // 1e-6 of m g d of the mean grain, or the scenario's simulated duration.
  const auto& gs = sc.sim->grains();
  double md = 0, dmean = 0;
  for (const auto& g : gs) {
    md += g.mass(sc.sim->context().materials[g.material].density);
    dmean += g.shape->equivalent_diameter();
  }
  dmean /= gs.size();
  const double ke_rest = 1e-6 * md * 9.81 * dmean;
  const double t_max = sc.sim->loading().settings().duration > 0 ? sc.sim->loading().settings().duration : 1.0;
  long settle_steps = 0;
  for (double t = 0; t < t_max; t += dt, ++settle_steps) {
    eng->step(dt);
    if (settle_steps % 1000 == 999 && eng->kinetic_energy() < ke_rest) break;
  }
  const LsdemBenchResult settled = lsdem_bench_phase(*eng, steps, dt);
  Json j;
  j["benchmark"] = "lsdem";
  j["scenario"] = file;
  j["grains"] = gs.size();
  j["threads"] = threads;
  j["dt_s"] = dt;
  j["settle_steps"] = settle_steps;
  j["kinetic_energy_J"] = eng->kinetic_energy();
  j["loose"] = phase_json(loose);
  j["settled"] = phase_json(settled);
  j["yade_reference_ms_per_step"] = {{"loose", 12.0}, {"settled", 82.0}};
  j["speedup_vs_yade_reference"] = {{"loose", 12.0 / loose.ms_per_step}, {"settled", 82.0 / settled.ms_per_step}};
  j["loop"] = loop_phase(*sc.sim, steps, dt, settled.ms_per_step);
  return j;
}


// The grains of a simulation as library-neutral rigid bodies (SI), for the raw baselines.
RawScene raw_scene_of(const Simulation& sim, const Container& box, double dt) {
  RawScene r;
  const auto& mats = sim.context().materials;
  for (const Grain& g : sim.grains()) {
    const Material& m = mats[g.material];
    const MassProperties& mp = g.shape->mass_properties();
    RawBody b;
    b.hull = g.shape->convex_hull();
    b.hull.translate(Vec3{} - mp.centroid);
    b.mass = m.density * mp.volume;
    b.inertia = mp.inertia * m.density;
    const Quat q = g.orientation.normalized();
    b.com = g.position + q.rotate(mp.centroid);
    b.orientation = q;
    b.velocity = g.velocity;
    b.angular_velocity = g.angular_velocity;
    b.friction = m.friction;
    b.rolling_friction = m.rolling_friction;
    r.bodies.push_back(std::move(b));
  }
  r.lx = box.lx;
  r.ly = box.ly;
  r.platen_z = sim.engine().platen_position();
  r.wall_friction = mats.empty() ? 0 : mats.front().wall_friction;
  r.gravity = sim.context().gravity;
  r.dt = dt;
  return r;
}

// `crumble bench engine --engine E [--scenario F]`: the scenario's packing (placed, not
// settled) on engine E; `settle` steps let the grains fall into contact, then `steps` steps
// are timed through the adapter (Engine::step, and separately the read-out the Simulation
// does: read_state + contacts) and, for bullet and ode, through the raw library on the same
// bodies from the same state (RawBulletBench / RawOdeBench). The adapter runs with the raw
// baseline's solver settings (fixed iterations: Bullet's tolerance exit off; ODE the
// scenario's contact points per pair in both), so both do the same solver work. Then the
// same number of steps through the simulation's loop (loop_phase).
Json bench_engine(const std::string& engine, long steps, long settle, int threads, const std::string& file_in) {
  const std::string file = file_in.empty() ? "scenarios/oedometer_rigid_quick.json" : file_in;
  Json doc = load_scenario_file(file);
  if (!doc.contains("engine") || !doc["engine"].is_object()) doc["engine"] = Json::object();
  const Json scenario_engine = doc["engine"];
  doc["engine"]["type"] = engine;
  if (engine == "bullet") {
    doc["engine"]["solver_tolerance"] = 0;
    doc["engine"]["solver_residual"] = 0;
  }
  doc["simulation"]["max_steps"] = steps;  // the loop phase: `steps` steps of Simulation::run,
  doc["loading"] = Json{{"mode", "none"}};  // with the platen held still as in the adapter phase
  BuildOptions opt;
  opt.threads = threads;
  opt.source_name = file;
  Scenario sc = build_scenario(doc, opt);
  if (sc.sim->context().dimension != 3 && engine != "lsdem")
    throw ConfigError(file + ": /dimension", "bench engine compares 3D scenes");
  // settle < 0: the scenario's own packing procedure (settled under the platen, as `run`
  // does); otherwise the grains are placed and fall for `settle` steps.
  if (settle >= 0) sc.packing.settle = false;
  const auto t_settle = std::chrono::steady_clock::now();
  build_packing(*sc.sim, sc.packing);
  Engine& eng = sc.sim->engine();
  const double dt = std::min(sc.sim->settings().time_steps.front().dt, eng.max_stable_dt());
  eng.set_platen(PlatenCommand{});
  for (long k = 0; k < settle; ++k) eng.step(dt);
  const double settle_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_settle).count();
  sc.sim->sync_grains();
  RawScene raw = raw_scene_of(*sc.sim, sc.sim->container(), dt);

  // The raw world gets the adapter's solver settings and length scale; both start from
  // this state and are stepped alternately, so the machine's load falls on both alike.
  std::unique_ptr<RawWorld> raw_world;
  Json engine_section = sc.effective["engine"];
  const Config engine_cfg(engine_section);
  // The solver settings both rigid-body adapters share, read from the adapter's own options.
  auto shared_settings = [&](const auto& o, double length_scale) {
    raw.solver_iterations = o.solver_iterations;
    raw.erp = o.erp;
    raw.mass_scale = o.mass_scale;
    raw.length_scale = length_scale;
  };
#if CRUMBLE_WITH_BULLET
  if (auto* b = dynamic_cast<BulletEngine*>(&eng)) {
    const auto o = BulletEngine::read_options(engine_cfg);
    shared_settings(o, b->length_scale());
    raw.margin_fraction = o.margin_fraction;
    raw_world = make_raw_bullet_world(raw);
  }
#endif
#if CRUMBLE_WITH_ODE
  if (auto* e = dynamic_cast<OdeEngine*>(&eng)) {
    const auto o = OdeEngine::read_options(engine_cfg);
    shared_settings(o, e->length_scale());
    raw.contacts_per_pair = o.contacts_per_pair;
    raw_world = make_raw_ode_world(raw);
  }
#endif
  using clock = std::chrono::steady_clock;
  auto seconds = [](clock::time_point a, clock::time_point b) { return std::chrono::duration<double>(b - a).count(); };
  double t_step = 0, t_read = 0, t_raw = 0, contacts = 0, raw_contacts = 0;
  std::vector<Grain> grains = sc.sim->grains();
  for (long k = 0; k < steps; ++k) {
    const auto a = clock::now();
    eng.step(dt);
    const auto b = clock::now();
    eng.read_state(grains);
    contacts += static_cast<double>(eng.contacts().size());
    const auto c = clock::now();
    t_step += seconds(a, b);
    t_read += seconds(b, c);
    if (raw_world) {
      const auto d = clock::now();
      raw_world->step();
      t_raw += seconds(d, clock::now());
      raw_contacts += raw_world->contact_pairs();
    }
  }
  Json j;
  j["benchmark"] = "engine";
  j["engine"] = engine;
  j["scenario"] = file;
  j["grains"] = sc.sim->grains().size();
  j["threads"] = threads;
  j["dt_s"] = dt;
  j["settle"] = settle < 0 ? Json("scenario packing procedure") : Json(settle);
  j["settle_wall_s"] = settle_s;
  j["steps"] = steps;
  j["adapter"] = {{"ms_per_step", 1e3 * t_step / steps},
                  {"readout_ms_per_step", 1e3 * t_read / steps},
                  {"contacts_per_step", contacts / steps}};
  if (raw_world) {
    const double raw_ms = 1e3 * t_raw / steps;
    j["raw"] = {{"ms_per_step", raw_ms}, {"contacts_per_step", raw_contacts / steps}};
    j["adapter_overhead"] = t_step / t_raw - 1;
    j["adapter_overhead_with_readout"] = (t_step + t_read) / t_raw - 1;
  } else {
    j["raw"] = nullptr;
    j["note"] = engine + " is crumble's own engine: there is no raw library to compare with";
  }
  j["loop"] = loop_phase(*sc.sim, steps, dt, 1e3 * t_step / steps);
  return j;
}

// `crumble bench pd-analysis [--scenario F] [--steps R] [--threads N]`: the breakage analysis
// that crushes a grain, alone. The scenario (default scenarios/single_grain_pd.json) gives the
// peridynamic options, the material and the size (scene.diameter, else d0); the grain, of G_c
// gc0 scaled by eq. 15 to that size, is pressed by two opposite contacts at 1.5 × the load of
// the reference grain scaled as √G_c·d² (Zhu & Zhao 2019, eq. 14), so the analysis ramps the
// load until the grain splits, as the analysis of a breakage check that crushes it does. R
// repeats; wall and CPU time per analysis, with the crushing force and the steps. breakage.threads
// is set from --threads.
Json bench_pd_analysis(long repeats, int threads, const std::string& file_in) {
  const std::string file = file_in.empty() ? "scenarios/single_grain_pd.json" : file_in;
  Json doc = load_scenario_file(file);
  if (!doc.contains("breakage") || !doc["breakage"].is_object() || doc["breakage"].value("type", "") != "peridynamics")
    throw ConfigError(file + ": /breakage/type", "bench pd-analysis needs a peridynamics scenario");
  doc["breakage"]["threads"] = threads;
  BuildOptions opt;
  opt.threads = 1;
  opt.source_name = file;
  Scenario sc = build_scenario(doc, opt);
  const auto& model = sc.sim->model();
  const Json& b = sc.effective["breakage"];
  const double gc0 = b.value("gc0", 30.0), d0 = b.value("d0", 2e-3);
  double d = d0;
  if (doc.contains("scene") && doc["scene"].is_object() && doc["scene"].contains("diameter"))
    d = doc["scene"]["diameter"].get<double>();
  const Material& m = sc.sim->context().materials.front();
  Json breakage_section = b;
  const PdOptions o = pd_options_from_config(Config(breakage_section));
  Grain g;
  g.id = 1;
  g.shape = Shape::sphere(d / 2);
  g.strength.set(PeridynamicsModel::kGc, pd_child_gc(o, gc0, d, d0));
  const double load = 1.5 * 180.0 * std::sqrt(g.strength.get_or(PeridynamicsModel::kGc, gc0) / gc0) * (d / d0) * (d / d0);
  std::vector<Contact> c(2);
  c[0].a = c[1].a = g.id;
  c[0].wall = kPlaten, c[0].point = {0, 0, d / 2}, c[0].force = {0, 0, -load};
  c[1].wall = kFloor, c[1].point = {0, 0, -d / 2}, c[1].force = {0, 0, load};
  auto cpu_now = [] {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
  };
  double wall = 0, wall_min = 1e300, cpu = 0;
  BreakageAnalysis a;
  for (long k = 0; k < repeats; ++k) {
    const double c0 = cpu_now();
    const auto t0 = std::chrono::steady_clock::now();
    a = model.analyse(g, m, c);
    const double w = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    cpu += cpu_now() - c0;
    wall += w;
    wall_min = std::min(wall_min, w);
  }
  Json j;
  j["benchmark"] = "pd-analysis";
  j["scenario"] = file;
  j["diameter_m"] = d;
  j["gc_J_m2"] = g.strength.get_or(PeridynamicsModel::kGc, gc0);
  j["density_scale"] = o.density_scale;
  j["threads"] = threads;
  j["load_N"] = load;
  j["outcome"] = a.outcome;
  j["force_at_split_N"] = a.figure("force_at_split_N");
  j["points"] = a.figure("points");
  j["bonds"] = a.figure("bonds");
  j["steps"] = a.figure("steps");
  j["repeats"] = repeats;
  j["wall_s_per_analysis"] = wall / repeats;
  j["wall_s_min"] = wall_min;
  j["cpu_s_per_analysis"] = cpu / repeats;
  double la[3] = {0, 0, 0};
  if (getloadavg(la, 3) == 3) j["load_average"] = {la[0], la[1], la[2]};
  return j;
}

}  // namespace

Json run_benchmark(const std::string& what, long steps, int threads, const std::string& scenario,
                   const std::string& engine, long settle_steps) {
  if (steps <= 0) steps = what == "pd-analysis" ? 3 : 1000;
  if (what == "engine") {
    if (engine.empty()) throw ConfigError("--engine", "bench engine needs --engine (known: " + engines().names() + ")");
    engines().find(engine, "--engine");
    return bench_engine(engine, steps, settle_steps, threads, scenario);
  }
  if (engine != "") throw ConfigError("--engine", "only `bench engine` takes --engine");
  if (what == "lsdem") return bench_lsdem(steps, threads, scenario);
  if (what == "pd-kernel") {
    // The LPS kernel on the lattice of LAMMPS's examples/peri cylinder (3487 points). LAMMPS
    // peri/lps on this machine kind: 19.4 s per 1000 steps (../shared/bench/README.md;
    // measured again by the peridynamics work: 13.8–14.7 s), ≈ 1.7e7 bond visits/s per core.
    Json j = Json::parse(pd_kernel_bench(steps, threads));
    j["benchmark"] = "pd-kernel";
    return j;
  }
  if (what == "pd-analysis") return bench_pd_analysis(steps, threads, scenario);
  throw ConfigError("bench " + what, "unknown benchmark; known: engine, lsdem, pd-kernel, pd-analysis");
}

}  // namespace crumble
