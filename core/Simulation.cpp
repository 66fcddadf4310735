#include "core/Simulation.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace crumble {

namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}
}  // namespace

bool Schedule::due(long step, double stress) {
  bool d = false;
  if (s_.every_steps > 0 && step % s_.every_steps == 0) d = true;
  if (s_.every_stress > 0 && stress >= last_stress_ + s_.every_stress) {
    // Advance by whole intervals so a jump in stress triggers one check, not many.
    last_stress_ += s_.every_stress * std::floor((stress - last_stress_) / s_.every_stress);
    d = true;
  }
  return d;
}

Simulation::Simulation(std::unique_ptr<Engine> engine, std::unique_ptr<BreakageModel> model,
                       std::unique_ptr<FragmentBuilder> builder, EngineContext ctx,
                       SimulationSettings settings, LoadingSettings loading, ScheduleSettings schedule,
                       ScreeningSettings screening, std::uint64_t seed)
    : engine_(std::move(engine)),
      model_(std::move(model)),
      builder_(std::move(builder)),
      ctx_(std::move(ctx)),
      settings_(std::move(settings)),
      loading_(loading),
      schedule_(schedule),
      screening_(screening),
      rng_(seed) {
  if (!engine_) throw std::invalid_argument("Simulation needs an engine");
  if (!model_) throw std::invalid_argument("Simulation needs a breakage model");
  if (settings_.time_steps.empty()) throw std::invalid_argument("Simulation needs at least one time step rule");
}

Simulation::~Simulation() = default;

void Simulation::set_container(const Container& c) {
  container_ = c;
  initial_height_ = c.height;
  engine_->set_container(c);
}

GrainId Simulation::add_grain(Grain g) {
  if (!g.shape) throw std::invalid_argument("grain without a shape");
  if (g.shape->dimension() != ctx_.dimension)
    throw std::invalid_argument("grain shape " + g.shape->describe() + " is " +
                                std::to_string(g.shape->dimension()) + "D but the scenario is " +
                                std::to_string(ctx_.dimension) + "D");
  if (g.material < 0 || g.material >= static_cast<int>(ctx_.materials.size()))
    throw std::invalid_argument("grain material index out of range");
  g.id = next_id_++;
  g.origin = g.id;
  Rng r = rng_.derive(static_cast<std::uint64_t>(g.id));
  model_->assign_strength(g, ctx_.materials[g.material], r);
  // The kinetic energy a grain starts with counts as energy put in (guards).
  energy_in_ += kinetic_energy(std::span<const Grain>(&g, 1), ctx_.materials, ctx_.dimension);
  // Running mean diameter of the initial grains (guards' reference size).
  reference_diameter_ += (g.shape->equivalent_diameter() - reference_diameter_) / static_cast<double>(grains_.size() + 1);
  engine_->add_grain(g);
  grains_.push_back(std::move(g));
  return grains_.back().id;
}

void Simulation::add_observer(std::shared_ptr<Observer> o) {
  observers_.push_back(std::move(o));
  observer_seconds_.push_back(0.0);
}

template <class F>
void Simulation::notify(F&& call) {
  for (std::size_t i = 0; i < observers_.size(); ++i) {
    const auto t0 = Clock::now();
    call(*observers_[i]);
    const double dt = seconds_since(t0);
    observer_seconds_[i] += dt;
    timings_.observers += dt;
  }
}

void Simulation::tally_output() {
  timings_.output_by_writer.clear();
  for (std::size_t i = 0; i < observers_.size(); ++i)
    timings_.output_by_writer[observers_[i]->name()] += observer_seconds_[i];
}

SimulationState Simulation::saved_state() const {
  SimulationState s = resumed_ ? resumed_from_ : SimulationState{};
  s.time = time_;
  s.step = step_;
  s.initial_height = initial_height_;
  s.platen_position = engine_->platen_position();
  s.removed_volume = removed_volume_;
  s.removed_mass = removed_mass_;
  s.removed_by_path = removed_by_path_;
  s.fragment_counts = fragment_counts_;
  s.events = events_;
  s.analyses = analyses_;
  s.analyses_skipped = analyses_skipped_;
  s.screened = screened_;
  s.fallbacks = fallbacks_;
  s.dt_reductions = dt_reductions_;
  s.next_id = next_id_;
  s.schedule_last_stress = schedule_.last_stress();
  s.max_platen_stress = max_platen_stress_;
  s.platen_stress = state().platen_stress;
  s.energy_in = energy_in_;
  s.reference_diameter = reference_diameter_;
  s.small_grain_overlaps = guard_max_.small_grain_overlaps;
  s.small_grains_removed = guard_max_.small_grains_removed;
  s.guard_max_overlap_fraction = guard_max_.max_overlap_fraction;
  s.guard_max_energy_ratio = guard_max_.energy_ratio;
  s.analysis_failures = analysis_failures_;
  s.rocks_fed = fed_;
  s.mass_fed = mass_fed_;
  s.product = product_;
  s.product_mass = product_mass_;
  s.ejected = ejected_;
  s.ejected_mass = ejected_mass_;
  if (!resumed_) {
    s.grains_initial = initial_grains_;
    s.mass_initial = initial_mass_;
    s.void_ratio_initial = initial_void_ratio_;
  }
  return s;
}

void Simulation::resume(const SimulationState& st, std::vector<Grain> grains) {
  adopt(st, std::move(grains));
  resumed_from_ = st;
  resumed_ = true;
}

void Simulation::restore_packing(const SimulationState& st, std::vector<Grain> grains) {
  adopt(st, std::move(grains));
}

void Simulation::adopt(const SimulationState& st, std::vector<Grain> grains) {
  if (!grains_.empty()) throw std::logic_error("Simulation::resume: grains were already added");
  if (container_.height <= 0) throw std::logic_error("Simulation::resume: set the container first");
  if (st.rocks_fed > feed_.count)
    throw std::invalid_argument("checkpoint: " + std::to_string(st.rocks_fed) + " rocks fed, but the scene feeds " +
                                std::to_string(feed_.count));
  for (auto& g : grains) {
    if (!g.shape) throw std::invalid_argument("checkpoint grain " + std::to_string(g.id) + " has no shape");
    if (g.id < 0 || g.id >= st.next_id)
      throw std::invalid_argument("checkpoint grain id " + std::to_string(g.id) + " outside [0, next_id)");
    engine_->add_grain(g);
  }
  grains_ = std::move(grains);
  time_ = st.time;
  step_ = st.step;
  initial_height_ = st.initial_height;
  removed_volume_ = st.removed_volume;
  removed_mass_ = st.removed_mass;
  removed_by_path_ = st.removed_by_path;
  fragment_counts_ = st.fragment_counts;
  events_ = st.events;
  analyses_ = st.analyses;
  analyses_skipped_ = st.analyses_skipped;
  screened_ = st.screened;
  fallbacks_ = st.fallbacks;
  dt_reductions_ = st.dt_reductions;
  next_id_ = st.next_id;
  schedule_.set_last_stress(st.schedule_last_stress);
  max_platen_stress_ = st.max_platen_stress;
  energy_in_ = st.energy_in;
  initial_elastic_counted_ = true;  // in the checkpoint's energy_in
  reference_diameter_ = st.reference_diameter;
  guard_max_.small_grain_overlaps = st.small_grain_overlaps;
  guard_max_.small_grains_removed = st.small_grains_removed;
  guard_max_.max_overlap_fraction = st.guard_max_overlap_fraction;
  guard_max_.energy_ratio = st.guard_max_energy_ratio;
  analysis_failures_ = st.analysis_failures;
  fed_ = st.rocks_fed;
  mass_fed_ = st.mass_fed;
  product_ = st.product;
  product_mass_ = st.product_mass;
  ejected_ = st.ejected;
  ejected_mass_ = st.ejected_mass;
}

double Simulation::area() const {
  return ctx_.dimension == 2 ? container_.lx : container_.lx * container_.ly;
}

double Simulation::solid_volume() const {
  double v = removed_volume_;
  for (const auto& g : grains_) v += g.shape->volume();
  return v;
}

double Simulation::time_step(double stress) const {
  for (const auto& r : settings_.time_steps)
    if (stress < r.below_stress) return r.dt;
  return settings_.time_steps.back().dt;
}

void Simulation::sync_grains() { engine_->read_state(grains_); }

void Simulation::account_step(double platen_force, double platen_travel) {
  energy_in_ += std::abs(platen_force * platen_travel);
  if (initial_elastic_counted_) return;
  energy_in_ += engine_->elastic_energy();
  initial_elastic_counted_ = true;
}

void Simulation::check_guards(const char* phase, double dt, bool full) {
  GuardContext at;
  at.phase = phase;
  at.step = step_;
  at.time = time_;
  at.dt = dt;
  at.advice = engine_->guard_advice();
  at.open = container_.open;
  const RunState st = state();
  at.platen_stress = st.platen_stress;
  check_scalar_invariants(settings_.guards, at, st.platen_height, st.void_ratio, st.platen_force);
  if (!full || !settings_.guards.enabled) return;
  sync_grains();
  at.reference_diameter = reference_diameter_;
  // Budget: what entered so far, plus every grain's weight falling the container's height
  // (at least 1 m/s² so that a scene without gravity still has a scale).
  double mass = 0;
  for (const auto& g : grains_) mass += g.mass(ctx_.materials[g.material].density);
  at.added_kinetic_energy = engine_->added_kinetic_energy();
  at.energy_budget = energy_in_ + mass * std::max(norm(ctx_.gravity), 1.0) * std::max(initial_height_, container_.height);
  const std::vector<Contact> cs = settings_.guards.max_overlap_fraction > 0 ? engine_->contacts() : std::vector<Contact>{};
  const GuardReading r =
      check_invariants(settings_.guards, at, container_, ctx_.dimension, st.platen_height, grains_, ctx_.materials, cs);
  guard_max_.max_overlap_fraction = std::max(guard_max_.max_overlap_fraction, r.max_overlap_fraction);
  guard_max_.energy_ratio = std::max(guard_max_.energy_ratio, r.energy_ratio);
  if (r.small_grain_overlaps > 0 && guard_max_.small_grain_overlaps == 0)
    std::cerr << "crumble: warning: a grain smaller than " << settings_.guards.small_grain_fraction
              << " of the initial mean diameter overlaps a neighbour by more than "
              << settings_.guards.max_overlap_fraction << " of its size at step " << step_
              << " (counted in summary.json: guard_small_grain_overlaps)\n";
  guard_max_.small_grain_overlaps += r.small_grain_overlaps;
  if (!r.escaped_small.empty()) remove_escaped(r.escaped_small);
}

void Simulation::remove_escaped(const std::vector<GrainId>& ids) {
  // Guards.h (GuardSettings::containment): tiny grains outside a closed container leave as
  // fines, their volume kept in the solid volume so the void ratio does not jump.
  std::vector<char> gone(grains_.size(), 0);
  for (std::size_t i = 0; i < grains_.size(); ++i) {
    const Grain& g = grains_[i];
    if (std::find(ids.begin(), ids.end(), g.id) == ids.end()) continue;
    if (guard_max_.small_grains_removed == 0)
      std::cerr << "crumble: warning: grain " << g.id << " (d = " << g.shape->equivalent_diameter()
                << " m, below simulation.guards.small_grain_fraction " << settings_.guards.small_grain_fraction
                << " of the initial mean diameter) left the container at step " << step_
                << "; taken out as fines (counted in summary.json: guard_small_grains_removed)\n";
    engine_->remove_grain(g.id);
    removed_volume_ += g.shape->volume();
    removed_mass_ += g.mass(ctx_.materials[g.material].density);
    removed_by_path_.guard += g.mass(ctx_.materials[g.material].density);
    ++guard_max_.small_grains_removed;
    gone[i] = 1;
  }
  std::size_t k = 0;
  for (std::size_t i = 0; i < grains_.size(); ++i) {
    if (gone[i]) continue;
    if (k != i) grains_[k] = std::move(grains_[i]);
    ++k;
  }
  grains_.resize(k);
}

RunState Simulation::state() const {
  RunState s;
  s.time = time_;
  s.step = step_;
  s.dt = dt_;
  s.platen_force = engine_->platen_force();
  s.floor_force = engine_->floor_force();
  s.platen_stress = area() > 0 ? s.platen_force / area() : 0;  // open scenes have no platen
  s.target_stress = loading_.target_stress(time_);
  s.platen_height = engine_->platen_position();
  s.axial_strain = initial_height_ > 0 ? (initial_height_ - s.platen_height) / initial_height_ : 0;
  const double vs = solid_volume();
  s.void_ratio = vs > 0 && !container_.open ? (area() * s.platen_height - vs) / vs : 0;
  s.grains = grains_.size();
  s.breakage_events = events_;
  s.analyses = analyses_;
  return s;
}

RunSummary Simulation::run(const Progress& progress) {
  const auto t_start = Clock::now();
  if (container_.height <= 0) throw std::logic_error("Simulation::run: no container set");
  RunSummary sum;
  RunState st = start_run(sum);
  auto last_progress = Clock::now();
  // A checkpoint is written at a sample step, after that step's discharge and feed: a
  // resumed run does them next at the following sample step, as the uninterrupted run does.
  if (!resumed_) update_open_scene();
  const Timings before_loop = timings_;
  const auto t_loop = Clock::now();
  while (!loading_.finished(time_, st.platen_stress, st.platen_force, st.axial_strain)) {
    if (settings_.max_steps > 0 && step_ >= settings_.max_steps) break;
    if (settings_.stop_after_breakage_events > 0 && events_ >= settings_.stop_after_breakage_events) break;
    if (stop_ && stop_->load()) {
      sum.interrupted = true;
      break;
    }
    const double dt = next_time_step(st);
    step_once(dt, st);
    sum.max_platen_stress = max_platen_stress_ = std::max(sum.max_platen_stress, st.platen_stress);
    // A stress ramp schedules by the stress it commands (Zhu & Zhao 2019 §5: a check every
    // 0.08 MPa of loading). The measured stress of an explicit engine rings: scheduled
    // by it, one transient peak would postpone every later check until the stress came back
    // to it (lsdem on the Zhu & Zhao packing: no check from a 37 MPa start-up peak on).
    const double schedule_stress = loading_.settings().mode == "stress_ramp" ? st.target_stress : st.platen_stress;
    if (model_->active() && schedule_.due(step_, schedule_stress)) {
      check_breakage(st);
      st = state();
    }
    if (settings_.sample_every > 0 && step_ % settings_.sample_every == 0)
      notify([&](Observer& o) { o.on_sample(*this, st); });
    if (progress && seconds_since(last_progress) > 1.0) {
      last_progress = Clock::now();
      progress(st, loading_.progress(time_, st.platen_stress, st.axial_strain));
    }
  }
  if (!sum.interrupted && !container_.open && loading_.settings().mode == "stress_ramp" &&
      loading_.finished(time_, st.platen_stress, st.platen_force, st.axial_strain)) {
    GuardContext at{"loading", step_, time_, st.platen_stress, dt_, engine_->guard_advice(), 0};
    check_stress_carried(settings_.guards, at, loading_.target_stress(time_));
  }
  {
    // Everything in the loop that no part above timed (Observer.h, Timings::loop).
    const Timings& a = before_loop;
    const Timings& b = timings_;
    const double parts = (b.engine - a.engine) + (b.contacts - a.contacts) + (b.screening - a.screening) +
                         (b.analyses - a.analyses) + (b.fragments - a.fragments) + (b.observers - a.observers) +
                         (b.guards - a.guards);
    timings_.loop += std::max(0.0, seconds_since(t_loop) - parts);
  }
  check_guards("loading", dt_, true);
  st = state();
  notify([&](Observer& o) { o.on_sample(*this, st); });
  sync_grains();
  fill_summary(sum, st);
  notify([&](Observer& o) { o.on_finish(*this, st, sum); });
  tally_output();
  sum.timings = timings_;
  sum.wall_seconds = seconds_since(t_start);
  return sum;
}

// The initial figures (those of the checkpoint on a resume), the observers started, and the
// first time step checked against the engine's stable step.
RunState Simulation::start_run(RunSummary& sum) {
  RunState st;
  notes_.clear();
  if (resumed_) {
    sum.grains_initial = resumed_from_.grains_initial;
    sum.mass_initial = resumed_from_.mass_initial;
    sum.void_ratio_initial = resumed_from_.void_ratio_initial;
    st = state();
  } else {
    sum.grains_initial = grains_.size();
    for (const auto& g : grains_) sum.mass_initial += g.mass(ctx_.materials[g.material].density);
    initial_height_ = engine_->platen_position();
    st = state();
    sum.void_ratio_initial = st.void_ratio;
  }
  initial_grains_ = sum.grains_initial;
  initial_mass_ = sum.mass_initial;
  initial_void_ratio_ = sum.void_ratio_initial;
  sum.max_platen_stress = max_platen_stress_;
  notify([&](Observer& o) { o.on_start(*this, st); });

  dt_ = time_step(0);
  const double bound = engine_->max_stable_dt();
  if (dt_ > bound && !settings_.auto_reduce_dt)
    throw std::invalid_argument("time step " + std::to_string(dt_) + " s exceeds the engine's stable step " +
                                std::to_string(bound) + " s (set simulation.auto_reduce_dt or a smaller dt)");
  return st;
}

// The step for the stress reached, reduced to the engine's stable step when it allows that.
double Simulation::next_time_step(const RunState& st) {
  // The first step after a resume: the stress at the checkpoint, which an engine that does
  // not keep its contact forces (Bullet) cannot measure yet.
  const bool first_resumed = resumed_ && step_ == resumed_from_.step && resumed_from_.platen_stress >= 0;
  double dt = time_step(std::max(first_resumed ? resumed_from_.platen_stress : st.platen_stress, 0.0));
  const double bound = engine_->max_stable_dt();
  if (dt > bound) {
    if (!settings_.auto_reduce_dt) throw std::runtime_error("time step exceeds the engine's stable step after breakage");
    if (dt_reductions_ == 0 || dt_ != bound)
      std::cerr << "crumble: warning: time step " << dt << " s reduced to the engine's stable step " << bound
                << " s at t = " << time_ << " s\n";
    dt = bound;
    ++dt_reductions_;
  }
  dt_ = dt;
  return dt;
}

// One engine step under the loading's platen command and the walls' motion, then the guards.
void Simulation::step_once(double dt, RunState& st) {
  engine_->set_platen(loading_.command(time_, area(), initial_height_));
  auto t0 = Clock::now();
  const double z_before = st.platen_height;
  drive_walls(time_, dt);
  engine_->step(dt);
  timings_.engine += seconds_since(t0);
  if (const Engine::SolverReport r = engine_->solver_report(); r.iterations >= 0) {
    ++solver_.steps;
    solver_.iterations_max = std::max(solver_.iterations_max, r.iterations);
    if (r.limit_before_tolerance) {
      ++solver_.limited;
      solver_.limited_change_max = std::max(solver_.limited_change_max, r.change);
    }
  }
  time_ += dt;
  ++step_;
  st = state();
  account_step(st.platen_force, st.platen_height - z_before);
  if (settings_.sample_every > 0 && step_ % settings_.sample_every == 0) {
    t0 = Clock::now();
    update_open_scene();
    check_guards("loading", dt, true);
    timings_.guards += seconds_since(t0);
  } else {
    GuardContext at{"loading", step_, time_, st.platen_stress, dt, engine_->guard_advice(), 0};
    at.open = container_.open;
    check_scalar_invariants(settings_.guards, at, st.platen_height, st.void_ratio, st.platen_force);
  }
}

// The run's counts and final figures in summary.json (before the observers add theirs).
void Simulation::fill_summary(RunSummary& sum, const RunState& st) {
  sum.steps = step_;
  sum.time = time_;
  sum.grains_final = grains_.size();
  for (const auto& g : grains_) sum.mass_final += g.mass(ctx_.materials[g.material].density);
  sum.mass_removed = removed_mass_;
  sum.extra["mass_removed_crushed_kg"] = removed_by_path_.crushed;
  sum.extra["mass_removed_chip_kg"] = removed_by_path_.chip;
  sum.extra["mass_removed_split_pieces_kg"] = removed_by_path_.split_pieces;
  sum.extra["mass_removed_fines_diameter_kg"] = removed_by_path_.fines_diameter;
  sum.extra["mass_removed_guard_kg"] = removed_by_path_.guard;
  sum.void_ratio_final = st.void_ratio;
  sum.breakage_events = events_;
  sum.analyses = analyses_;
  sum.analyses_skipped = analyses_skipped_;
  for (const auto& [reason, n] : screened_.items()) sum.extra[std::string("screening_") + reason] = static_cast<double>(n);
  sum.fragment_fallbacks = fallbacks_;
  const FragmentCounts& fc = fragment_counts_;
  sum.extra["fragment_refinements"] = static_cast<double>(fc.refinements);
  sum.extra["fragment_pieces_absorbed"] = static_cast<double>(fc.absorbed);
  sum.extra["fragment_unresolved"] = static_cast<double>(fc.unresolved);
  sum.extra["fragment_grid_nodes_per_child"] =
      fc.children > 0 ? static_cast<double>(fc.grid_nodes) / static_cast<double>(fc.children) : 0.0;
  long failed = 0;
  for (const auto& [word, count] : analysis_failures_) {
    sum.extra["analyses_failed_" + word] = static_cast<double>(count);
    failed += count;
  }
  sum.extra["analyses_failed"] = static_cast<double>(failed);
  sum.dt_reductions = dt_reductions_;
  finish_open_scene(sum);
  // The part of all the solid that ever entered (initial grains and fed rocks) removed as fines.
  const double entered = sum.mass_initial + mass_fed_;
  sum.extra["fines_mass_fraction"] = entered > 0 ? removed_mass_ / entered : 0.0;
  sum.extra["guard_max_overlap_fraction"] = guard_max_.max_overlap_fraction;
  sum.extra["guard_max_energy_ratio"] = guard_max_.energy_ratio;
  sum.extra["guard_small_grain_overlaps"] = static_cast<double>(guard_max_.small_grain_overlaps);
  sum.extra["guard_small_grains_removed"] = static_cast<double>(guard_max_.small_grains_removed);
  for (const auto& [key, value] : engine_->summary_figures()) sum.extra["engine_" + key] = value;
  summarise_solver(sum);
}

void Simulation::summarise_solver(RunSummary& sum) {
  if (solver_.steps <= 0) return;
  const double limited = static_cast<double>(solver_.limited) / static_cast<double>(solver_.steps);
  sum.extra["engine_solver_iterations_max"] = solver_.iterations_max;
  sum.extra["engine_solver_limited_fraction"] = limited;
  sum.extra["engine_solver_limited_change_max"] = solver_.limited_change_max;
  // Unconverged contact forces change the result (docs/validation.md, Zhu & Zhao §5): say so,
  // unless the scenario declares its iteration limit deliberate.
  if (limited < 0.1) return;
  std::ostringstream text;
  text << "the contact solver stopped at its iteration limit (" << solver_.iterations_max << ") before its tolerance in "
       << std::lround(100 * limited) << " % of the loading steps (relative impulse change left: up to "
       << solver_.limited_change_max
       << "); its contact forces are less converged than engine.solver_tolerance asks: raise "
          "engine.solver_iterations for converged forces (counted in summary.json: engine_solver_limited_fraction)";
  notes_.push_back(make_note(deliberate_, "/engine/solver_iterations", text.str()));
  print_note(notes_.back());
}

// Counted by the error's leading word (the text before its first ':', e.g. "convex_hull"),
// written to summary.json as analyses_failed and analyses_failed_<word>; the first one is
// told on stderr.
void Simulation::note_analysis_failure(const Grain& g, const std::string& error) {
  std::string word;
  for (const char c : error.substr(0, error.find(':'))) {
    const bool keep = std::isalnum(static_cast<unsigned char>(c)) != 0;
    if (keep) word += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    else if (!word.empty() && word.back() != '_') word += '_';
    if (word.size() >= 40) break;
  }
  while (!word.empty() && word.back() == '_') word.pop_back();
  if (word.empty()) word = "other";
  if (analysis_failures_.empty())
    std::cerr << "crumble: warning: the breakage analysis or fragment build of grain " << g.id << " ("
              << g.shape->describe() << ") failed: " << error
              << "; the grain stays intact and the run goes on (failures counted in summary.json: analyses_failed)\n";
  ++analysis_failures_[word];
}

void Simulation::check_breakage(const RunState& st) {
  BreakageBatch b = select_candidates();
  if (b.candidates.empty()) return;
  run_analyses(b);
  build_fragments(b);
  const auto t0 = Clock::now();
  const double observers0 = timings_.observers;
  std::vector<char> remove(grains_.size(), 0);
  std::vector<Grain> added;
  for (long k = 0; k < static_cast<long>(b.candidates.size()); ++k)
    if (apply_outcome(b, k, st, added)) remove[b.candidates[k]] = 1;
  std::vector<Grain> kept;
  kept.reserve(grains_.size() + added.size());
  for (std::size_t i = 0; i < grains_.size(); ++i)
    if (!remove[i]) kept.push_back(std::move(grains_[i]));
  for (auto& c : added) kept.push_back(std::move(c));
  grains_ = std::move(kept);
  // The observers told of the outcomes count as output, not as fragment building.
  timings_.fragments += std::max(0.0, seconds_since(t0) - (timings_.observers - observers0));
}

// The contacts, and the grains the screening selects with the loads their analyses get.
Simulation::BreakageBatch Simulation::select_candidates() {
  BreakageBatch b;
  auto t0 = Clock::now();
  const std::vector<Contact> all = engine_->contacts();
  engine_->read_state(grains_);
  timings_.contacts += seconds_since(t0);

  t0 = Clock::now();
  b.on = contacts_by_grain(grains_, all);
  for (std::size_t i = 0; i < grains_.size(); ++i) {
    const ScreeningResult sr = screen(grains_[i], b.on[i], screening_, model_->threshold_force(grains_[i]));
    screened_.add(sr);
    if (!sr.selected) continue;
    std::vector<PartnerForce> now = partner_forces(grains_[i], b.on[i]);
    if (skip_analysis(grains_[i], now, screening_)) {
      ++analyses_skipped_;
      continue;
    }
    b.candidates.push_back(i);
    b.loads.push_back(std::move(now));
  }
  timings_.screening += seconds_since(t0);
  return b;
}

// Analyses of different grains are independent: one grain per task. Results are stored by
// candidate index so the outcome does not depend on the number of threads (or ranks, with an
// executor). An analysis that throws leaves its error in b.errors.
void Simulation::run_analyses(BreakageBatch& b) {
  const auto t0 = Clock::now();
  const long n = static_cast<long>(b.candidates.size());
  b.results.assign(n, BreakageAnalysis{});
  b.frags.assign(n, FragmentResult{});
  b.errors.assign(n, std::string());
  const int threads = std::max(1, settings_.threads);
  if (executor_) {
    std::vector<AnalysisJob> jobs(n);
    for (long k = 0; k < n; ++k) {
      const std::size_t i = b.candidates[k];
      jobs[k] = {&grains_[i], grains_[i].material, b.on[i]};
    }
    executor_->analyse(*model_, ctx_.materials, jobs, b.results, b.errors);
  } else {
    // One grain: its analysis gets every thread (the peridynamic passes are bitwise the same
    // on any count), so a check that selects one grain does not leave the other cores idle.
    // (Outside any parallel region: nested in an inactive one, OpenMP would start new threads
    // for each of the analysis' thousands of regions.)
    const auto analyse = [&](long k) {
      const Grain& g = grains_[b.candidates[k]];
      try {
        b.results[k] = model_->analyse(g, ctx_.materials[g.material], b.on[b.candidates[k]]);
      } catch (const std::exception& e) {
        b.errors[k] = e.what();
      }
    };
    model_->set_analysis_threads(n == 1 ? threads : 1);
    if (n == 1) {
      analyse(0);
    } else {
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
      for (long k = 0; k < n; ++k) analyse(k);
    }
  }
  timings_.analyses += seconds_since(t0);
}

// The fragments of every broken grain, one grain per task; a build that throws leaves its
// error in b.errors.
void Simulation::build_fragments(BreakageBatch& b) {
  const auto t0 = Clock::now();
  const long n = static_cast<long>(b.candidates.size());
  const int threads = std::max(1, settings_.threads);
  for (long k = 0; k < n; ++k) {
    if (!b.errors[k].empty() || !b.results[k].broken || !b.results[k].fracture) continue;
    if (!builder_) throw std::runtime_error("a grain broke but no fragment builder is configured");
  }
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (long k = 0; k < n; ++k) {
    if (!b.errors[k].empty() || !b.results[k].broken || !b.results[k].fracture) continue;
    try {
      b.frags[k] = builder_->build(*grains_[b.candidates[k]].shape, *b.results[k].fracture);
    } catch (const std::exception& e) {
      b.errors[k] = e.what();
    }
  }
  timings_.fragments += seconds_since(t0);
}

// The outcome of candidate k told to the observers, and a broken grain replaced by its
// children in the engine (added to `added`). True when the grain is to leave grains_.
bool Simulation::apply_outcome(BreakageBatch& b, long k, const RunState& st, std::vector<Grain>& added) {
  const Grain& parent = grains_[b.candidates[k]];
  const BreakageAnalysis& result = b.results[k];
  const FragmentResult& frag = b.frags[k];
  ++analyses_;
  AnalysisRecord rec{time_, step_, st.platen_stress, parent.id, parent.shape->equivalent_diameter(), parent.generation,
                     result};
  rec.analysis.fracture.reset();
  if (!b.errors[k].empty()) {
    // An analysis or a fragment build that threw (a degenerate geometry) leaves the grain
    // as it was, before anything of it changed: the mass budget holds, and the run goes on.
    rec.analysis.broken = false;
    rec.analysis.outcome = "failed";
    notify([&](Observer& o) { o.on_analysis(*this, rec); });
    note_analysis_failure(parent, b.errors[k]);
    return false;
  }
  // A split needs two pieces; one child plus builder-removed fines (a chip) also counts.
  // The record says what the builder made of it: "no_split" when the model broke the
  // grain but the builder returned fewer than two pieces (the grain stays as it is),
  // "chip" when one child and removed fines came out.
  // "crushed" when the builder removed all of it as fines (no child; FragmentBuilder.h),
  // "unresolved" when the builder could not cut it into a piece it resolves (the grain stays).
  const bool crushed = frag.children.empty() && frag.removed_volume > 0;
  const std::size_t pieces = frag.children.size() + (frag.removed_volume > 0 ? 1 : 0);
  if (result.broken && frag.unresolved) rec.analysis.outcome = "unresolved";
  else if (result.broken && crushed) rec.analysis.outcome = "crushed";
  else if (result.broken && pieces < 2) rec.analysis.outcome = "no_split";
  else if (result.broken && frag.children.size() == 1) rec.analysis.outcome = "chip";
  notify([&](Observer& o) { o.on_analysis(*this, rec); });
  Grain& g = grains_[b.candidates[k]];
  if (!result.broken) {
    // Remembered for the skip rule (Screening.h) only when the rule is on, so that runs
    // without it write the checkpoints they always wrote.
    if (screening_.skip_intact_tolerance > 0) g.intact_load = std::move(b.loads[k]);
    return false;
  }
  g.intact_load.clear();
  if (pieces < 2 && !crushed) {
    // The model's verdict counts even when the builder could not split the grain (Grain.h).
    ++g.crush_count;
    if (frag.unresolved) ++fragment_counts_.unresolved;
    return false;
  }
  split_grain(parent, frag, rec, st, added);
  return true;
}

// The grain replaced by the builder's pieces (those finer than simulation.fines_diameter are
// removed as fines), the mass budget checked, the breakage event told to the observers.
void Simulation::split_grain(const Grain& parent, const FragmentResult& frag, const AnalysisRecord& rec,
                             const RunState& st, std::vector<Grain>& added) {
  const Material& mat = ctx_.materials[parent.material];
  BreakageEvent ev;
  ev.time = time_;
  ev.step = step_;
  ev.platen_stress = st.platen_stress;
  ev.parent = parent.id;
  ev.parent_volume = parent.shape->volume();
  ev.parent_diameter = parent.shape->equivalent_diameter();
  ev.generation = parent.generation;
  ev.fragment_method = frag.method;
  ev.analysis = rec.analysis;
  fallbacks_ += frag.fallbacks;
  fragment_counts_.grid_nodes += frag.grid_nodes;
  fragment_counts_.children += static_cast<long>(frag.children.size());
  fragment_counts_.refinements += frag.refinements;
  fragment_counts_.absorbed += frag.absorbed;
  // Mass budget: children + the builder's removed pieces = parent (FragmentBuilder.h).
  double vsum = frag.removed_volume;
  for (const auto& f : frag.children) vsum += f.shape->volume();
  if (!(frag.removed_volume >= 0) || !(std::abs(vsum - ev.parent_volume) <= 1e-9 * ev.parent_volume))
    throw std::runtime_error("fragment builder '" + builder_->name() + "' lost volume on grain " +
                             std::to_string(parent.id) + ": children + removed " + std::to_string(vsum) +
                             " m³ vs parent " + std::to_string(ev.parent_volume) + " m³");
  ev.removed_volume = frag.removed_volume;
  std::vector<Grain> children = make_children(parent, frag, mat, ev);
  removed_volume_ += ev.removed_volume;
  removed_mass_ += ev.removed_volume * mat.density;
  double& by_builder = frag.children.empty()       ? removed_by_path_.crushed
                       : frag.children.size() == 1 ? removed_by_path_.chip
                                                   : removed_by_path_.split_pieces;
  by_builder += frag.removed_volume * mat.density;
  removed_by_path_.fines_diameter += (ev.removed_volume - frag.removed_volume) * mat.density;
  engine_->replace_grain(parent.id, children);
  for (auto& c : children) added.push_back(std::move(c));
  ++events_;
  notify([&](Observer& o) { o.on_breakage(*this, ev); });
}

// The children of `parent`: ids, lineage, pose in the world (v + ω × (c_child − c_parent)),
// inherited strength; pieces finer than simulation.fines_diameter go to ev.removed_volume.
std::vector<Grain> Simulation::make_children(const Grain& parent, const FragmentResult& frag, const Material& mat,
                                             BreakageEvent& ev) {
  std::vector<Grain> children;
  const Mat3 R = parent.orientation.matrix();
  for (const auto& f : frag.children) {
    const double d = f.shape->equivalent_diameter();
    if (d < settings_.fines_diameter) {
      ev.removed_volume += f.shape->volume();
      continue;
    }
    Grain c;
    c.id = next_id_++;
    c.parent = parent.id;
    c.origin = parent.origin;
    c.generation = parent.generation + 1;
    c.crush_count = parent.crush_count + 1;
    c.shape = f.shape;
    c.material = parent.material;
    const Vec3 r = R * f.offset;
    c.position = parent.position + r;
    c.orientation = parent.orientation;
    c.velocity = parent.velocity + cross(parent.angular_velocity, r);  // v + ω × (c_child − c_parent)
    c.angular_velocity = parent.angular_velocity;
    Rng rr = rng_.derive(static_cast<std::uint64_t>(c.id));
    model_->inherit_strength(parent, c, mat, rr);
    ev.children.push_back(c.id);
    ev.child_volumes.push_back(f.shape->volume());
    ev.child_diameters.push_back(d);
    children.push_back(std::move(c));
  }
  return children;
}

}  // namespace crumble
