#include "run/StandardObservers.h"

#include <algorithm>

#include "output/Checkpoint.h"
#include "output/LayerOutputs.h"
#include "output/Recorders.h"
#include "output/StagesWriter.h"
#include "output/VtkWriter.h"
#include "output/Writers.h"

namespace crumble {

using Json = nlohmann::json;

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
  // The shape descriptors, computed once per shape for shape.csv and the VTK snapshots.
  const auto metrics = std::make_shared<ShapeMetricsCache>();
  if (sc.output.shape_metrics)
    sim.add_observer(std::make_shared<ShapeWriter>(out, sim.context().dimension, resumed ? st.step : -1, metrics));
  if (sc.output.vtk_every > 0 || sc.output.vtk_final)
    sim.add_observer(std::make_shared<VtkWriter>(
        out,
        VtkWriter::Settings{sc.output.vtk_every, sc.output.vtk_final, sc.output.vtk_contacts,
                            sc.packing.container.height, sc.output.vtk_max_frames, sc.output.vtk_binary},
        resumed ? st.step : -1, metrics));
  if (sc.output.vtk_analyses) sim.add_observer(std::make_shared<AnalysisVtkWriter>(out, resumed ? st.step : -1, sc.output.vtk_binary));
  sim.add_observer(std::make_shared<StagesWriter>(
      out, sim.loading().settings().mode == "strain_rate" ? StagesWriter::Axis::Strain : StagesWriter::Axis::Stress,
      resumed ? st.step : -1L));
  sim.add_observer(make_compression_recorder(out));
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
    sim.add_observer(make_report_recorder(out, sc.output.psd_at_stress, sc.output.psd_at_strain, fines_size));
  }
  // Last of the writers: every row of a checkpointed step is on disk before the checkpoint.
  if (sc.output.checkpoint_every > 0 || sc.output.checkpoint_every_s > 0)
    sim.add_observer(std::make_shared<CheckpointWriter>(out, sc.name, sc.output.checkpoint_every,
                                                        sc.output.checkpoint_every_s, checkpoint_info));
  if (sim.grains().size() == 1 && sim.model().active()) sim.add_observer(make_crushing_recorder(out));
  else sim.add_observer(std::make_shared<LoadDisplacementWriter>(out));
  if (sc.output.psd_layers > 0) sim.add_observer(std::make_shared<LayerPsdWriter>(out, static_cast<int>(sc.output.psd_layers)));
  if (sim.container().open) sim.add_observer(std::make_shared<ProductWriter>(out, sc.packing.scene_figures));
}

}  // namespace crumble
