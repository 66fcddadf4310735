// ParaView output (docs/output.md "ParaView"): VTK XML files written as Observers, each to a
// temporary name and renamed into place when complete.
//
// - VtkWriter: per snapshot vtk/grains_NNNNNNNN.vtp (grain surfaces with per-grain cell
//   fields), vtk/walls_NNNNNNNN.vtp (container walls and moving walls), vtk/platen_NNNNNNNN.vtp
//   (closed containers), vtk/contacts_NNNNNNNN.vtp (output.vtk_contacts) and
//   vtk/scene_NNNNNNNN.vtm, a multiblock naming those files; the series grains.pvd (grains
//   only) and scene.pvd (every block).
// - AnalysisVtkWriter (output.vtk_analyses): for every breakage whose analysis returned
//   per-point data (BreakageAnalysis::points, e.g. the peridynamic lattice with its damage),
//   vtk/analysis_NNNNNNNN_gID.vtp in world coordinates, listed in analyses.pvd.
//
// No NaN or infinity is ever written: a non-finite value is an error naming the field.
#pragma once
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/Observer.h"
#include "core/Options.h"
#include "core/Simulation.h"
#include "output/Writers.h"

namespace crumble {

// The output options this family reads ("output" object of a scenario).
struct VtkOutputSettings {
  long vtk_every = 0;         // steps between VTK snapshots (0 = none)
  long vtk_max_frames = 20;   // most snapshots over the loading (0 = no limit)
  bool vtk_final = true;      // write the final state as VTK
  bool vtk_contacts = false;  // contact-force lines in each VTK snapshot
  bool vtk_analyses = false;  // per-point data of breakage analyses (vtk/analysis_*.vtp)
  bool vtk_binary = true;     // zlib-compressed binary arrays (false: ascii text)
};
// Bound to the VtkOutputSettings base of S (the scenario's output settings).
template <class S>
OptionTable vtk_output_options_of() {
  using V = VtkOutputSettings;
  return {
      opt::integer("vtk_every", static_cast<long S::*>(&V::vtk_every), 0, std::numeric_limits<long>::max(),
                   "steps between ParaView snapshots (vtk/, grains.pvd, scene.pvd; docs/output.md); 0 = none"),
      opt::integer("vtk_max_frames", static_cast<long S::*>(&V::vtk_max_frames), 0,
                   std::numeric_limits<long>::max(),
                   "the most vtk_every snapshots over the loading: a snapshot also waits until the loading's "
                   "progress (the ramp's time, the stop strain or stop stress reached) enters its next "
                   "1/vtk_max_frames, so an engine with a small time step writes about as many as one with a "
                   "large step (docs/output.md); 0 = no limit"),
      opt::boolean("vtk_final", static_cast<bool S::*>(&V::vtk_final), "a ParaView snapshot of the final state"),
      opt::boolean("vtk_contacts", static_cast<bool S::*>(&V::vtk_contacts),
                   "each snapshot adds vtk/contacts_*.vtp: one line per contact (centroid to centroid, or to the "
                   "contact point for a wall) with its normal force magnitude and force vector"),
      opt::boolean("vtk_analyses", static_cast<bool S::*>(&V::vtk_analyses),
                   "every breakage whose analysis returns per-point data (peridynamics: the lattice with damage, "
                   "piece and displacement per point) is written as vtk/analysis_*.vtp, listed in analyses.pvd"),
      opt::mapped_choice("vtk_format", static_cast<bool S::*>(&V::vtk_binary), {{"binary", true}, {"ascii", false}},
                         "encoding of the VTK arrays: binary = zlib-compressed (VTK XML 1.0, read by ParaView, VTK >= 6 "
                         "and crumble's Python reader; a grain's values repeat over its cells and compress to a few "
                         "per cent), ascii = numbers as text (about 10 times larger and slower to write; "
                         "docs/output.md)"),
  };
}
const OptionTable& vtk_output_options();

// One VTK PolyData piece in the XML format (.vtp). Cells are of one kind per piece
// (vertices, lines or polygons); fields hold 1 or 3 components per point or cell.
struct VtpPiece {
  enum class Cells { Verts, Lines, Polys } kind = Cells::Polys;
  std::vector<Vec3> points;
  std::vector<std::vector<long>> cells;  // point indices per cell
  struct Field {
    std::string name;
    int components = 1;
    bool integer = false;
    std::vector<double> values;  // components × count
    bool exact = false;          // 17 significant digits: the double reads back bit for bit
  };
  std::vector<Field> point_fields, cell_fields;

  Field& cell_field(const std::string& name, int components = 1, bool integer = false);
  Field& point_field(const std::string& name, int components = 1, bool integer = false);
};
// The text of the arrays of one piece as the last snapshot wrote them (a grain keeps its id,
// shape and surface cells between two breakages): an array whose values are bitwise those
// of the last call is not formatted again.
class VtpTextCache {
 public:
  // The text stored under key, when it was stored for exactly these values; else null.
  const std::string* find(const std::string& key, const std::vector<double>& values) const;
  const std::string& store(const std::string& key, std::vector<double> values, std::string text);

 private:
  struct Entry {
    std::vector<double> values;
    std::string text;
  };
  std::map<std::string, Entry> entries_;
};

// The .vtp text; throws std::runtime_error naming the field when a value is not finite or a
// field has the wrong length. With a cache: the text of unchanged arrays comes from it.
// binary: the arrays zlib-compressed and base64-encoded (VTK XML 1.0); else as text.
std::string vtp_text(const VtpPiece& piece, VtpTextCache* cache = nullptr, bool binary = false);

// A ParaView collection (.pvd) kept as text, one line formatted per entry when it is added
// (a run rewrites its collections after every snapshot). parts: several files at one time
// get one part number each, so ParaView shows them together.
class PvdCollection {
 public:
  explicit PvdCollection(bool parts = false) : parts_(parts) {}
  void add(double time, const std::string& file);  // file: its name inside vtk/
  std::string text() const;

 private:
  bool parts_;
  std::string body_;
  std::map<double, int> part_;
};

class VtkWriter : public Observer {
 public:
  std::string name() const override { return "vtk"; }
  struct Settings {
    long every = 0;           // steps between snapshots (0 = none)
    bool final_state = true;  // a snapshot of the final state
    bool contacts = false;    // contact-force lines (output.vtk_contacts)
    double wall_height = 0;   // m, height of the drawn side walls (0: the container's as set);
                              // the scenario's, so a resumed run draws the same walls
    long max_frames = 0;      // most snapshots over the loading's progress (0 = no limit)
    bool binary = true;       // output.vtk_format: compressed binary arrays, else ascii
  };
  // resume_step >= 0: keep the snapshots of the earlier run up to that step. metrics: the
  // shape descriptors' cache, shared with the run's ShapeWriter (null: one of its own).
  VtkWriter(const std::string& dir, Settings settings, long resume_step = -1,
            std::shared_ptr<ShapeMetricsCache> metrics = nullptr);
  void on_start(const Simulation& sim, const RunState& s) override;
  void on_sample(const Simulation& sim, const RunState& s) override;
  void on_finish(const Simulation& sim, const RunState& s, RunSummary&) override;

 private:
  void snapshot(const Simulation& sim, const RunState& s);
  bool due(const Simulation& sim, const RunState& s) const;
  long frame_of(const Simulation& sim, const RunState& s) const;
  void add_to_collections(double time, long step);
  void write_collections();
  std::string dir_;
  Settings set_;
  long last_ = -1;
  long last_frame_ = -1;  // the loading's 1/max_frames part of the last snapshot
  PvdCollection grains_pvd_, scene_pvd_;  // every snapshot
  bool collections_written_ = false;      // the .pvd files hold every snapshot so far
  std::map<std::string, VtpTextCache> text_;  // by block (grains, walls, ...)
  std::shared_ptr<ShapeMetricsCache> metrics_;  // the grains' shape descriptors, once per shape
};

class AnalysisVtkWriter : public Observer {
 public:
  std::string name() const override { return "vtk_analyses"; }
  // resume_step >= 0: keep the analyses of the earlier run up to that step.
  AnalysisVtkWriter(const std::string& dir, long resume_step = -1, bool binary = true);
  void on_breakage(const Simulation& sim, const BreakageEvent& e) override;
  void on_finish(const Simulation&, const RunState&, RunSummary&) override;

 private:
  void write_collection();
  std::string dir_;
  bool binary_;
  PvdCollection pvd_{true};
  bool collection_written_ = false;  // analyses.pvd holds every analysis so far
};

// Names a run writes into vtk/ (and their temporary names), for `--force` cleaning.
bool is_vtk_file_name(const std::string& name);

}  // namespace crumble
