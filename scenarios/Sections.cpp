#include "scenarios/Sections.h"

#include <limits>

#include "core/Guards.h"
#include "core/Loading.h"
#include "core/Schedule.h"
#include "core/ShapeSpec.h"
#include "core/Screening.h"
#include "core/Simulation.h"

namespace crumble {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr long kLongMax = std::numeric_limits<long>::max();
}  // namespace

const DefaultImplementations& default_implementations(int dimension) {
  // Bullet is 3D only: a 2D scenario has to name its engine (lsdem). Alpha shapes are 3D
  // only: 2D fragments are level sets.
  static const DefaultImplementations d3{"bullet", "none", "alpha_shape"}, d2{"bullet", "none", "level_set"};
  return dimension == 2 ? d2 : d3;
}

// The "type" of the three seams' sections: the defaults are default_implementations'.
const OptionTable& implementation_options() {
  static const OptionTable t = [] {
    const DefaultImplementations &d3 = default_implementations(3), &d2 = default_implementations(2);
    auto row = [](const std::string& section, const std::string& in3, const std::string& in2, const std::string& doc) {
      OptionSpec spec = opt::string(section + ".type", in3, doc);
      spec.def = std::monostate{};
      spec.default_doc = "\"" + in3 + "\"" + (in2 == in3 ? "" : " (2D: \"" + in2 + "\")");
      return spec;
    };
    return OptionTable{
        row("engine", d3.engine, d2.engine,
            "the engine (`crumble list`); its options sit beside \"type\"; bullet is 3D only, a 2D scenario names lsdem"),
        row("breakage", d3.breakage, d2.breakage, "the breakage model and its options"),
        row("fragments", d3.fragments, d2.fragments,
            "the fragment builder and its options (read when breakage is not none)"),
    };
  }();
  return t;
}

const OptionTable& scenario_options() {
  using S = ScenarioSettings;
  static const OptionTable t = [] {
    const double dt = SimulationSettings{}.time_steps.back().dt;
    return OptionTable{
        opt::string("name", &S::name, "copied to summary.json"),
        opt::string("description", &S::description, "free text"),
        opt::integer("dimension", &S::dimension, 2, 3, "2D is a first-class mode (x–y plane, gravity along −y)"),
        opt::unsigned_integer("seed", &S::seed, "the one seed of the run (packing, strengths)"),
        opt::integer("threads", &S::threads, 1, 1024,
                     "threads for breakage analyses and engines that use them; results do not depend on it"),
        opt::vec3("gravity", &S::gravity, "m/s²", "gravity")
            .depends<S>("[0, 0, -9.81] m/s² (2D: [0, -9.81, 0])",
                        [](const S& s) {
                          const Vec3 g = S{}.gravity;
                          return option_detail::to_value(s.dimension == 3 ? g : Vec3{g.x, g.z, g.y});
                        }),
        opt::positive("time_step", dt, "s",
                      "a number, or rules [{\"below_stress\": Pa, \"dt\": s}, …] (Zhu & Zhao 2019 §5: 8e-5 / 6e-5 / "
                      "5e-5 s below 10 / 24 / above)"),
    };
  }();
  return t;
}

const OptionTable& material_options() {
  using S = Material;
  static const OptionTable t = {
      opt::positive("density", &S::density, "kg/m³", "grain density (Zhu & Zhao 2019 Table 1)"),
      opt::positive("young", &S::young, "Pa", "Young's modulus"),
      opt::number("poisson", &S::poisson, -0.99, 0.5, "", "Poisson's ratio"),
      opt::number("friction", &S::friction, 0, kInf, "", "grain–grain Coulomb friction coefficient"),
      opt::number("wall_friction", &S::wall_friction, 0, kInf, "", "grain–wall Coulomb friction coefficient"),
      opt::number("rolling_friction", &S::rolling_friction, 0, kInf, "", "rolling friction (Bullet convention)"),
      opt::number("restitution", &S::restitution, 0, 1, "",
                  "no engine models restitution, so another value than 0 is an error (on lsdem the contact damping "
                  "engine.damping_ratio sets the energy lost in a contact)"),
  };
  return t;
}

const OptionTable& container_options() {
  using S = ContainerSettings;
  using C = Container;
  static const OptionTable t = [] {
    const auto in_3d = [](const S& s) { return s.dimension == 3; };
    return OptionTable{
        opt::positive("lx", opt::nested(&S::box, &C::lx), "m", "width (x)").required_key(),
        opt::positive("ly", opt::nested(&S::box, &C::ly), "m", "depth (y), 3D").required_key().when<S>(in_3d),
        opt::number("ly", opt::nested(&S::box, &C::ly), 0, 0, "m", "2D: 0 (or left out)")
            .when<S>([in_3d](const S& s) { return !in_3d(s); }),
        opt::number("platen_mass", opt::nested(&S::box, &C::platen_mass), 0, kInf, "kg",
                    "mass of the force-controlled platen; 0 = the grains' total mass"),
        opt::positive("height", opt::nested(&S::box, &C::height), "m", "height up to the platen")
            .if_given("the generated cloud's (required for an explicit packing)"),
    };
  }();
  return t;
}

const OptionTable& packing_options() {
  using S = PackingSettings;
  static const OptionTable t = [] {
    const auto cloud = [](const S& s) { return s.type == "cloud"; };
    return OptionTable{
        opt::choice("type", &S::type, {"cloud", "grains", "file"},
                    "a cloud drawn from a PSD and settled (Zhu & Zhao 2019 §5), an explicit list of grains, or a "
                    "packing.json saved by an earlier run"),
        opt::integer("count", &S::count, 1, 1000000, "cloud: grains drawn").when<S>(cloud),
        opt::boolean("keep_template_size", &S::keep_template_size,
                     "cloud: each grain keeps its template's size (no psd or diameter)")
            .when<S>(cloud),
        opt::positive("diameter", &S::diameter, "m", "cloud: one equivalent diameter for every grain (not with psd)")
            .if_given("the psd's")
            .when<S>([cloud](const S& s) { return cloud(s) && !s.keep_template_size; }),
        opt::number("fill_fraction", &S::fill_fraction, 0.01, 0.5, "",
                    "cloud: solid fraction of the generated cloud (its height follows)")
            .depends<S>("0.2 (2D: 0.35)",
                        [](const S& s) { return s.dimension == 3 ? S{}.fill_fraction : 0.35; })
            .when<S>(cloud),
        opt::integer("material", &S::material, 0, kLongMax, "cloud: material index of every grain").when<S>(cloud),
        opt::boolean("settle", &S::settle, "grains: settle the list under the platen before loading")
            .when<S>([](const S& s) { return s.type == "grains"; }),
        opt::string("path", &S::path, "file: the packing.json of an earlier run")
            .required_key()
            .when<S>([](const S& s) { return s.type == "file"; }),
        opt::choice("relax", &S::relax, {"auto", "on", "off"},
                    "file: before loading, let the packing come to rest on this scenario's engine under the platen "
                    "at settle.stress (settle.* as for a cloud, but enabled); auto = when another engine built "
                    "packing.json (its \"engine\")")
            .when<S>([](const S& s) { return s.type == "file"; }),
    };
  }();
  return t;
}

const OptionTable& grain_entry_options() {
  using S = GrainEntrySettings;
  static const OptionTable t = {
      opt::vec3("position", &S::position, "m", "the grain's centroid (finite)"),
      opt::numbers("orientation", &S::orientation, "", "quaternion [w, x, y, z] (normalised; not zero)"),
      opt::integer("material", &S::material, 0, kLongMax, "material index"),
  };
  return t;
}

const OptionTable& settle_options() {
  using S = SettleSettings;
  static const OptionTable t = {
      opt::boolean("enabled", &S::enabled, "the cloud settles under the platen before loading"),
      opt::number("stress", &S::stress, 0, kInf, "Pa", "pushed by the platen while settling"),
      opt::positive("max_time", &S::max_time, "s", "simulated time at most"),
      opt::number("dt", &S::dt, 0, kInf, "s", "time step; 0 = the scenario's first (capped by the engine's bound)"),
      opt::positive("tolerance", &S::tolerance, "",
                    "settled once the platen moves less than this × the mean diameter per window"),
      opt::positive("window", &S::window, "s", "simulated time between checks"),
      opt::number("friction_scale", &S::friction_scale, 0, 1, "",
                  "friction × this while settling, restored before loading (0: frictionless, a denser packing)"),
      opt::number("global_damping_scale", &S::global_damping_scale, 0, 1, "",
                  "engine.global_damping × this while settling, restored before loading (0: none; Harmon et al. "
                  "2020 Table 2's C_g = 0.01/Δt would hold a grain falling under gravity to g / C_g ≈ 0.2 mm/s)"),
  };
  return t;
}

const OptionTable& relax_options() {
  static const OptionTable t = [] {
    OptionTable r;
    for (const auto& o : settle_options())
      if (o.key != "enabled" && o.key != "friction_scale" && o.key != "global_damping_scale") r.push_back(o);
    return r;
  }();
  return t;
}

const OptionTable& loading_options() {
  using S = LoadingSettings;
  static const OptionTable t = [] {
    const auto mode = [](const char* m) { return [m](const S& s) { return s.mode == m; }; };
    return OptionTable{
        opt::choice("mode", &S::mode, {"stress_ramp", "strain_rate", "none"},
                    "a force-controlled platen ramped to max_stress, a platen moving at strain_rate, or a platen "
                    "held still (a scene with its own length allows only none)"),
        opt::number("duration", &S::duration, 0, kInf, "s", "none: simulated time; 0 = until simulation.max_steps")
            .when<S>(mode("none")),
        opt::positive("max_stress", &S::max_stress, "Pa", "stress_ramp: end value").when<S>(mode("stress_ramp")),
        opt::positive("ramp_time", &S::ramp_time, "s", "stress_ramp: time to reach max_stress")
            .when<S>(mode("stress_ramp")),
        opt::number("hold_time", &S::hold_time, 0, kInf, "s", "stress_ramp: held at max_stress after the ramp")
            .when<S>(mode("stress_ramp")),
        opt::number("initial_stress", &S::initial_stress, 0, kInf, "Pa", "stress_ramp: value at t = 0")
            .when<S>(mode("stress_ramp")),
        opt::positive("strain_rate", &S::strain_rate, "1/s", "strain_rate: axial strain rate")
            .when<S>(mode("strain_rate")),
        opt::number("stop_stress", &S::stop_stress, 0, kInf, "Pa", "stop at this platen stress; 0 = none"),
        opt::number("stop_force", &S::stop_force, 0, kInf, "N", "stop at this platen force; 0 = none"),
        opt::number("stop_strain", &S::stop_strain, 0, 1, "", "stop at this axial strain; 0 = none"),
    };
  }();
  return t;
}

const OptionTable& simulation_options() {
  using S = SimulationSettings;
  static const OptionTable t = {
      opt::integer("max_steps", &S::max_steps, 0, kLongMax, "0 = no limit (the loading decides)"),
      opt::integer("sample_every", &S::sample_every, 1, kLongMax, "steps between series rows"),
      opt::number("fines_diameter", &S::fines_diameter, 0, kInf, "m",
                  "children smaller than this leave the engine; their mass is counted as removed and stays in every "
                  "PSD"),
      opt::boolean("auto_reduce_dt", &S::auto_reduce_dt,
                   "a step above an explicit engine's stable bound is reduced with a warning and counted in "
                   "dt_reductions; false makes it an error, reported by crumble validate already when the packing's "
                   "grains set the bound (e.g. lsdem)"),
      opt::integer("stop_after_breakage_events", &S::stop_after_breakage_events, 0, kLongMax,
                   "stop after this many breakage events; 0 = never"),
  };
  return t;
}

const OptionTable& guard_options() {
  using S = GuardSettings;
  static const OptionTable t = {
      opt::boolean("enabled", &S::enabled, "false switches every guard off except the non-finite check"),
      opt::number("max_overlap_fraction", &S::max_overlap_fraction, 0, 1, "",
                  "largest overlap of one contact / the smaller grain's equivalent diameter (wall contact: the "
                  "grain's); fragments of the same initial grain are exempt from each other"),
      opt::number("energy_factor", &S::energy_factor, 0, kInf, "",
                  "kinetic energy may not exceed this × the energy that can have entered (initial kinetic energy + "
                  "platen work + every grain's weight over the container height)"),
      opt::number("small_grain_fraction", &S::small_grain_fraction, 0, 1, "",
                  "a contact whose smaller grain is below this × the initial mean diameter is counted "
                  "(guard_small_grain_overlaps) instead of stopping the run when it overlaps beyond the limit; such "
                  "a grain that leaves the container is taken out as fines"),
      opt::boolean("containment", &S::containment,
                   "every grain centroid between the side walls, above the floor and below the platen"),
  };
  return t;
}

const OptionTable& schedule_options() {
  using S = ScheduleSettings;
  static const OptionTable t = {
      opt::number("every_stress", &S::every_stress, 0, kInf, "Pa",
                  "breakage is checked every this much platen stress; 0 disables the rule")
          .depends("the breakage model's (peridynamics: 0.08e6, Zhu & Zhao 2019 §5; stress: 0)"),
      opt::integer("every_steps", &S::every_steps, 0, kLongMax, "… and every this many steps; 0 disables the rule")
          .depends("the breakage model's (peridynamics: 0; stress: 100)"),
  };
  return t;
}

const OptionTable& output_options() {
  using S = OutputSettings;
  static const OptionTable t = [] {
    OptionTable o{
        opt::integer("series_every", &S::series_every, 0, kLongMax, "steps between series rows; 0 = simulation.sample_every"),
        opt::numbers("psd_at_stress", &S::psd_at_stress, "Pa",
                     "a psd.csv table when the stress first passes each (a level never reached: the final state, "
                     "labelled as such)"),
        opt::numbers("psd_at_strain", &S::psd_at_strain, "",
                     "axial strains in (0, 1): a psd.csv table at the first sample whose strain reaches each"),
        opt::boolean("shape_metrics", &S::shape_metrics, "shape.csv (below)"),
        opt::boolean("intact_analyses", &S::intact_analyses,
                     "false: events.csv gets rows only for the analyses that broke their grain"),
    };
    for (auto& v : vtk_output_options_of<S>()) o.push_back(std::move(v));
    for (auto& v : OptionTable{
             opt::integer("checkpoint_every", &S::checkpoint_every, 0, kLongMax,
                          "steps between writes of checkpoint.json; 0 = none"),
             opt::boolean("plots", &S::plots, "PNG figures at the end of crumble run (they need python3-matplotlib)"),
             opt::integer("psd_layers", &S::psd_layers, 0, 100,
                          "N > 0: psd_layers.csv, sieve curves of N layers of the initial packing (Liu et al. 2019 "
                          "§4.3.3); 0 = none"),
             opt::number("checkpoint_every_s", &S::checkpoint_every_s, 0, kInf, "s",
                         "wall-time seconds between writes of checkpoint.json; 0 = none"),
         })
      o.push_back(std::move(v));
    return o;
  }();
  return t;
}

const OptionTable& scene_options() {
  using S = SceneSettings;
  static const OptionTable t = [] {
    const auto single = [](const S& s) { return s.type == "single_grain"; };
    return OptionTable{
        opt::choice("type", &S::type, {"single_grain", "jaw_crusher"},
                    "one grain between floor and platen (Zhu & Zhao 2019 §4.2), or the 2D jaw crusher of Harmon et "
                    "al. 2020 §4 (its own table)"),
        opt::positive("diameter", &S::diameter, "m", "single_grain: the grain's equivalent diameter").when<S>(single),
        opt::integer("material", &S::material, 0, kLongMax, "single_grain: material index").when<S>(single),
        opt::number("platen_mass", &S::platen_mass, 0, kInf, "kg", "single_grain: 0 = the grain's mass")
            .when<S>(single),
    };
  }();
  return t;
}

const OptionTable& jaw_crusher_options() {
  using S = JawCrusherSettings;
  static const OptionTable t = {
      opt::positive("css", &S::css, "m", "closed side setting (Harmon et al. 2020 §4.2 run 0.05, 0.08, 0.1)"),
      opt::positive("throw", &S::throw_, "m", "eccentric throw = OSS − CSS (Table 1)"),
      opt::positive("rpm", &S::rpm, "", "revolutions of the eccentric per minute (Table 1)"),
      opt::number("nip_angle", &S::nip_angle, 1, 60, "°", "mean angle between the plates (Table 1)"),
      opt::number("nip_angle_variation", &S::nip_angle_variation, 0.01, 20, "°",
                  "the swing jaw's amplitude (Table 1)"),
      opt::positive("cycles", &S::cycles, "", "revolutions simulated (§4.2: forty)"),
      opt::positive("plate_thickness", &S::plate_thickness, "m", "the plates' rectangles"),
      opt::positive("plate_level_set_spacing", &S::plate_level_set_spacing, "m", "the plates' level-set grids"),
      opt::number("phase", &S::phase, -kInf, kInf, "rad",
                  "phase of the eccentric at t = 0 (0: mean opening, closing after half a turn)"),
      opt::number("hopper_height", &S::hopper_height, 0, kInf, "m",
                  "two fixed vertical walls above the plates' tops (0 = none): fragments thrown up by the squeeze "
                  "fall back into the crusher (our addition; the paper's frame is not described)"),
      opt::positive("discharge_depth", &S::discharge_depth, "m", "below the plates' bottoms, grains leave as product"),
  };
  return t;
}

const OptionTable& rock_options() {
  using S = RockFeedSettings;
  static const OptionTable t = {
      opt::integer("count", &S::count, 0, kLongMax, "rocks fed in total"),
      opt::numbers("diameter", &S::diameter, "m",
                   "[d_min, d_max]: range of the rocks' equivalent diameters; a rock wider than the feed opening is an "
                   "error"),
      opt::positive("level_set_spacing", &S::level_set_spacing, "m", "the rocks' grids (Table 1: 7 mm per pixel)"),
      opt::positive("surface_points_per_cell", &S::surface_points_per_cell, "",
                    "surface nodes per grid cell (Table 1: 2 per pixel)"),
      opt::integer("material", &S::material, 0, kLongMax, "material index"),
      opt::number("spawn_height", &S::spawn_height, 0, kInf, "m",
                  "drop height of a rock's lowest point above the plates' tops"),
  };
  return t;
}

const OptionTable& wall_options() {
  using S = WallSettings;
  static const OptionTable t = {
      opt::string("name", &S::name, "the wall's name").depends("\"wall_INDEX\""),
      opt::vec3("position", &S::position, "m", "centroid; in 2D z = 0"),
      opt::numbers("orientation", &S::orientation, "", "quaternion [w, x, y, z]; in 2D a turn about z only"),
  };
  return t;
}

const OptionTable& motion_options() {
  using S = WallMotion;
  using T = WallMotion::Type;
  static const OptionTable t = [] {
    const auto is = [](T type) { return [type](const S& s) { return s.type == type; }; };
    return OptionTable{
        opt::mapped_choice("type", &S::type, {{"fixed", T::Fixed}, {"eccentric", T::Eccentric}, {"velocity", T::Velocity}},
                           "fixed: stays at its pose; velocity: x(t) = x0 + v·t, turned by ω·t; eccentric: the swing "
                           "jaw of a single-toggle jaw crusher"),
        opt::vec3("velocity", &S::velocity, "m/s", "velocity: translation").when<S>(is(T::Velocity)),
        opt::vec3("angular_velocity", &S::angular_velocity, "rad/s", "velocity: rotation about the centroid")
            .when<S>(is(T::Velocity)),
        opt::vec3("pivot", &S::pivot, "m", "eccentric: the point the wall turns about").when<S>(is(T::Eccentric)),
        opt::vec3("axis", &S::axis, "", "eccentric: the rotation axis (2D: z)").when<S>(is(T::Eccentric)),
        opt::positive("throw", &S::throw_, "m", "eccentric: chord travelled by the point at the lever")
            .required_key()
            .when<S>(is(T::Eccentric)),
        opt::positive("lever", &S::lever, "m", "eccentric: distance of that point from the pivot (throw ≤ 2·lever)")
            .required_key()
            .when<S>(is(T::Eccentric)),
        opt::positive("rpm", &S::rpm, "", "eccentric: revolutions per minute").required_key().when<S>(is(T::Eccentric)),
        opt::number("phase", &S::phase, -kInf, kInf, "rad", "eccentric: θ(t) = A·sin(2π·rpm/60·t + phase)")
            .when<S>(is(T::Eccentric)),
    };
  }();
  return t;
}

std::vector<SectionOptions> scenario_sections() {
  return {
      {"scenario", "the top level of a scenario", &scenario_options()},
      {"implementations", "the type of the engine, breakage and fragments sections", &implementation_options()},
      {"materials", "one entry of \"materials\" (Zhu & Zhao 2019 Table 1)", &material_options()},
      {"container", "the rigid box", &container_options()},
      {"packing", "the packing (cloud, grains or file)", &packing_options()},
      {"settle", "packing.settle: how a cloud settles (Zhu & Zhao 2019 §5)", &settle_options()},
      {"grains", "one entry of packing.grains (SHAPE, pose, material)", &grain_entry_options()},
      {"loading", "the platen's loading", &loading_options()},
      {"simulation", "loop settings", &simulation_options()},
      {"guards", "simulation.guards: physical invariants every engine must keep", &guard_options()},
      {"schedule", "when breakage is checked", &schedule_options()},
      {"screening", "which grains are analysed; the skip rule for grains analysed whole", &screening_options()},
      {"output", "what is written besides summary, series and events", &output_options()},
      {"scene", "a whole set-up from a few numbers (instead of container and packing)", &scene_options()},
      {"jaw_crusher", "the jaw_crusher scene (Harmon et al. 2020 §4, Table 1)", &jaw_crusher_options()},
      {"rocks", "scene.rocks of the jaw crusher", &rock_options()},
      {"walls", "one entry of \"walls\"", &wall_options()},
      {"motion", "walls[i].motion", &motion_options()},
      {"shape", "every SHAPE", &shape_options()},
      {"resolution", "SHAPE.resolution: how finely a shape is discretised", &shape_resolution_options()},
      {"superellipsoid", "SHAPE of type superellipsoid, besides radii", &superellipsoid_options()},
      {"superellipse", "SHAPE of type superellipse (2D), besides radii", &superellipse_options()},
      {"random_polygon", "SHAPE of type random_polygon (2D)", &random_polygon_options()},
      {"pool", "a packing template of type pool (2D), besides the random_polygon keys", &pool_options()},
  };
}

}  // namespace crumble
