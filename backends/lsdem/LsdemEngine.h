// `lsdem`: the in-house level-set DEM engine (Harmon et al. 2020 §2; Kawamoto et al. 2016), 2D and 3D.
//
// Grains are rigid bodies carrying a shared LevelSetGrid (signed distance, negative inside)
// and its surface nodes with area (2D: length) weights. A contact between grains a and b is
// found by looking up the nodes of the smaller grain (the master) in the other's level set:
// penetration p_i = −φ_b(x_i), normal n_i = ∇φ_b/|∇φ_b| (Harmon et al. 2020 eqs. 3–4).
//
// Contact law (our decision; Harmon et al. 2020 leave it open). Per contact (grain pair, or
// grain and wall) the overlap is the deepest node penetration δ = max p_i and the normal
// force follows a point-contact law, F_n = k_n·δ ("linear") or (4/3)·E*·√R*·δ^{3/2}
// ("hertz", R* from the grains' equivalent radii). F_n is then spread over the penetrating
// nodes in proportion to p_i·w_i (penetration × node area), each node pushing along its own
// normal. Because the node areas weight the spread and δ is a point value, the total force,
// its point of application and its moment converge as the nodes are refined, and k_n keeps
// the units of the paper's tables (N/m; in 2D per metre of thickness). Each node also
// carries a tangential spring (incremental, stiffness ks_ratio·k·α_i with α_i the node's
// share) capped by Coulomb friction μ·|f_n,i|; its history is kept per (node, partner).
// Viscous damping with critical-damping ratio ζ: normal F_d = −2ζ·√(m*·k)·v_n (the total
// normal force clipped at zero: no cohesion), tangential −2ζ·√(m*·k_s)·v_t (spread like the
// springs, not stored, inside the Coulomb cap). Global damping −C_g·m·v and −C_g·I·ω.
//
// Integration: leapfrog (velocities at half steps), quaternions in 3D with the gyroscopic
// term, a rotation angle about z in 2D. 2D: motion in x–y, gravity from the context
// (normally −y), floor y = 0, walls x = 0, lx, platen moving along y; 3D: floor z = 0, walls
// x = 0, lx and y = 0, ly, platen along z. Walls act on every node of a grain that lies
// behind the plane.
//
// Stable step: max_stable_dt() = dt_safety · √(m_min / k_max), m_min the lightest grain,
// k_max the largest normal stiffness (linear: max(kn, wall_kn); hertz: the tangent
// stiffness 2·E*·√(R*·δ_ref) at δ_ref = hertz_reference_overlap · smallest equivalent radius).
// A single contact of a grain on a fixed wall is stable below 2·√(m/k); dt_safety = 0.1
// leaves room for several simultaneous contacts and keeps the energy error of an undamped
// impact (force onset between steps, deepest node changing) below 1 %.
//
// Selective mass scaling (off by default; selective_dt or selective_dt_fraction):
// a grain whose own stable step dt_safety·√(m/k_max) is below a target step gets its mass
// and its inertia tensor multiplied by s = (target / own step)² (so its own step equals the
// target, and its radius of gyration is kept); grains at or above the target are untouched.
// The target is selective_dt (s), or selective_dt_fraction × the stable step of
// the packing the engine first steps (the initial packing: with a fraction ≤ 1 none of its
// grains is scaled; the fragments born later are). The factor is fixed when the grain is
// added. Weight uses the true mass (gravity never sees the added mass), and so do the
// Simulation's mass budget and the platen's mass rule. Global damping (−C_g·m·v, −C_g·I·ω)
// acts on the mass and inertia before the factor: under a steady force a scaled grain drifts
// as fast as the unscaled one, so the added mass is inertia only (damping the added mass too
// held the fragments back: the 2D Harmon oedometer carried 40 % more stress over its first
// 5 % of strain, docs/validation.md). The added mass (s − 1)·m per grain is
// reported (summary_figures: added mass in kg and as a fraction of the grains' true mass, the
// largest factor, the grains scaled), and its kinetic energy (added_kinetic_energy) is added
// to the grains' kinetic energy that the energy guard bounds (core/Guards.h).
//
// Size-following stiffness (kn_reference_radius > 0, linear law only): a contact's normal
// stiffness is kn·R/R_ref (grain–wall: wall_kn·R/R_ref), R the smaller equivalent radius of
// the pair, as a Hertz-like contact's stiffness grows with its radius. A grain's contacts are
// then at most k·R_i/R_ref stiff, so its own step is dt_safety·√(m_i·R_ref/(k·R_i)) ∝ R_i (3D)
// instead of R_i^1.5, and max_stable_dt() is the smallest of them. Off (0) by default.
//
// Contact search: bounding spheres hashed into a uniform grid of cells build a Verlet list
// of the pairs within a skin (pair_list_skin, 0.2 × the largest bounding radius), rebuilt only when two
// grains may together have moved farther than the skin (broad phase); per
// pair, a sphere tree over the master's nodes pruned against the partner's bounding sphere,
// node box and level set (|∇φ| ≤ √dim for the trilinear interpolant of distance samples);
// the nodes found within a skin of half a grid cell are kept as candidates, and only they
// are looked up while the accumulated bound on their relative motion stays below
// skin/√dim (exact: the same nodes are found as by a full search).
//
// Determinism: the narrow phase runs in parallel over (pair | grain–wall) work items, each
// writing its own slot; forces are then summed in the fixed order of the items (a function
// of positions and ids), so results are bitwise independent of the thread count.
#pragma once
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/Config.h"
#include "core/Options.h"
#include "core/Engine.h"
#include "core/Platen.h"
#include "geometry/LevelSetGrid.h"

namespace crumble {

struct LsdemSettings {
  std::string contact_law = "linear";  // "linear" | "hertz" (hertz: 3D only)
  double kn = 4e7;                      // N/m, grain–grain normal stiffness (Harmon et al. 2020 Table 2)
  double kn_reference_radius = 0;       // m: kn × R_min / this per contact (linear law); 0 = kn everywhere
  double ks_ratio = 0.6;                // k_s / k_n (Harmon et al. 2020 Table 2)
  double wall_kn = 0;                   // N/m, grain–wall; 0 = kn
  double damping_ratio = 0.4;           // normal critical-damping ratio ζ (Harmon et al. 2020 Table 1 C_res)
  double global_damping = 0;            // C_g, 1/s (Harmon et al. 2020 Tables 1–2)
  double dt_safety = 0.1;               // fraction of √(m_min/k_max)
  double hertz_reference_overlap = 0.01;  // δ_ref / smallest equivalent radius (hertz step estimate)
  double mass_scale = 1;                // density scaling: mass and inertia ×, weight unchanged
  double selective_dt = 0;           // s: target step of selective mass scaling; 0 = off
  double selective_dt_fraction = 0;  // target = this × the initial packing's stable step; 0 = off
  double pair_list_skin = 0.2;          // Verlet skin / largest bounding radius (0: list rebuilt every step)
  bool exact_spheres = true;            // "sphere_representation": "sphere" (else the hull of its mesh)
  int threads = 1;
};

// Work counters for benchmarks. Cumulative since construction or reset_stats().
struct LsdemStats {
  long steps = 0;
  long node_queries = 0;     // level-set lookups of a node (grain–grain)
  long tree_queries = 0;     // level-set lookups pruning a subtree of nodes
  long wall_node_checks = 0; // node–plane tests
  long bbox_overlaps = 0;    // broad-phase grain pairs whose bounding spheres overlap
  long contact_pairs = 0;    // pairs with at least one penetrating node (summed over steps)
  long penetrating_nodes = 0;
  long pair_list_builds = 0;  // rebuilds of the broad phase's Verlet list
  double seconds = 0;        // wall time inside step()
  // Last step only.
  long last_bbox_overlaps = 0;
  long last_contact_pairs = 0;
  long last_node_queries = 0;
};

struct LsdemBenchResult {
  long steps = 0;
  double seconds = 0;      // wall time
  double cpu_seconds = 0;  // process CPU time (all threads): robust on a shared machine
  double ms_per_step = 0;  // wall
  double cpu_ms_per_step = 0;
  double steps_per_second = 0;
  double node_queries_per_second = 0;
  double mean_bbox_overlaps = 0;  // per step
  double mean_contact_pairs = 0;  // per step
  double mean_node_queries = 0;   // per step
  int threads = 1;
};

class LsdemEngine final : public Engine {
 public:
  LsdemEngine(LsdemSettings s, EngineContext ctx);
  ~LsdemEngine() override;

  std::string name() const override { return "lsdem"; }
  std::string guard_advice() const override {
    return "Raise the contact stiffness (engine.kn) so overlaps stay small at this stress, reduce the time step "
           "(time_step), or lower loading.max_stress.";
  }
  void set_container(const Container& c) override;
  void add_grain(const Grain& g) override;
  void remove_grain(GrainId id) override;
  std::size_t grain_count() const override;

  void step(double dt) override;
  double max_stable_dt() const override;
  bool set_friction_scale(double scale) override {
    friction_scale_ = scale;
    return true;
  }
  bool set_global_damping_scale(double scale) override {
    global_damping_scale_ = scale;
    return true;
  }
  bool set_relaxation_damping(bool on) override;

  void read_state(std::span<Grain> grains) const override;
  std::vector<Contact> contacts() const override { return contacts_; }

  void set_platen(const PlatenCommand& cmd) override { platen_.set_command(cmd); }
  double platen_position() const override { return platen_.position(); }
  double platen_force() const override { return platen_force_; }
  double floor_force() const override { return floor_force_; }
  double wall_force(int wall) const override {
    return wall >= 0 && wall < static_cast<int>(container_wall_force_.size()) ? container_wall_force_[wall] : 0.0;
  }

  // Rigid walls of any shape (crusher plates): a closed TriMesh through
  // Shape::polyhedron, a box, or in 2D a polygon; the shape's level set is used, and its
  // surface nodes are not (grains are always the master side). Kinematic: they move with
  // the velocity and angular velocity (world frame, about the shape's centroid) given by
  // set_shape_wall_motion. Contacts name them wall = kFirstShapeWall + index.
  static constexpr int kFirstShapeWall = 6;
  int add_shape_wall(const Shape::Ptr& shape, const Vec3& position, const Quat& orientation = {});
  void set_shape_wall_motion(int wall, const Vec3& velocity, const Vec3& angular_velocity);
  // Pose of a shape wall, and the total force (N) the grains exert on it.
  Vec3 shape_wall_position(int wall) const;
  Quat shape_wall_orientation(int wall) const;
  Vec3 shape_wall_force(int wall) const;

  // The engine-neutral moving walls (core/MovingWall.h) are shape walls.
  int add_moving_wall(const MovingWall& w) override;
  void set_moving_wall(int index, const WallKinematics& k) override;
  Vec3 moving_wall_force(int index) const override { return shape_wall_force(index); }

  // Checkpoints: body states (positions, half-step velocities, exact quaternions, the last
  // step's motion bounds), every pair's tangential history and candidate nodes, the step
  // stamp, the platen's position and velocity, the shape walls' poses and motion, and the
  // forces last measured. Pairs are written sorted by key, so equal states give equal files.
  bool save_state(nlohmann::json& out) const override;
  void restore_state(const nlohmann::json& state) override;

  const LsdemSettings& settings() const { return s_; }
  const LsdemStats& stats() const { return stats_; }
  void reset_stats() { stats_ = LsdemStats{}; }
  void set_threads(int n) { s_.threads = n < 1 ? 1 : n; }
  // Kinetic energy (J; 2D: per metre) of the grains, translational + rotational.
  double kinetic_energy() const;
  // The normal springs' energy at the last force evaluation (Engine::elastic_energy).
  double elastic_energy() const override { return elastic_energy_; }
  // Selective mass scaling: the target step (s; 0 = off or not yet known), the figures for
  // summary.json, and the kinetic energy (J; 2D: J/m) of the added mass at the grains'
  // true masses: Σ ½(s − 1)·(m·v² + ω·I·ω).
  double selective_target_dt() const { return target_dt_; }
  std::map<std::string, double> summary_figures() const override;
  double added_kinetic_energy() const override;

  struct ShapeData;
  struct Body;
  struct Item;
  struct StateReader;

 private:
  struct NodeHist {
    int node;
    Vec3 ft;  // tangential force (N), world frame
  };
  // Per (master, partner) state kept between steps: tangential history, and the master's
  // nodes within `skin` of the partner at the last full search with the bound on their
  // relative motion since (a node moving by d changes φ by at most √dim·d).
  struct PairState {
    std::vector<NodeHist> hist;
    std::vector<int> cand;
    double drift = 0;
    bool has_cand = false;
    long stamp = -1;  // last step that used it
  };
  struct KeyHash {
    std::size_t operator()(const std::pair<GrainId, GrainId>& k) const {
      const auto a = static_cast<std::uint64_t>(k.first), b = static_cast<std::uint64_t>(k.second);
      return static_cast<std::size_t>((a * 0x9E3779B97F4A7C15ull) ^ (b + 0x7F4A7C159E3779B9ull + (a << 6) + (a >> 2)));
    }
  };
  using Wall = WallPlane;  // normal points into the box
  ShapeData& shape_data(const Shape::Ptr& s);
  std::shared_ptr<const LevelSetGrid> grid_of(const Shape& s) const;
  void compute_forces(double dt);
  // The steps of compute_forces. Work items: grain pairs in reach (their states kept,
  // refreshed or dropped); grains near a shape wall, then near a plane wall (returns the
  // number of items before the plane walls); the narrow phase over the items; the
  // reduction in item order (gravity and global damping first; apply_contact adds one
  // item's forces and contact, true for a grain pair), and the counters.
  bool near_list_stale() const;
  void collect_pair_items();
  std::size_t collect_wall_items(const std::vector<WallPlane>& walls);
  void narrow_phase(const std::vector<WallPlane>& walls, double dt);
  void apply_body_loads();
  void reduce_forces(const std::vector<WallPlane>& walls, std::size_t npairs);
  bool apply_contact(const Item& item, const std::vector<WallPlane>& walls);
  void integrate(double dt);
  // Selective mass scaling: the largest normal stiffness the stable step uses; the step of
  // the current grains at their unscaled masses; the mass and inertia of b for the target
  // (factor 1 below it, or when off); the target fixed at the first step (fraction mode).
  double stiffness_bound() const;
  double unscaled_stable_dt() const;
  double stable_dt(bool unscaled) const;
  void apply_selective_scaling(Body& b) const;
  void set_selective_factor(Body& b, double sel) const;
  // restore_state's reader of the target step and the factors (by grain id).
  std::pair<double, std::map<GrainId, double>> read_selective(StateReader& reader, const nlohmann::json& state) const;
  void fix_selective_target();
  std::vector<Wall> walls() const;
  int up() const { return ctx_.dimension == 3 ? 2 : 1; }

  LsdemSettings s_;
  EngineContext ctx_;
  Container container_;
  bool has_container_ = false;
  std::map<const Shape*, std::shared_ptr<ShapeData>> shapes_;
  std::vector<Body> bodies_;
  std::vector<Body> walls_kin_;         // shape walls (kinematic)
  std::vector<Vec3> shape_wall_force_;  // force of the grains on each shape wall
  std::unordered_map<GrainId, std::size_t> index_;
  // Per (master, partner) key of two grains; states of grain–wall contacts (partner < 0:
  // wall −1 − id) are kept apart in wall_history_ and swept every step.
  std::unordered_map<std::pair<GrainId, GrainId>, PairState, KeyHash> history_;
  std::unordered_map<std::pair<GrainId, GrainId>, PairState, KeyHash> wall_history_;
  long stamp_ = 0;
  // Verlet list of the broad phase: body pairs (i < j, sorted) whose bounding spheres were
  // within `near_skin_` of each other when it was built, with the pair's live state (or
  // null). Rebuilt when two bodies may together have moved more than the skin, and after
  // any change of the bodies; a pair whose spheres overlap now is always in it.
  struct NearPair {
    int i, j;  // bodies, i < j
    int a, b;  // master and partner (the smaller grain is the master)
    double rr;  // sum of the bounding radii
    std::pair<GrainId, GrainId> key;
    PairState* st;
  };
  std::vector<NearPair> near_;
  std::vector<Vec3> near_x0_;
  double near_skin_ = 0;
  bool near_valid_ = false;
  void build_near();
  // restore_state's readers: the saved bodies in their saved order, one pair's state.
  std::vector<Body> read_bodies(StateReader& reader, const nlohmann::json& bodies) const;
  std::pair<std::pair<GrainId, GrainId>, PairState> read_pair(const StateReader& reader, const nlohmann::json& pair) const;
  // The saved shape walls (absent: none), each with the grains' force on it.
  std::vector<std::pair<Body, Vec3>> read_walls(StateReader& reader, const nlohmann::json& state) const;
  std::vector<Item> items_;
  std::vector<Contact> contacts_;
  PlatenDriver platen_;  // the shared platen rules (core/Platen.h), integrated here explicitly
  double platen_force_ = 0, floor_force_ = 0;
  double elastic_energy_ = 0;  // J (2D: J/m), summed over the last step's contacts
  std::array<double, 6> container_wall_force_{};  // by WallId: the grains' push on each container wall
  double friction_scale_ = 1;  // set_friction_scale (settling)
  double global_damping_scale_ = 1;  // set_global_damping_scale (settling)
  double relax_damping_ = 0;   // 1/s, added to global_damping while a packing relaxes
  double target_dt_ = 0;       // s: selective mass scaling's target step (0: off or not yet fixed)
  LsdemStats stats_;
};

// The options of the "engine" object (keys, defaults, ranges: `crumble list --options lsdem`).
const OptionTable& lsdem_options();
// Factory for the registry: cfg is the scenario's "engine" object, read through lsdem_options().
std::unique_ptr<Engine> make_lsdem_engine(const Config& cfg, const EngineContext& ctx);

// The speed benchmark's scene (after YADE's examples/levelSet/discharge.py): `grains`
// superellipsoids (radii `radius`·U(0.8, 1.2) per axis, exponents U(0.4, 1.2), drawn among
// `shapes` distinct shapes with `nodes` surface nodes each) on a cubic lattice of spacing
// 2.6·radius above the floor of a box whose side holds `per_row` grains; they are given a
// small random velocity and fall. Sets the container (no platen); the engine must be empty.
struct LsdemBenchScene {
  int grains = 1000;
  int nodes = 2000;
  int shapes = 10;
  int per_row = 10;
  double radius = 5e-3;  // m
  std::uint64_t seed = 1;
};
void lsdem_bench_scene(LsdemEngine& engine, const LsdemBenchScene& scene);

// Runs `steps` steps of `dt` (0 = the engine's max_stable_dt()) and reports speed and the
// work counters of that phase (the engine's stats are reset first).
LsdemBenchResult lsdem_bench_phase(LsdemEngine& engine, long steps, double dt = 0);

}  // namespace crumble
