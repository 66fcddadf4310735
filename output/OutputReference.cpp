#include "output/OutputReference.h"

#include <algorithm>
#include <stdexcept>

namespace crumble {

using Json = nlohmann::json;

namespace {

// ------------------------------------------------------------------ CSV files of a run

OutputCsv series_csv() {
  return {"series.csv",
          "every run, one row per sample (`output.sample_every` steps) and one at the start",
          {{"time_s", "s", "simulated time"},
           {"step", "1", "time step number"},
           {"dt_s", "s", "time step"},
           {"platen_stress_Pa", "Pa", "vertical stress the grains push the platen with: its force over the container's "
                                      "cross-section (2D: N/m over the width)"},
           {"target_stress_Pa", "Pa", "stress a `stress_ramp` loading commands at this time (0 under other loading modes)"},
           {"axial_strain", "1", "platen displacement over the initial sample height"},
           {"void_ratio", "1", "pore volume over solid volume below the platen (removed fines stay in the solid volume)"},
           {"grains", "1", "grains in the engine"},
           {"breakage_events", "1", "breakage events so far"},
           {"analyses", "1", "breakage analyses so far"},
           {"platen_height_m", "m", "height of the platen above the floor"},
           {"platen_force_N", "N", "force the grains push the platen up with (2D: N per m of thickness)"},
           {"floor_force_N", "N", "force the grains push the floor down with (2D: N per m of thickness)"},
           {"k0", "1", "lateral stress ratio σ_h/σ_v from the side walls' forces over their loaded areas; empty where "
                       "undefined (no vertical stress yet, an open scene)"}}};
}

OutputCsv events_csv() {
  return {
      "events.csv",
      "every run, one row per breakage analysis (`output.intact_analyses` false: only the analyses that broke their "
      "grain), the breakage written on its analysis's row",
      {{"time_s", "s", "simulated time of the check"},
       {"step", "1", "time step of the check"},
       {"platen_stress_Pa", "Pa", "platen stress at the check"},
       {"grain", "1", "id of the grain analysed"},
       {"diameter_m", "m", "its equivalent diameter (sphere, 2D disk, of the same volume, area)"},
       {"generation", "1", "0 for the packing, parent's + 1 for a fragment"},
       {"wall_ms", "ms", "wall time of the analysis"},
       {"outcome", "", "the model's word for the result: split (broken), intact, no_load, failed, … "
                       "(docs/scenarios.md of each model)"},
       {"max_force_N", "N", "largest contact force the analysis considered"},
       {"children", "1", "fragments put into the engine (0: the grain stayed whole)"},
       {"child_volumes_m3", "m³", "their volumes, separated by `;` (2D: areas, m²)"},
       {"child_diameters_m", "m", "their equivalent diameters, separated by `;`"},
       {"removed_volume_m3", "m³", "volume removed as fines (2D: area, m²)"},
       {"fragment_method", "", "how the children were built (the fragment builder's word; empty without breakage)"},
       {"<figure>", "", "one column per figure the breakage model declares (BreakageModel::figure_names, in its "
                        "order; empty where the analysis did not set it), listed below"},
       {"points", "1", "lattice points of the analysis", "peridynamics"},
       {"bonds", "1", "bonds of the lattice (peridynamics) or of the elements (bonded_particles)", "peridynamics, bonded_particles"},
       {"steps", "1", "time steps of the analysis", "peridynamics, block_beam, bonded_particles"},
       {"force_at_split_N", "N", "contact force reached when the grain split (0: it did not)", "peridynamics, block_beam, bonded_particles"},
       {"first_break_force_N", "N", "largest contact force at which the static solution breaks its first bond "
                                    "(`elastic_preload`; 0 without it)", "peridynamics"},
       {"hold_steps", "1", "steps at full load, to the split or the end", "peridynamics"},
       {"quiet_transits_max", "1", "longest stretch at full load without a newly broken bond, in P-wave transits",
        "peridynamics"},
       {"threads", "1", "threads the analysis ran on", "peridynamics"},
       {"sigma_1_Pa", "Pa", "largest principal value of the average stress σ̄ = (1/V) Σ x_c ⊗ F_c (Harmon et al. "
                            "2020, eq. 5)", "stress"},
       {"sigma_2_Pa", "Pa", "second principal value of σ̄", "stress"},
       {"sigma_3_Pa", "Pa", "third principal value of σ̄ (3D only)", "stress"},
       {"equivalent_stress_Pa", "Pa", "the criterion's equivalent stress (Harmon et al. 2020, eqs. 7–10)", "stress"},
       {"strength_Pa", "Pa", "the grain's strength σ0 (eq. 12, scaled by eq. 13 for fragments)", "stress"},
       {"tensile_strength_Pa", "Pa", "the grain's tensile strength (criterion `max_principal` only)", "stress"},
       {"plane_through_centroid", "1", "1 when the split plane passes through the centroid", "stress"},
       {"blocks", "1", "blocks of the grain's tessellation", "block_beam"},
       {"beams", "1", "beams joining the blocks", "block_beam"},
       {"broken_beams", "1", "beams broken in the analysis", "block_beam"},
       {"elements", "1", "bonded elements of the grain", "bonded_particles"},
       {"broken_bonds", "1", "bonds broken in the analysis", "bonded_particles"},
       {"pieces", "1", "pieces the broken bonds leave", "bonded_particles"},
       {"largest_piece_deca_m", "m", "equivalent diameter of the largest piece", "bonded_particles"},
       {"inner_pore_volume_m3", "m³", "pore volume enclosed by the elements", "bonded_particles"}}};
}

OutputCsv psd_csv() {
  return {"psd.csv",
          "every run: a size distribution by mass at the start (`initial`), when the platen stress first reaches each "
          "`output.psd_at_stress` level, the axial strain each `output.psd_at_strain` level, and at the end; 25 sieves "
          "from the largest initial grain down by factors of 2^(1/4), removed fines counted finer than every sieve",
          {{"label", "", "`initial`, `level_<Pa>`, `strain_<value>`, `final`; a level never reached is tabled from the "
                         "final state as `level_<Pa>_not_reached_final_at_<Pa>_Pa` (`strain_…_not_reached_final_at_…`)"},
           {"platen_stress_Pa", "Pa", "platen stress when the table was taken"},
           {"sieve_diameter_m", "m", "sieve size (equivalent diameter)"},
           {"percent_passing_by_mass", "%", "mass finer than the sieve over the total (grains and removed fines)"},
           {"axial_strain", "1", "axial strain when the table was taken"},
           {"step", "1", "step of the sample the table was taken at"}}};
}

OutputCsv breakage_per_mpa_csv() {
  return {"breakage_per_mpa.csv",
          "every run, at the end: breakage events per 1 MPa of platen stress (Zhu & Zhao 2019, Fig. 12)",
          {{"stress_from_MPa", "MPa", "lower bound of the stress bin"},
           {"stress_to_MPa", "MPa", "upper bound"},
           {"breakage_events", "1", "breakage events with their platen stress in the bin"}}};
}

OutputCsv shape_csv() {
  return {"shape.csv",
          "runs with `output.shape_metrics`: number means of the grains' shape descriptors, one row per sample",
          {{"time_s", "s", "simulated time"},
           {"step", "1", "time step"},
           {"axial_strain", "1", "axial strain"},
           {"platen_stress_Pa", "Pa", "platen stress"},
           {"grains", "1", "grains in the engine"},
           {"mean_circularity", "1", "mean circularity (Harmon et al. 2020, eq. 23)", "2D"},
           {"mean_aspect_ratio", "1", "mean aspect ratio of the best-fit ellipse", "2D"},
           {"mean_sieve_size_m", "m", "mean sieve size (Harmon et al. 2020, eq. 21)", "2D"},
           {"mean_sphericity", "1", "mean Wadell sphericity", "3D"},
           {"mean_EI", "1", "mean Zingg elongation index", "3D"},
           {"mean_FI", "1", "mean Zingg flatness index", "3D"}}};
}

OutputCsv stages_csv() {
  return {"stages.csv",
          "every run: one row per MPa of vertical stress (`stress` axis) or, under loading.mode `strain_rate`, per "
          "percent of axial strain (`strain` axis), and one for the stage in progress at the end; `crumble stages DIR` "
          "reads it",
          {{"stress_from_MPa", "MPa", "stress at the stage's start", "stress"},
           {"stress_to_MPa", "MPa", "stress at its end", "stress"},
           {"strain_from_percent", "%", "axial strain at the stage's start", "strain"},
           {"strain_to_percent", "%", "axial strain at its end", "strain"},
           {"complete", "1", "1 for a whole stage, 0 for the one in progress at the end"},
           {"resumed", "1", "1 when a resume cut the stage (its wall time misses what came before the resume)"},
           {"step", "1", "step at the stage's end"},
           {"time_s", "s", "simulated time at its end"},
           {"grains_start", "1", "grains at its start"},
           {"grains", "1", "grains at its end"},
           {"wall_s", "s", "wall time of the stage"},
           {"wall_total_s", "s", "wall time of the loading so far"},
           {"steps", "1", "steps of the stage"},
           {"engine_s", "s", "engine time of the stage"},
           {"engine_ms_per_step", "ms", "engine time per step"},
           {"analyses", "1", "breakage analyses in the stage"},
           {"breaking_analyses", "1", "analyses in the stage that broke their grain"},
           {"analysis_s", "s", "wall time of the analyses in the stage"},
           {"mean_analysis_ms", "ms", "mean wall time of one analysis (all threads)"},
           {"breaking_share_of_analysis_time", "1", "share of the analysis time spent on analyses that broke a grain"},
           {"fragments_s", "s", "time building fragments in the stage"},
           {"analyses_total", "1", "analyses so far"},
           {"breakage_events_total", "1", "breakage events so far"}}};
}

OutputCsv ncl_csv() {
  return {"ncl.csv",
          "every run, at the end, from series.csv: the compression line",
          {{"platen_stress_Pa", "Pa", "platen stress (samples with a positive stress)"},
           {"log10_stress", "1", "log10 of it in Pa"},
           {"void_ratio", "1", "void ratio"},
           {"grains", "1", "grains in the engine"}}};
}

OutputCsv psd_summary_csv() {
  return {"psd_summary.csv",
          "every run, at the end: one row per table of psd.csv",
          {{"label", "", "the table's label in psd.csv"},
           {"platen_stress_Pa", "Pa", "platen stress of the table"},
           {"axial_strain", "1", "axial strain of the table"},
           {"fractal_dimension_by_mass", "1", "fractal dimension read from the size distribution by mass (empty where "
                                              "undefined)"},
           {"relative_breakage", "1", "Hardin (1985) relative breakage B_r against the initial table (empty where "
                                      "undefined)"},
           {"breakage_cutoff_m", "m", "the size below which B_r counts no breakage potential"}}};
}

OutputCsv load_displacement_csv() {
  return {"load_displacement.csv",
          "every run, at the end, from series.csv: the platen's load–displacement curve",
          {{"platen_displacement_m", "m", "platen travel from its first sample"},
           {"platen_force_N", "N", "platen force"}}};
}

OutputCsv psd_layers_csv() {
  return {"psd_layers.csv",
          "runs with `output.psd_layers` > 0, at the end: the final size distribution of each horizontal layer of the "
          "initial packing (grains and fragments by the layer of their origin), at the sieves of Liu et al. 2019 "
          "§4.3.3 scaled to the largest grain",
          {{"layer", "1", "layer number, 1 at the top"},
           {"layer_top_m", "m", "initial height of the layer's top"},
           {"layer_bottom_m", "m", "initial height of its bottom"},
           {"layer_mass_kg", "kg", "final mass of the layer's grains"},
           {"sieve_diameter_m", "m", "sieve size"},
           {"percent_passing_by_mass", "%", "mass of the layer finer than the sieve"}}};
}

OutputCsv product_psd_csv() {
  return {"product_psd.csv",
          "open scenes (a jaw crusher), at the end: the size distribution by mass of what left through the discharge, "
          "at the sieves 1 mm · 2^(k/2) spanning the product; fines removed inside the scene pass every sieve",
          {{"sieve_m", "m", "sieve size (the minor-axis sieve size, Harmon et al. 2020 §4.2)"},
           {"passing_percent", "%", "product mass passing the sieve"},
           {"passing_mass_kg", "kg", "the same as a mass"}}};
}

OutputCsv product_csv() {
  return {"product.csv",
          "open scenes, at the end: one row per grain that left through the discharge",
          {{"time", "s", "simulated time it left"},
           {"grain", "1", "its id"},
           {"origin", "1", "the grain of the initial packing or feed it descends from"},
           {"generation", "1", "its generation"},
           {"equivalent_diameter_m", "m", "its equivalent diameter"},
           {"sieve_m", "m", "its sieve size"},
           {"mass_kg", "kg", "its mass (2D: per m of thickness)"}}};
}

// ------------------------------------------------------------------ compare and sweep

std::vector<OutputColumn> time_part_columns() {
  return {{"time_<part>_s", "s",
           "summary.json time_breakdown_s.<part>, one column per part: engine, contacts, screening, analyses, "
           "fragments, guards, output"}};
}

OutputCsv comparison_csv() {
  OutputCsv c{"comparison.csv",
              "`crumble compare` (and `crumble sweep`), in its output folder: one row per combination, every figure at "
              "full precision (comparison.md shows the same for a person)",
              {{"<path>", "", "one column per varied path (`--vary PATH=…`): the combination's value"},
               {"folder", "", "the combination's run folder"},
               {"status", "", "ok, failed, interrupted, bad input, crashed or not run"},
               {"exit_status", "1", "exit status of the run"},
               {"reason", "", "why a run did not finish (empty for ok)"},
               {"engine", "", "summary.json engine"},
               {"breakage", "", "summary.json breakage"},
               {"fragments", "", "summary.json fragments"},
               {"grains_initial", "1", "summary.json grains_initial"},
               {"grains_final", "1", "summary.json grains_final"},
               {"breakage_events", "1", "summary.json breakage_events"},
               {"void_ratio_initial", "1", "summary.json void_ratio_initial"},
               {"void_ratio_at_<level>", "1", "one column per reported level: summary.json "
                                              "void_ratio_at_stress_<Pa>_Pa, void_ratio_at_strain_<value>"},
               {"void_ratio_final", "1", "summary.json void_ratio_final"},
               {"max_platen_stress_Pa", "Pa", "summary.json max_platen_stress_Pa"},
               {"psd_d50_final_m", "m", "summary.json psd_d50_final_m"},
               {"fines_fraction_final", "1", "summary.json fines_fraction_final"},
               {"fines_size_m", "m", "summary.json fines_size_m"},
               {"<figure>", "", "the figures some scenes report, a column each when some row has it: "
                                "crushing_force_N, characteristic_strength_Pa, crushing_stress_Pa, product_d50_m, "
                                "ncl_loglog_slope, relative_breakage_final, k0_final (their summary.json keys)"},
               {"steps", "1", "summary.json steps"},
               {"wall_seconds", "s", "summary.json wall_seconds"}}};
  for (auto& col : time_part_columns()) c.columns.push_back(col);
  c.columns.push_back({"packing_hash", "", "SHA-256 of the packing the run started from"});
  return c;
}

OutputCsv sweep_csv() {
  OutputCsv c{"sweep.csv",
              "`crumble sweep`, in its output folder: one row per setting, its metrics against the reference setting "
              "(pareto.md shows the same for a person)",
              {{"<path>", "", "one column per swept path (`--param`): the setting's value"},
               {"folder", "", "the setting's run folder"},
               {"status", "", "ok, failed, interrupted, bad input, crashed or not run"},
               {"exit_status", "1", "exit status of the run"},
               {"reason", "", "why a run did not finish (empty for ok)"},
               {"reference", "1", "1 for the reference setting"},
               {"wall_seconds", "s", "summary.json wall_seconds"}}};
  for (auto& col : time_part_columns()) c.columns.push_back(col);
  c.columns.push_back({"peak_rss_bytes", "B", "peak resident memory of the run process (getrusage ru_maxrss)"});
  c.columns.push_back({"<metric>", "", "two columns per chosen metric (`--metric`): `<metric>_<unit>` (`<metric>` "
                                       "for a pure number), its value, and `<metric>_rel_error`, its relative "
                                       "error against the reference"});
  c.columns.push_back({"error", "1", "the setting's error: the largest relative error of its metrics (empty when none is defined)"});
  c.columns.push_back({"on_front", "1", "1 when the setting is on the front of cost (wall_seconds) and error: no other setting is cheaper and as accurate or more"});
  return c;
}

// ------------------------------------------------------------------ summary.json

template <auto Member>
Json field(const RunSummary& s) {
  return s.*Member;
}

std::vector<SummaryKey> run_keys() {
  return {
      {"scenario", "", "the scenario's name", ""},
      {"engine", "", "the engine (`engine.type`)", ""},
      {"breakage", "", "the breakage model (`breakage.type`)", ""},
      {"fragments", "", "the fragment builder (`fragments.type`)", ""},
      {"seed", "1", "the random seed", ""},
      {"threads", "1", "threads of the run", ""},
      {"wall_seconds", "s", "wall time of the run (packing and loading)", "", &field<&RunSummary::wall_seconds>},
      {"steps", "1", "time steps of the loading", "", &field<&RunSummary::steps>},
      {"simulated_time_s", "s", "simulated time at the end", "", &field<&RunSummary::time>},
      {"grains_initial", "1", "grains at the start of the loading", "", &field<&RunSummary::grains_initial>},
      {"grains_final", "1", "grains in the engine at the end", "", &field<&RunSummary::grains_final>},
      {"breakage_events", "1", "breakage events", "", &field<&RunSummary::breakage_events>},
      {"analyses", "1", "breakage analyses", "", &field<&RunSummary::analyses>},
      {"analyses_skipped", "1", "grains screened in whose analysis the skip rule spared", "",
       &field<&RunSummary::analyses_skipped>},
      {"fragment_fallbacks", "1", "documented fallbacks the fragment builders took", "",
       &field<&RunSummary::fragment_fallbacks>},
      {"dt_reductions", "1", "times the time step was reduced", "", &field<&RunSummary::dt_reductions>},
      {"mass_initial_kg", "kg", "solid mass at the start (2D: per m of thickness)", "",
       &field<&RunSummary::mass_initial>},
      {"mass_final_kg", "kg", "solid mass in the engine at the end", "", &field<&RunSummary::mass_final>},
      {"mass_removed_kg", "kg", "mass removed as fines", "", &field<&RunSummary::mass_removed>},
      {"void_ratio_initial", "1", "void ratio at the start of the loading", "",
       &field<&RunSummary::void_ratio_initial>},
      {"void_ratio_final", "1", "void ratio at the end", "", &field<&RunSummary::void_ratio_final>},
      {"max_platen_stress_Pa", "Pa", "largest platen stress of the run", "", &field<&RunSummary::max_platen_stress>},
      {"interrupted", "", "true when a signal stopped the run early", "interrupted runs"},
      {"packing_hash", "", "SHA-256 of packing.json (or of the packing file the run started from)", ""},
      {"packing_settle_steps", "1", "steps the packing settled for (of the run it continues, when resumed)",
       "runs that settled a packing or resume one"},
      {"packing_settled", "1", "1 when the packing met its settling criterion",
       "runs that settled a packing or resume one"},
      {"resumed_from_step", "1", "step the loading resumed at", "`--resume` in the loading"},
      {"resumed_from_settle_step", "1", "settling step the packing resumed at", "`--resume` in the settling"},
      {"resume_changes", "", "the settings changed on `--resume` (array)", "`--resume` with changed settings"},
      {"notes", "", "every note of the run, printed or not: `note`, `setting` (its JSON path, when about one), "
                    "`deliberate` (the scenario's reason, when declared; then not printed)", ""},
      {"method", "", "what the scenario's `method` set: `name`, `sets` (path = value), `left_as_given`",
       "scenarios with a `method`"},
      {"fidelity", "", "what the fidelity preset did: `preset`, `sets`, `left_as_given`, `left_as_method_set`, "
                       "`changes_nothing`, `note`", "scenarios with a `fidelity` preset"},
      {"packing_relaxed", "1", "1 when the file packing relaxed on this engine before loading (`packing.relax`)",
       "file packings"},
      {"relax_<figure>", "",
       "what the relaxation did: steps, converged (1/0), platen_stress_first_Pa / _max_Pa / _final_Pa (Pa), "
       "grain_displacement_max_m / _mean_m (m, from the file's positions), void_ratio_before / _after",
       "relaxed file packings"},
      {"analysis_ranks", "1", "MPI ranks running analyses", "runs with an analysis executor (MPI)"},
      {"analyses_per_rank", "1", "analyses per rank (array)", "runs with an analysis executor (MPI)"},
      {"analysis_seconds_per_rank", "s", "analysis seconds per rank (array)", "runs with an analysis executor (MPI)"},
      {"representations_built.<kind>", "1",
       "geometric representations built by the run, per kind: level_set_grids, meshes, outlines, convex_hulls, "
       "mesh_distance_trees, alpha_shapes, meshes_clipped, level_set_splits, pd_lattices", ""},
      {"stage", "", "`packing`: the summary of `--packing-only` (then with grains, the packing keys and "
                    "representations_built, and no loading figures)", "`--packing-only`"},
      {"grains", "1", "grains of the packing", "`--packing-only`"}};
}

template <auto Member>
Json timing(const RunSummary& s) {
  return s.timings.*Member;
}

Json fragments_per_event(const RunSummary& s) {
  return s.breakage_events > 0 ? s.timings.fragments / static_cast<double>(s.breakage_events) : 0.0;
}

std::vector<SummaryKey> time_keys() {
  return {
      {"time_breakdown_s.engine", "s", "wall time in the engine's steps", "", &timing<&Timings::engine>},
      {"time_breakdown_s.contacts", "s", "reading the contacts", "", &timing<&Timings::contacts>},
      {"time_breakdown_s.screening", "s", "screening grains for analysis", "", &timing<&Timings::screening>},
      {"time_breakdown_s.analyses", "s", "breakage analyses", "", &timing<&Timings::analyses>},
      {"time_breakdown_s.fragments", "s", "building the children and putting them into the engine", "",
       &timing<&Timings::fragments>},
      {"time_breakdown_s.guards", "s", "the physical guards' checks", "", &timing<&Timings::guards>},
      {"time_breakdown_s.output", "s", "the output writers", "", &timing<&Timings::observers>},
      {"time_breakdown_s.loop", "s", "the rest of the loading loop (platen command, state read-out, schedule)", "",
       &timing<&Timings::loop>},
      {"time_breakdown_s.output_by_writer.<writer>", "s",
       "`output` by writer (series, events, psd, vtk, …): the parts sum to `output`", ""},
      {"time_breakdown_s.fragments_per_event", "s", "`fragments` per breakage event (0 without one)", "",
       &fragments_per_event}};
}

std::vector<SummaryKey> simulation_keys() {
  return {
      {"mass_removed_crushed_kg", "kg", "removed as fines: grains the fragment builder removed whole (outcome crushed); the paths sum to mass_removed_kg", ""},
      {"mass_removed_chip_kg", "kg", "removed as fines: pieces the builder removed when it kept one child (outcome chip)", ""},
      {"mass_removed_split_pieces_kg", "kg", "removed as fines: pieces the builder removed from a split into two children or more", ""},
      {"mass_removed_fines_diameter_kg", "kg", "removed as fines: children finer than `simulation.fines_diameter`", ""},
      {"mass_removed_guard_kg", "kg", "removed by the guards: small grains that left the container", ""},
      {"screening_<reason>", "1",
       "grain checks per screening outcome: too_small, few_contacts, below_threshold, unbalanced_force, "
       "unbalanced_moment (turned away) and selected (passed every rule)", ""},
      {"fragment_refinements", "1", "splits the fragment builder repeated on a finer grid", ""},
      {"fragment_pieces_absorbed", "1", "unresolved pieces the fragment builder merged into a kept child", ""},
      {"fragment_unresolved", "1", "broken grains the fragment builder could not cut into a piece it resolves, left whole (outcome unresolved)", ""},
      {"fragment_grid_nodes_per_child", "1", "mean nodes of the children's grids per child built (0 without children)", ""},
      {"analyses_failed", "1", "analyses or fragment builds that failed (the grain stayed intact)", ""},
      {"analyses_failed_<reason>", "1",
       "the same per reason: the error's first words, lower case joined by `_`", "a failed analysis"},
      {"fines_mass_fraction", "1", "mass removed as fines over all the solid that entered (initial and fed)", ""},
      {"guard_max_overlap_fraction", "1", "largest overlap over the smaller grain's diameter the guards saw", ""},
      {"guard_max_energy_ratio", "1", "largest kinetic energy over the energy that can have entered (initial kinetic energy, platen work, weight falling the container's height)", ""},
      {"guard_small_grain_overlaps", "1", "contacts over the overlap limit whose smaller grain is tiny (counted instead of stopping the run)", ""},
      {"guard_small_grains_removed", "1", "tiny grains that left a closed container, taken out as fines", ""},
      {"engine_<figure>", "1",
       "the engine's own counts (Engine::summary_figures): bullet and ode compound_shapes, compound_pieces, "
       "compound_failures; ode concave_shapes_as_hull", "engines that report them"},
      {"engine_solver_iterations_max", "1", "most iterations the contact solver took in a loading step", "engines with an iterative "
                                                                                    "contact solver"},
      {"engine_solver_limited_fraction", "1", "share of the loading steps the solver stopped at its iteration limit before its tolerance",
       "engines with an iterative contact solver"},
      {"engine_solver_limited_change_max", "1", "largest relative impulse change left at the limit",
       "engines with an iterative contact solver"},
      {"rocks_fed", "1", "rocks fed into the scene", "scenes with a feed or moving walls"},
      {"mass_fed_kg", "kg", "mass fed", "scenes with a feed or moving walls"},
      {"product_grains", "1", "grains that left through the discharge", "open scenes"},
      {"product_mass_kg", "kg", "their mass", "open scenes"},
      {"ejected_grains", "1", "grains thrown out of the top of the scene (removed, not product)", "open scenes"},
      {"mass_ejected_kg", "kg", "their mass", "open scenes"},
      {"mass_budget_error_kg", "kg", "(final + removed + product + ejected) − (initial + fed): 0 up to rounding",
       "open scenes"}};
}

std::vector<SummaryKey> writer_keys() {
  return {
      {"k0_final", "1", "the last defined K0 of series.csv", "closed containers, once K0 is defined"},
      {"mean_circularity_final", "1", "shape.csv's last mean circularity", "2D, output.shape_metrics"},
      {"mean_aspect_ratio_final", "1", "shape.csv's last mean aspect ratio", "2D, output.shape_metrics"},
      {"mean_sphericity_final", "1", "shape.csv's last mean sphericity", "3D, output.shape_metrics"},
      {"mean_zingg_ei_final", "1", "shape.csv's last mean Zingg EI", "3D, output.shape_metrics"},
      {"mean_zingg_fi_final", "1", "shape.csv's last mean Zingg FI", "3D, output.shape_metrics"},
      {"jaw_<figure>", "m, °, 1", "the jaw crusher's geometry: jaw_plate_length_m, jaw_plate_height_m, jaw_css_m, "
                           "jaw_oss_m, jaw_feed_opening_m (m), jaw_cycles, jaw_swing_amplitude_deg (°)",
       "jaw crusher scenes"},
      {"product_psd_mass_kg", "kg", "mass of product_psd.csv: product and removed fines", "open scenes"},
      {"product_d50_m", "m", "d50 of the product by mass (fines at size 0)", "open scenes with a product"},
      {"product_sieve_min_m", "m", "smallest sieve size of the product", "open scenes with a product"},
      {"product_sieve_max_m", "m", "largest sieve size of the product", "open scenes with a product"},
      {"diameter_m", "m", "the grain's equivalent diameter", "single-grain runs"},
      {"max_platen_force_N", "N", "largest platen force", "single-grain runs; other runs with a load–displacement "
                                                          "curve"},
      {"displacement_at_max_force_m", "m", "platen travel at the largest force", "runs with a load–displacement "
                                                                                  "curve"},
      {"crushing_force_N", "N", "force at which the grain broke (peridynamics: force_at_split_N, else the "
                                "largest contact force)", "single-grain runs that broke"},
      {"crushing_stress_Pa", "Pa", "equivalent stress at failure", "single-grain runs that broke, stress models"},
      {"characteristic_strength_Pa", "Pa", "crushing force over d² (Zhu & Zhao 2019, Fig. 9)",
       "single-grain runs that broke"},
      {"fragment_count", "1", "children of the first breakage", "single-grain runs that broke"},
      {"fragment_diameters_m", "m", "their equivalent diameters (array)", "single-grain runs that broke"},
      {"ncl_loglog_slope", "1", "slope of log e against log σ over σ ≥ 0.3 σ_max (Zhu & Zhao 2019 §5)",
       "where the fit is defined"},
      {"ncl_compression_index", "1", "C_c = −de/dlog10 σ over the same range", "where the fit is defined"},
      {"fractal_dimension_final", "1", "fractal dimension of the final sizes", "runs with breakage, where defined"},
      {"relative_breakage_final", "1", "Hardin's B_r of the final PSD against the initial", "where defined"},
      {"void_ratio_at_stress_<Pa>_Pa", "1", "void ratio at each `output.psd_at_stress` level reached",
       "levels reached"},
      {"void_ratio_at_strain_<value>", "1", "void ratio at each `output.psd_at_strain` level reached",
       "levels reached"},
      {"psd_d50_final_m", "m", "d50 of the final PSD by mass (removed fines at size 0)", "where defined"},
      {"psd_d10_final_m", "m", "d10 of the final PSD", "where defined"},
      {"psd_d60_final_m", "m", "d60 of the final PSD", "where defined"},
      {"psd_uniformity_final", "1", "d60/d10 of the final PSD", "where defined"},
      {"fines_fraction_final", "1", "mass fraction of removed fines and grains finer than fines_size_m",
       "when any solid is left or removed"},
      {"fines_size_m", "m", "the fines size of fines_fraction_final: the larger of screening.min_diameter and "
                            "simulation.fines_diameter", ""},
      {"layer_<k>_passing_percent_at_0.025_dmax", "%", "layer k's mass finer than 0.025 d_max", "output.psd_layers"},
      {"layer_<k>_passing_percent_at_0.25_dmax", "%", "layer k's mass finer than 0.25 d_max", "output.psd_layers"},
      {"layer_<k>_largest_fragment_m", "m", "layer k's largest grain", "output.psd_layers"}};
}

}  // namespace

const std::vector<OutputCsv>& output_csv_files() {
  static const std::vector<OutputCsv> files = {
      series_csv(),      events_csv(), psd_csv(),         breakage_per_mpa_csv(), shape_csv(),
      stages_csv(),      ncl_csv(),    psd_summary_csv(), load_displacement_csv(), psd_layers_csv(),
      product_psd_csv(), product_csv(), comparison_csv(), sweep_csv()};
  return files;
}

const OutputCsv& output_csv(const std::string& file) {
  for (const auto& f : output_csv_files())
    if (f.file == file) return f;
  throw std::logic_error("output_csv: '" + file + "' is not declared (output/OutputReference.cpp)");
}

std::string csv_header(const std::string& file, const std::string& variant, const ColumnExpander& expand) {
  std::string h;
  auto add = [&h](const std::string& name) { h += (h.empty() ? "" : ",") + name; };
  for (const auto& c : output_csv(file).columns) {
    if (!c.only.empty() && c.only != variant) continue;
    if (c.name.find('<') == std::string::npos) add(c.name);
    else if (expand)
      for (const auto& n : expand(c.name)) add(n);
  }
  return h;
}

const std::vector<SummaryKey>& summary_keys() {
  static const std::vector<SummaryKey> keys = [] {
    std::vector<SummaryKey> k;
    for (auto part : {run_keys(), time_keys(), simulation_keys(), writer_keys()}) k.insert(k.end(), part.begin(), part.end());
    return k;
  }();
  return keys;
}

bool matches_declared_name(const std::string& pattern, const std::string& name) {
  const auto a = pattern.find('<');
  const auto b = pattern.find('>', a);
  if (a == std::string::npos || b == std::string::npos) return pattern == name;
  const std::string head = pattern.substr(0, a), tail = pattern.substr(b + 1);
  return name.size() > head.size() + tail.size() && name.compare(0, head.size(), head) == 0 &&
         name.compare(name.size() - tail.size(), tail.size(), tail) == 0;
}

bool summary_key_declared(const std::string& key) {
  return std::any_of(summary_keys().begin(), summary_keys().end(),
                     [&](const SummaryKey& k) { return matches_declared_name(k.name, key); });
}

}  // namespace crumble
