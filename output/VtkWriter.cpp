#include "output/VtkWriter.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/MovingWall.h"
#include "core/Screening.h"
#include "output/Writers.h"

namespace crumble {

namespace fs = std::filesystem;

const OptionTable& vtk_output_options() {
  static const OptionTable t = vtk_output_options_of<VtkOutputSettings>();
  return t;
}

VtpPiece::Field& VtpPiece::cell_field(const std::string& name, int components, bool integer) {
  for (auto& f : cell_fields)
    if (f.name == name) return f;
  cell_fields.push_back({name, components, integer, {}});
  return cell_fields.back();
}

VtpPiece::Field& VtpPiece::point_field(const std::string& name, int components, bool integer) {
  for (auto& f : point_fields)
    if (f.name == name) return f;
  point_fields.push_back({name, components, integer, {}});
  return point_fields.back();
}

namespace {

void write_fields(std::ostream& os, const std::vector<VtpPiece::Field>& fields, std::size_t count, const char* where) {
  for (const auto& f : fields) {
    if (f.values.size() != count * static_cast<std::size_t>(f.components))
      throw std::logic_error(std::string("VTK ") + where + " field '" + f.name + "' has " +
                             std::to_string(f.values.size()) + " values for " + std::to_string(count) + " entries");
    os << "<DataArray type=\"" << (f.integer ? "Int64" : "Float64") << "\" Name=\"" << f.name
       << "\" NumberOfComponents=\"" << f.components << "\" format=\"ascii\">\n";
    for (std::size_t i = 0; i < f.values.size(); ++i) {
      const double v = f.values[i];
      if (!std::isfinite(v))
        throw std::runtime_error("refusing to write a non-finite value in VTK " + std::string(where) + " field '" +
                                 f.name + "'");
      if (f.integer) os << static_cast<long long>(v);
      else if (f.exact) os << std::setprecision(17) << v << std::setprecision(6);
      else os << v;
      os << ((i + 1) % f.components == 0 ? '\n' : ' ');
    }
    os << "</DataArray>\n";
  }
}

}  // namespace

std::string vtp_text(const VtpPiece& p) {
  std::ostringstream os;
  os << std::setprecision(10);
  const std::size_t nc = p.cells.size();
  const auto count = [&](VtpPiece::Cells k) { return p.kind == k ? nc : 0; };
  os << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
     << "<PolyData>\n<Piece NumberOfPoints=\"" << p.points.size() << "\" NumberOfVerts=\""
     << count(VtpPiece::Cells::Verts) << "\" NumberOfLines=\"" << count(VtpPiece::Cells::Lines)
     << "\" NumberOfStrips=\"0\" NumberOfPolys=\"" << count(VtpPiece::Cells::Polys) << "\">\n";
  os << "<PointData>\n";
  write_fields(os, p.point_fields, p.points.size(), "point");
  os << "</PointData>\n<CellData>\n";
  write_fields(os, p.cell_fields, nc, "cell");
  os << "</CellData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const auto& x : p.points) {
    if (!is_finite(x)) throw std::runtime_error("refusing to write a non-finite VTK point");
    os << x.x << ' ' << x.y << ' ' << x.z << '\n';
  }
  os << "</DataArray>\n</Points>\n";
  const char* tag = p.kind == VtpPiece::Cells::Verts ? "Verts" : p.kind == VtpPiece::Cells::Lines ? "Lines" : "Polys";
  os << '<' << tag << ">\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (const auto& c : p.cells) {
    for (std::size_t i = 0; i < c.size(); ++i) {
      if (c[i] < 0 || static_cast<std::size_t>(c[i]) >= p.points.size())
        throw std::logic_error("VTK cell names point " + std::to_string(c[i]) + " of " + std::to_string(p.points.size()));
      os << c[i] << (i + 1 < c.size() ? ' ' : '\n');
    }
  }
  os << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  long off = 0;
  for (const auto& c : p.cells) os << (off += static_cast<long>(c.size())) << '\n';
  os << "</DataArray>\n</" << tag << ">\n</Piece>\n</PolyData>\n</VTKFile>\n";
  return os.str();
}

namespace {

std::string step_name(const char* prefix, long step, const char* ext) {
  char name[96];
  std::snprintf(name, sizeof name, "%s_%08ld.%s", prefix, step, ext);
  return name;
}

std::string pvd_text(const std::vector<std::pair<double, std::string>>& entries, bool parts) {
  std::ostringstream os;
  os << std::setprecision(12) << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
  // Several files at one time (analyses of one check): one part each, so ParaView shows them together.
  std::map<double, int> part;
  for (const auto& [t, f] : entries) {
    os << "  <DataSet timestep=\"" << t << '"';
    if (parts) os << " part=\"" << part[t]++ << '"';
    os << " file=\"vtk/" << f << "\"/>\n";
  }
  os << "</Collection>\n</VTKFile>\n";
  return os.str();
}

// (timestep, file) of every entry of a .pvd this family wrote.
std::vector<std::pair<double, std::string>> read_pvd(const std::string& path) {
  std::vector<std::pair<double, std::string>> out;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    const auto t = line.find("timestep=\""), f = line.find("file=\"vtk/");
    if (t == std::string::npos || f == std::string::npos) continue;
    out.push_back({std::atof(line.c_str() + t + 10), line.substr(f + 10, line.find('"', f + 10) - (f + 10))});
  }
  return out;
}

// The step in a file name prefix_NNNNNNNN[...].ext; -1 when there is none.
long step_of(const std::string& name) {
  const auto u = name.find('_');
  if (u == std::string::npos) return -1;
  char* end = nullptr;
  const long v = std::strtol(name.c_str() + u + 1, &end, 10);
  return end == name.c_str() + u + 1 ? -1 : v;
}

void add_polygon_cell(VtpPiece& p, const std::vector<Vec3>& pts) {
  std::vector<long> c;
  for (const auto& x : pts) {
    c.push_back(static_cast<long>(p.points.size()));
    p.points.push_back(x);
  }
  p.cells.push_back(std::move(c));
}

void push3(std::vector<double>& v, const Vec3& x) { v.insert(v.end(), {x.x, x.y, x.z}); }

}  // namespace

VtkWriter::VtkWriter(const std::string& dir, Settings settings, long resume_step) : dir_(dir), set_(settings) {
  fs::create_directories(dir_ + "/vtk");
  if (resume_step < 0) return;
  // Keep the earlier snapshots up to the resume step (file names carry the step).
  for (const auto& [t, f] : read_pvd(dir_ + "/grains.pvd")) {
    const long step = step_of(f);
    if (step >= 0 && step <= resume_step) steps_.push_back({t, step});
  }
  last_ = resume_step;
}

void VtkWriter::write_collections() const {
  std::vector<std::pair<double, std::string>> grains, scene;
  for (const auto& [t, step] : steps_) {
    grains.push_back({t, step_name("grains", step, "vtp")});
    scene.push_back({t, step_name("scene", step, "vtm")});
  }
  write_file_atomic(dir_ + "/grains.pvd", pvd_text(grains, false));
  write_file_atomic(dir_ + "/scene.pvd", pvd_text(scene, false));
}

void VtkWriter::on_start(const Simulation& sim, const RunState& s) {
  if ((set_.every > 0 || set_.final_state) && s.step != last_) snapshot(sim, s);
}

void VtkWriter::on_sample(const Simulation& sim, const RunState& s) {
  if (set_.every > 0 && (last_ < 0 || s.step - last_ >= set_.every)) snapshot(sim, s);
}

void VtkWriter::on_finish(const Simulation& sim, const RunState& s, RunSummary&) {
  if (set_.final_state && s.step != last_) snapshot(sim, s);
  write_collections();
}

namespace {

// Pose, volume and mass of each grain, at full precision (crumble's Python reader sums the
// masses to the summary's mass_final_kg): `position` (centroid, m), `orientation` (unit
// quaternion body → world, w x y z), `volume` (m³; 2D: m² of the outline) and `mass` (kg;
// 2D: per m of thickness).
void declare_pose_fields(VtpPiece& p) {
  p.cell_field("position", 3).exact = true;
  p.cell_field("orientation", 4).exact = true;
  p.cell_field("volume").exact = true;
  p.cell_field("mass").exact = true;
}

void push_pose(VtpPiece& p, const Grain& g, double density) {
  push3(p.cell_field("position", 3).values, g.position);
  auto& q = p.cell_field("orientation", 4).values;
  q.insert(q.end(), {g.orientation.w, g.orientation.x, g.orientation.y, g.orientation.z});
  p.cell_field("volume").values.push_back(g.shape->volume());
  p.cell_field("mass").values.push_back(g.mass(density));
}

// The grain's surface in world coordinates: 3D its mesh's triangles, 2D its outline as one
// polygon. Returns the number of cells added.
std::size_t add_grain_surface(VtpPiece& p, const Grain& g) {
  if (g.shape->dimension() == 3) {
    const TriMesh& m = g.shape->mesh();
    const long base = static_cast<long>(p.points.size());
    for (const auto& v : m.vertices) p.points.push_back(g.to_world(v));
    for (const auto& t : m.triangles) p.cells.push_back({base + t[0], base + t[1], base + t[2]});
    return m.triangles.size();
  }
  std::vector<Vec3> poly;
  for (const auto& v : g.shape->outline()) poly.push_back(g.to_world(v));
  add_polygon_cell(p, poly);
  return 1;
}

VtpPiece grains_piece(const Simulation& sim, const std::vector<std::vector<Contact>>& on) {
  VtpPiece p;
  p.kind = VtpPiece::Cells::Polys;
  const BreakageModel& model = sim.model();
  const std::string measure = model.load_measure_name();
  // Every strength value any grain carries (one model: the same names on every grain).
  std::set<std::string> strength_names;
  for (const auto& g : sim.grains())
    for (const auto& [k, v] : g.strength.values) strength_names.insert(k);
  const bool two_d = sim.context().dimension == 2;
  const char* shape_names[3] = {two_d ? "circularity" : "sphericity", two_d ? "aspect_ratio" : "zingg_ei",
                                two_d ? "sieve_size" : "zingg_fi"};
  // Field order: what ParaView lists first is what a user looks for first.
  for (const char* n : {"grain", "parent", "origin", "generation", "crush_count"}) p.cell_field(n, 1, true);
  p.cell_field("diameter");
  p.cell_field("velocity", 3);
  p.cell_field("angular_velocity", 3);
  declare_pose_fields(p);
  if (!measure.empty()) p.cell_field(measure);
  for (const auto& n : strength_names) p.cell_field(n);
  for (const char* n : shape_names) p.cell_field(n);

  std::map<const Shape*, GrainShapeMetrics> metrics;
  const auto& grains = sim.grains();
  for (std::size_t gi = 0; gi < grains.size(); ++gi) {
    const Grain& g = grains[gi];
    auto mit = metrics.find(g.shape.get());
    if (mit == metrics.end()) mit = metrics.emplace(g.shape.get(), grain_shape_metrics(*g.shape)).first;
    const GrainShapeMetrics& gm = mit->second;
    // -1 marks "no descriptor" (a degenerate sliver); no output of crumble holds NaN.
    auto val = [](double v) { return std::isfinite(v) ? v : -1.0; };
    const double shp[3] = {val(two_d ? gm.circularity : gm.sphericity), val(two_d ? gm.aspect_ratio : gm.elongation),
                           val(two_d ? gm.sieve_size : gm.flatness)};
    double load = 0;
    if (!measure.empty()) {
      load = model.load_measure(g, sim.context().materials[g.material], on[gi]);
      if (!std::isfinite(load))
        throw std::runtime_error("breakage model '" + model.name() + "' gave a non-finite " + measure + " for grain " +
                                 std::to_string(g.id));
    }
    const std::size_t ncells = add_grain_surface(p, g);
    for (std::size_t c = 0; c < ncells; ++c) {
      p.cell_field("grain", 1, true).values.push_back(static_cast<double>(g.id));
      p.cell_field("parent", 1, true).values.push_back(static_cast<double>(g.parent));
      p.cell_field("origin", 1, true).values.push_back(static_cast<double>(g.origin));
      p.cell_field("generation", 1, true).values.push_back(g.generation);
      p.cell_field("crush_count", 1, true).values.push_back(g.crush_count);
      p.cell_field("diameter").values.push_back(g.shape->equivalent_diameter());
      push3(p.cell_field("velocity", 3).values, g.velocity);
      push3(p.cell_field("angular_velocity", 3).values, g.angular_velocity);
      push_pose(p, g, sim.context().materials[g.material].density);
      if (!measure.empty()) p.cell_field(measure).values.push_back(load);
      // -1: the grain has no such value (cannot happen with one model; kept explicit).
      for (const auto& n : strength_names) p.cell_field(n).values.push_back(g.strength.get_or(n, -1.0));
      for (int k = 0; k < 3; ++k) p.cell_field(shape_names[k]).values.push_back(shp[k]);
    }
  }
  return p;
}

// The container's floor and side walls (closed containers) and every moving wall at time t.
// 3D: polygons (the container's faces up to its initial height, the walls' surface meshes);
// 2D: polylines in the x–y plane (the walls' outlines closed).
VtpPiece walls_piece(const Simulation& sim, double t, double wall_height) {
  VtpPiece p;
  const bool two_d = sim.context().dimension == 2;
  p.kind = two_d ? VtpPiece::Cells::Lines : VtpPiece::Cells::Polys;
  auto& id = p.cell_field("wall", 1, true).values;
  const Container& c = sim.container();
  if (!c.open) {
    const double lx = c.lx, ly = c.ly, h = wall_height > 0 ? wall_height : c.height;
    if (two_d) {
      add_polygon_cell(p, {{0, 0, 0}, {lx, 0, 0}});
      id.push_back(kFloor);
      add_polygon_cell(p, {{0, 0, 0}, {0, h, 0}});
      id.push_back(kWallXMin);
      add_polygon_cell(p, {{lx, 0, 0}, {lx, h, 0}});
      id.push_back(kWallXMax);
    } else {
      add_polygon_cell(p, {{0, 0, 0}, {lx, 0, 0}, {lx, ly, 0}, {0, ly, 0}});
      id.push_back(kFloor);
      add_polygon_cell(p, {{0, 0, 0}, {0, ly, 0}, {0, ly, h}, {0, 0, h}});
      id.push_back(kWallXMin);
      add_polygon_cell(p, {{lx, 0, 0}, {lx, ly, 0}, {lx, ly, h}, {lx, 0, h}});
      id.push_back(kWallXMax);
      add_polygon_cell(p, {{0, 0, 0}, {lx, 0, 0}, {lx, 0, h}, {0, 0, h}});
      id.push_back(kWallYMin);
      add_polygon_cell(p, {{0, ly, 0}, {lx, ly, 0}, {lx, ly, h}, {0, ly, h}});
      id.push_back(kWallYMax);
    }
  }
  const auto& walls = sim.moving_walls();
  for (std::size_t i = 0; i < walls.size(); ++i) {
    const MovingWall& w = walls[i];
    const WallKinematics k = wall_kinematics(w, t);
    auto world = [&](const Vec3& v) { return k.position + k.orientation.rotate(v); };
    const long wall_id = kWallYMax + 1 + static_cast<long>(i);
    if (w.shape->dimension() == 2) {
      std::vector<Vec3> poly;
      for (const auto& v : w.shape->outline()) poly.push_back(world(v));
      if (!poly.empty()) poly.push_back(poly.front());
      if (two_d) {
        add_polygon_cell(p, poly);
        id.push_back(static_cast<double>(wall_id));
      }
    } else if (!two_d) {
      const TriMesh& m = w.shape->mesh();
      const long base = static_cast<long>(p.points.size());
      for (const auto& v : m.vertices) p.points.push_back(world(v));
      for (const auto& tri : m.triangles) {
        p.cells.push_back({base + tri[0], base + tri[1], base + tri[2]});
        id.push_back(static_cast<double>(wall_id));
      }
    }
  }
  return p;
}

VtpPiece platen_piece(const Simulation& sim, const RunState& s) {
  VtpPiece p;
  const bool two_d = sim.context().dimension == 2;
  const Container& c = sim.container();
  const double z = sim.engine().platen_position();
  if (two_d) {
    p.kind = VtpPiece::Cells::Lines;
    add_polygon_cell(p, {{0, z, 0}, {c.lx, z, 0}});
  } else {
    add_polygon_cell(p, {{0, 0, z}, {c.lx, 0, z}, {c.lx, c.ly, z}, {0, c.ly, z}});
  }
  p.cell_field("force_N").values.push_back(s.platen_force);
  p.cell_field("stress_Pa").values.push_back(s.platen_stress);
  return p;
}

// One line per contact: from grain a's centroid to grain b's (a wall contact: to its point).
VtpPiece contacts_piece(const Simulation& sim, const std::vector<Contact>& contacts) {
  VtpPiece p;
  p.kind = VtpPiece::Cells::Lines;
  std::map<GrainId, Vec3> centre;
  for (const auto& g : sim.grains()) centre[g.id] = g.position;
  for (const char* n : {"grain_a", "grain_b", "wall"}) p.cell_field(n, 1, true);
  p.cell_field("normal_force_N");
  p.cell_field("force_N", 3);
  p.cell_field("normal", 3);
  for (const auto& c : contacts) {
    const auto a = centre.find(c.a);
    if (a == centre.end()) continue;
    Vec3 end = c.point;
    if (!c.is_wall()) {
      const auto b = centre.find(c.b);
      if (b == centre.end()) continue;
      end = b->second;
    }
    add_polygon_cell(p, {a->second, end});
    p.cell_field("grain_a", 1, true).values.push_back(static_cast<double>(c.a));
    p.cell_field("grain_b", 1, true).values.push_back(static_cast<double>(c.b));
    p.cell_field("wall", 1, true).values.push_back(c.wall);
    p.cell_field("normal_force_N").values.push_back(std::abs(dot(c.force, c.normal)));
    push3(p.cell_field("force_N", 3).values, c.force);
    push3(p.cell_field("normal", 3).values, c.normal);
  }
  return p;
}

}  // namespace

void VtkWriter::snapshot(const Simulation& sim_c, const RunState& s) {
  auto& sim = const_cast<Simulation&>(sim_c);
  sim.sync_grains();
  last_ = s.step;
  const bool need_contacts = set_.contacts || !sim.model().load_measure_name().empty();
  const std::vector<Contact> contacts = need_contacts ? sim.engine().contacts() : std::vector<Contact>{};
  const auto on = contacts_by_grain(sim.grains(), contacts);

  std::vector<std::pair<std::string, std::string>> blocks;  // (block name, file)
  auto put = [&](const char* block, const VtpPiece& piece) {
    const std::string name = step_name(block, s.step, "vtp");
    write_file_atomic(dir_ + "/vtk/" + name, vtp_text(piece));
    blocks.push_back({block, name});
  };
  put("grains", grains_piece(sim, on));
  put("walls", walls_piece(sim, s.time, set_.wall_height));
  if (!sim.container().open) put("platen", platen_piece(sim, s));
  if (set_.contacts) put("contacts", contacts_piece(sim, contacts));

  std::ostringstream vtm;
  vtm << "<?xml version=\"1.0\"?>\n<VTKFile type=\"vtkMultiBlockDataSet\" version=\"1.0\" "
         "byte_order=\"LittleEndian\">\n<vtkMultiBlockDataSet>\n";
  for (std::size_t i = 0; i < blocks.size(); ++i)
    vtm << "  <DataSet index=\"" << i << "\" name=\"" << blocks[i].first << "\" file=\"" << blocks[i].second
        << "\"/>\n";
  vtm << "</vtkMultiBlockDataSet>\n</VTKFile>\n";
  write_file_atomic(dir_ + "/vtk/" + step_name("scene", s.step, "vtm"), vtm.str());
  steps_.push_back({s.time, s.step});
  write_collections();
}

AnalysisVtkWriter::AnalysisVtkWriter(const std::string& dir, long resume_step) : dir_(dir) {
  fs::create_directories(dir_ + "/vtk");
  if (resume_step < 0) return;
  for (const auto& [t, f] : read_pvd(dir_ + "/analyses.pvd")) {
    const long step = step_of(f);
    if (step >= 0 && step <= resume_step) files_.push_back({t, f});
  }
}

void AnalysisVtkWriter::write_collection() const {
  std::vector<std::pair<double, std::string>> e;
  for (const auto& f : files_) e.push_back({f.time, f.file});
  write_file_atomic(dir_ + "/analyses.pvd", pvd_text(e, true));
}

void AnalysisVtkWriter::on_breakage(const Simulation& sim, const BreakageEvent& e) {
  const auto& cloud = e.analysis.points;
  if (!cloud) return;
  // The parent is still among the grains while its breakage is reported (pose of the check).
  const Grain* parent = nullptr;
  for (const auto& g : sim.grains())
    if (g.id == e.parent) parent = &g;
  if (!parent) throw std::logic_error("breakage of grain " + std::to_string(e.parent) + " reported without the grain");
  VtpPiece p;
  p.kind = VtpPiece::Cells::Verts;
  for (std::size_t i = 0; i < cloud->points.size(); ++i) {
    p.points.push_back(parent->to_world(cloud->points[i]));
    p.cells.push_back({static_cast<long>(i)});
  }
  for (const auto& [name, v] : cloud->scalars) p.point_field(name).values = v;
  for (const auto& [name, v] : cloud->vectors) {
    auto& f = p.point_field(name, 3).values;
    for (const auto& x : v) push3(f, parent->orientation.rotate(x));
  }
  auto& gid = p.point_field("grain", 1, true).values;
  gid.assign(cloud->points.size(), static_cast<double>(e.parent));
  char name[96];
  std::snprintf(name, sizeof name, "analysis_%08ld_g%lld.vtp", e.step, static_cast<long long>(e.parent));
  write_file_atomic(dir_ + "/vtk/" + name, vtp_text(p));
  files_.push_back({e.time, name});
  write_collection();
}

void AnalysisVtkWriter::on_finish(const Simulation&, const RunState&, RunSummary&) { write_collection(); }

bool is_vtk_file_name(const std::string& name) {
  std::string n = name;
  if (n.size() > 4 && n.compare(n.size() - 4, 4, ".tmp") == 0) n.resize(n.size() - 4);
  auto ends = [&](const char* sfx) {
    const std::string s = sfx;
    return n.size() > s.size() && n.compare(n.size() - s.size(), s.size(), s) == 0;
  };
  auto starts = [&](const char* pfx) { return n.rfind(pfx, 0) == 0; };
  if (ends(".vtp"))
    return starts("grains_") || starts("walls_") || starts("platen_") || starts("contacts_") || starts("analysis_");
  return ends(".vtm") && starts("scene_");
}

}  // namespace crumble
