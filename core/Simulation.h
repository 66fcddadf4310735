// The one loop: load, step, check breakage on schedule, replace broken
// grains by their fragments, notify observers.
#pragma once
#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <vector>

#include "core/AnalysisExecutor.h"
#include "core/BreakageModel.h"
#include "core/Engine.h"
#include "core/FragmentBuilder.h"
#include "core/Guards.h"
#include "core/Loading.h"
#include "core/Notes.h"
#include "core/Observer.h"
#include "core/OpenScene.h"
#include "core/Schedule.h"
#include "core/Screening.h"

namespace crumble {

struct TimeStepRule {
  double below_stress;  // Pa: applies while the measured stress is below this
  double dt;            // s
};

struct SimulationSettings {
  // Zhu & Zhao 2019 §5: dt by stress level; the last rule applies above all bounds.
  std::vector<TimeStepRule> time_steps{{1e300, 5e-5}};
  long max_steps = 0;                 // 0 = no limit (the loading decides)
  long sample_every = 100;            // steps between series samples
  double fines_diameter = 0;          // m: children smaller than this leave the engine
  bool auto_reduce_dt = true;         // shrink dt (with a warning) below the engine's bound
  long stop_after_breakage_events = 0;  // 0 = never (single-grain crushing stops at 1)
  int threads = 1;
  GuardSettings guards;               // physical invariants (core/Guards.h)
};

// Mass taken out of the engine as fines (kg), by the path that took it (summary.json
// mass_removed_<path>_kg; the paths sum to mass_removed_kg).
struct RemovedMassByPath {
  double crushed = 0;         // grains the builder removed whole (outcome crushed)
  double chip = 0;            // pieces the builder removed when it kept one child (outcome chip)
  double split_pieces = 0;    // pieces the builder removed from a split into two children or more
  double fines_diameter = 0;  // children finer than simulation.fines_diameter
  double guard = 0;           // small grains that left the container (guards)
};

// What the fragment builders made so far (summary.json fragment_grid_nodes_per_child,
// fragment_refinements, fragment_pieces_absorbed, fragment_unresolved).
struct FragmentCounts {
  long grid_nodes = 0;   // nodes of the children's grids
  long children = 0;     // children built
  long refinements = 0;  // splits repeated on a finer grid
  long absorbed = 0;     // unresolved pieces merged into a kept child
  long unresolved = 0;   // broken grains the builder could not cut into a resolved piece (left whole)
};

// Everything besides the grains that a run needs to continue from a checkpoint. The
// engine is rebuilt from the grains: contact history and solver warm starts start afresh,
// and the platen starts at rest where it was.
struct SimulationState {
  double time = 0;
  long step = 0;
  double initial_height = 0;
  double platen_position = 0;
  double removed_volume = 0, removed_mass = 0;
  RemovedMassByPath removed_by_path;
  FragmentCounts fragment_counts;
  long events = 0, analyses = 0, fallbacks = 0, dt_reductions = 0;
  long analyses_skipped = 0;  // screened in but skipped by the skip rule (Screening.h)
  ScreeningCounts screened;   // grain checks per screening outcome
  GrainId next_id = 0;
  double schedule_last_stress = 0;
  std::size_t grains_initial = 0;
  double mass_initial = 0, void_ratio_initial = 0, max_platen_stress = 0;
  // Pa at the checkpoint's step: a resumed run picks its first step's time step by it (an
  // engine without contact history, as Bullet, measures no platen force before that step).
  // Negative: unknown (older checkpoints).
  double platen_stress = -1;
  double energy_in = 0;  // J: platen work and initial kinetic energy so far (guards)
  double reference_diameter = 0;  // m: mean diameter of the initial grains (guards)
  long small_grain_overlaps = 0;
  long small_grains_removed = 0;  // tiny grains that left the container, taken out as fines
  double guard_max_overlap_fraction = 0, guard_max_energy_ratio = 0;  // largest margins so far (summary.json)
  // Breakage analyses or fragment builds that threw, by the error's leading word
  // (summary.json: analyses_failed_<word>).
  std::map<std::string, long> analysis_failures;
  // Open scenes (core/OpenScene.h): rocks fed so far (the next one is the feed's rock number
  // rocks_fed), their mass, and the product collected so far. The moving walls' pose follows
  // from `time` (their motion is prescribed).
  long rocks_fed = 0;
  double mass_fed = 0;
  std::vector<ProductGrain> product;
  double product_mass = 0;
  std::vector<ProductGrain> ejected;  // grains thrown out of the top of the scene (Container)
  double ejected_mass = 0;
};

// Where the settling of a packing (scenarios/Packing.h) stands after a step: what a
// checkpoint written while the packing settles keeps, so that the settling goes on from it
// as if it had never stopped.
struct SettleProgress {
  long steps = 0;            // settling steps done
  double last_platen = 0;    // m: platen position at the end of the last completed window
  double dt = 0;             // s: the settling's time step
  double mean_diameter = 0;  // m: the grains' mean equivalent diameter (convergence scale)
  // Pa: the platen stress after the first step and the largest since (a file packing relaxed
  // on another engine than the one that built it starts with that engine's overlaps).
  double stress_first = 0, stress_max = 0;
};

class Simulation {
 public:
  Simulation(std::unique_ptr<Engine> engine, std::unique_ptr<BreakageModel> model,
             std::unique_ptr<FragmentBuilder> builder, EngineContext ctx, SimulationSettings settings,
             LoadingSettings loading, ScheduleSettings schedule, ScreeningSettings screening,
             std::uint64_t seed);
  ~Simulation();

  void set_container(const Container& c);
  // Adds a grain of the initial packing: assigns its id and samples its strength.
  GrainId add_grain(Grain g);
  void add_observer(std::shared_ptr<Observer> o);

  // Moving walls (core/MovingWall.h): handed to the engine (which may refuse them) and
  // driven by the loop with their prescribed motion. Open scenes (Container::open): rocks
  // fed during the run and grains that leave through the domain's bottom as product
  // (core/OpenScene.h; implemented in SimulationOpen.cpp).
  int add_moving_wall(MovingWall w);
  const std::vector<MovingWall>& moving_walls() const { return walls_; }
  void set_feed(FeedSettings f);
  const FeedSettings& feed() const { return feed_; }
  long rocks_fed() const { return fed_; }
  double mass_fed() const { return mass_fed_; }
  const std::vector<ProductGrain>& product() const { return product_; }
  double product_mass() const { return product_mass_; }

  // Checkpoint and resume: state() of the run so far (call sync_grains() for the grains),
  // and, instead of add_grain(), the grains and state of a checkpoint (container set first).
  SimulationState saved_state() const;
  void resume(const SimulationState& st, std::vector<Grain> grains);
  // Instead of add_grain(), the grains and state of a checkpoint written while the packing
  // settled (before run()): the guards' tallies and ids go on from it, and run() then starts
  // as a fresh run does (its initial figures taken from the settled packing).
  void restore_packing(const SimulationState& st, std::vector<Grain> grains);
  bool resumed() const { return resumed_; }

  // A flag (e.g. set by SIGINT/SIGTERM) that ends the loop after the current step; the run
  // then finishes normally (outputs, checkpoint) and reports itself as interrupted.
  void set_stop_flag(const std::atomic<bool>* flag) { stop_ = flag; }
  // Runs the breakage analyses elsewhere (core/AnalysisExecutor.h, e.g. MPI ranks); null:
  // on this process's threads (SimulationSettings::threads). Fragments are built here.
  void set_analysis_executor(std::shared_ptr<AnalysisExecutor> e) { executor_ = std::move(e); }
  const AnalysisExecutor* analysis_executor() const { return executor_.get(); }

  using Progress = std::function<void(const RunState&, double fraction)>;
  RunSummary run(const Progress& progress = {});

  const std::vector<Grain>& grains() const { return grains_; }
  const Engine& engine() const { return *engine_; }
  Engine& engine() { return *engine_; }
  const BreakageModel& model() const { return *model_; }
  const FragmentBuilder* builder() const { return builder_.get(); }
  const EngineContext& context() const { return ctx_; }
  const Container& container() const { return container_; }
  const SimulationSettings& settings() const { return settings_; }
  // One time step for the whole run, set before run() (the benchmarks: the step they timed
  // the engine with, already within the engine's stable bound).
  void set_time_step(double dt) { settings_.time_steps = {{1e300, dt}}; }
  // Where the wall time of this run (since its start or resume) went so far.
  const Timings& timings() const { return timings_; }
  const Loading& loading() const { return loading_; }
  double solid_volume() const;  // in the engine + removed fines
  double removed_volume() const { return removed_volume_; }
  double removed_mass() const { return removed_mass_; }  // kg, the fines taken out of the engine
  const RemovedMassByPath& removed_by_path() const { return removed_by_path_; }
  RunState state() const;
  // Pull poses from the engine into grains() (observers that draw or measure call this).
  void sync_grains();

  // Physical guards (core/Guards.h), for code that steps the engine outside run() (packing
  // settlement): account the energy one engine step put in, and check every invariant now.
  // Throws PhysicsGuardError. The energy of a step: the platen's work (force × travel), and
  // after the first step of the run (or of its settling) the elastic energy stored in the
  // overlaps the grains were placed with (Engine::elastic_energy of that step's forces,
  // evaluated at the initial poses): it is energy present at the start, which the engine
  // turns into motion as it pushes the grains apart.
  void account_step(double platen_force, double platen_travel);
  void check_guards(const char* phase, double dt, bool full);
  // Largest margins the guards have seen so far in this process.
  const GuardReading& guard_margins() const { return guard_max_; }

  // The scenario's deliberate settings (core/Notes.h): the run's notes about them are not
  // printed. notes(): every note of the last run, printed or not, for summary.json.
  void set_deliberate(DeliberateSettings d) { deliberate_ = std::move(d); }
  const std::vector<Note>& notes() const { return notes_; }

 private:
  double area() const;
  double time_step(double stress) const;
  // The grains one breakage check selects, with what their analyses get and give.
  struct BreakageBatch {
    std::vector<std::vector<Contact>> on;          // contacts per grain
    std::vector<std::size_t> candidates;           // indices into grains_
    std::vector<std::vector<PartnerForce>> loads;  // per candidate, what its analysis is given
    std::vector<BreakageAnalysis> results;
    std::vector<FragmentResult> frags;
    std::vector<std::string> errors;  // non-empty: the analysis or the fragment build threw
  };
  // Every observer called with `call(observer)`, each call's wall time added to
  // timings_.observers and to that observer's own tally (Timings::output_by_writer).
  template <class F>
  void notify(F&& call);
  void tally_output();  // timings_.output_by_writer from the per-observer seconds
  RunState start_run(RunSummary& sum);
  double next_time_step(const RunState& st);
  void step_once(double dt, RunState& st);
  void fill_summary(RunSummary& sum, const RunState& st);
  void summarise_solver(RunSummary& sum);
  void check_breakage(const RunState& st);
  BreakageBatch select_candidates();
  void run_analyses(BreakageBatch& b);
  void build_fragments(BreakageBatch& b);
  bool apply_outcome(BreakageBatch& b, long k, const RunState& st, std::vector<Grain>& added);
  void split_grain(const Grain& parent, const FragmentResult& frag, const AnalysisRecord& rec, const RunState& st,
                   std::vector<Grain>& added);
  std::vector<Grain> make_children(const Grain& parent, const FragmentResult& frag, const Material& mat,
                                   BreakageEvent& ev);
  void note_analysis_failure(const Grain& g, const std::string& error);
  void drive_walls(double t, double dt);  // set every moving wall for the step [t, t + dt]
  void update_open_scene();               // discharge product, feed the next rock
  void finish_open_scene(RunSummary& sum) const;
  std::unique_ptr<Engine> engine_;
  std::unique_ptr<BreakageModel> model_;
  std::unique_ptr<FragmentBuilder> builder_;
  std::shared_ptr<AnalysisExecutor> executor_;
  EngineContext ctx_;
  SimulationSettings settings_;
  Loading loading_;
  Schedule schedule_;
  ScreeningSettings screening_;
  Rng rng_;
  Container container_;
  std::vector<Grain> grains_;
  std::vector<std::shared_ptr<Observer>> observers_;
  std::vector<double> observer_seconds_;  // s, per observer (the same order)
  GrainId next_id_ = 0;
  double time_ = 0;
  long step_ = 0;
  double dt_ = 0;
  double removed_volume_ = 0;
  double removed_mass_ = 0;
  RemovedMassByPath removed_by_path_;
  // The builders' cost figures (FragmentResult), counted per process like analysis failures.
  FragmentCounts fragment_counts_;
  double initial_height_ = 0;
  long events_ = 0, analyses_ = 0, fallbacks_ = 0, dt_reductions_ = 0;
  long analyses_skipped_ = 0;
  std::map<std::string, long> analysis_failures_;  // analyses that threw, by the error's leading word
  ScreeningCounts screened_;
  Timings timings_;
  bool resumed_ = false;
  const std::atomic<bool>* stop_ = nullptr;
  SimulationState resumed_from_;
  double max_platen_stress_ = 0;
  std::size_t initial_grains_ = 0;
  double initial_mass_ = 0, initial_void_ratio_ = 0;
  double energy_in_ = 0;
  bool initial_elastic_counted_ = false;  // account_step counted the initial overlaps' energy
  double reference_diameter_ = 0;
  GuardReading guard_max_;
  DeliberateSettings deliberate_;
  std::vector<Note> notes_;
  // The engine's contact solver over this process's loading steps (Engine::solver_report).
  struct SolverTally {
    long steps = 0, limited = 0;  // steps reported; of them stopped at the limit, tolerance unmet
    int iterations_max = -1;
    double limited_change_max = 0;
  } solver_;
  void remove_escaped(const std::vector<GrainId>& ids);
  void adopt(const SimulationState& st, std::vector<Grain> grains);  // resume()'s and restore_packing()'s part
  std::vector<MovingWall> walls_;
  std::vector<double> wall_radius_;  // bounding radius of each wall's shape
  FeedSettings feed_;
  long fed_ = 0;
  double mass_fed_ = 0;  // kg of rocks fed during the run
  std::vector<ProductGrain> product_;
  double product_mass_ = 0;
  std::vector<ProductGrain> ejected_;
  double ejected_mass_ = 0;
  void discharge(const Grain& g, std::vector<ProductGrain>& to, double& mass);
};

}  // namespace crumble
