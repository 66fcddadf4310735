#include "output/VtkWriter.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include <zlib.h>

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

// Numbers as `std::ostream << std::setprecision(10) << v` prints them: std::to_chars in the
// general format with a precision is printf's %.Ng, which the stream uses; without the
// stream's cost (a snapshot of the Zhu & Zhao quick packing holds ~10⁵ numbers).
void append_number(std::string& out, double v, int precision = 10) {
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, precision);
  out.append(buf, r.ptr);
}

void append_integer(std::string& out, long long v) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

// The text of one value of field f; a cell field repeats a grain's value over all its cells,
// so the text of the last value at each component is kept and reused while the value repeats.
class FieldText {
 public:
  explicit FieldText(const VtpPiece::Field& f) : f_(f), last_(f.components) {}
  void append(std::string& out, std::size_t i) {
    const double v = f_.values[i];
    Last& l = last_[i % f_.components];
    if (!l.text.empty() && std::memcmp(&l.value, &v, sizeof v) == 0) {
      out += l.text;
      return;
    }
    l.value = v;
    l.text.clear();
    if (f_.integer) append_integer(l.text, static_cast<long long>(v));
    else append_number(l.text, v, f_.exact ? 17 : 10);
    out += l.text;
  }

 private:
  struct Last {
    double value = 0;
    std::string text;
  };
  const VtpPiece::Field& f_;
  std::vector<Last> last_;
};

// The values of field f, one entry (its components) a line. A cell field repeats a grain's
// entry over all its cells: an entry bitwise equal to the one before copies that line's text.
std::string values_text(const VtpPiece::Field& f, const char* where) {
  std::string os;
  os.reserve(12 * f.values.size());
  FieldText text(f);
  const std::size_t c = static_cast<std::size_t>(f.components);
  std::size_t line = 0, line_size = 0;  // the last line's start in os and its length
  for (std::size_t e = 0; e * c < f.values.size(); ++e) {
    const double* v = f.values.data() + e * c;
    if (e > 0 && std::memcmp(v, v - c, c * sizeof(double)) == 0) {
      os.append(os, line, line_size);
      continue;
    }
    line = os.size();
    for (std::size_t k = 0; k < c; ++k) {
      if (!std::isfinite(v[k]))
        throw std::runtime_error("refusing to write a non-finite value in VTK " + std::string(where) + " field '" +
                                 f.name + "'");
      text.append(os, e * c + k);
      os += k + 1 == c ? '\n' : ' ';
    }
    line_size = os.size() - line;
  }
  return os;
}

// VTK XML binary data (format="binary", VTKFile header_type UInt64, compressor
// vtkZLibDataCompressor): the header [blocks 1, block size n, last block size n, compressed
// size c] base64-encoded on its own, then the zlib-compressed bytes base64-encoded. A grain's
// cell values repeat over its triangles, so they compress to a few per cent.
void append_base64(std::string& out, const unsigned char* p, std::size_t n) {
  static const char* abc = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  for (std::size_t i = 0; i < n; i += 3) {
    const unsigned v = (unsigned{p[i]} << 16) | (i + 1 < n ? unsigned{p[i + 1]} << 8 : 0u) | (i + 2 < n ? p[i + 2] : 0u);
    out += abc[(v >> 18) & 63];
    out += abc[(v >> 12) & 63];
    out += i + 1 < n ? abc[(v >> 6) & 63] : '=';
    out += i + 2 < n ? abc[v & 63] : '=';
  }
}

std::string binary_text(const void* data, std::size_t bytes) {
  uLongf c = compressBound(static_cast<uLong>(bytes));
  std::vector<unsigned char> z(c);
  if (compress2(z.data(), &c, static_cast<const Bytef*>(data), static_cast<uLong>(bytes), Z_BEST_SPEED) != Z_OK)
    throw std::runtime_error("zlib could not compress a VTK array of " + std::to_string(bytes) + " bytes");
  const std::uint64_t header[4] = {1, bytes, bytes, c};
  std::string out;
  out.reserve(4 * (sizeof header + c) / 3 + 8);
  append_base64(out, reinterpret_cast<const unsigned char*>(header), sizeof header);
  append_base64(out, z.data(), c);
  out += '\n';
  return out;
}

template <class T>
std::string binary_text(const std::vector<T>& v) {
  return binary_text(v.data(), v.size() * sizeof(T));
}

std::vector<std::int64_t> as_int64(const std::vector<double>& v) {
  return {v.begin(), v.end()};
}

void require_finite(const VtpPiece::Field& f, const char* where) {
  for (double v : f.values)
    if (!std::isfinite(v))
      throw std::runtime_error("refusing to write a non-finite value in VTK " + std::string(where) + " field '" +
                               f.name + "'");
}

// The opening tag of a DataArray; an empty array is written as ascii (nothing to compress).
std::string array_head(const char* type, const std::string& name, int components, bool binary, bool empty) {
  std::string h = std::string("<DataArray type=\"") + type + "\"";
  if (!name.empty()) h += " Name=\"" + name + "\"";
  if (components > 0) h += " NumberOfComponents=\"" + std::to_string(components) + "\"";
  return h + " format=\"" + (binary && !empty ? "binary" : "ascii") + "\">\n";
}

std::string field_text(const VtpPiece::Field& f, const char* where, bool binary) {
  if (!binary || f.values.empty()) return values_text(f, where);
  require_finite(f, where);
  return f.integer ? binary_text(as_int64(f.values)) : binary_text(f.values);
}

void write_fields(std::string& os, const std::vector<VtpPiece::Field>& fields, std::size_t count, const char* where,
                  VtpTextCache* cache, bool binary) {
  for (const auto& f : fields) {
    if (f.values.size() != count * static_cast<std::size_t>(f.components))
      throw std::logic_error(std::string("VTK ") + where + " field '" + f.name + "' has " +
                             std::to_string(f.values.size()) + " values for " + std::to_string(count) + " entries");
    const std::string head = array_head(f.integer ? "Int64" : "Float64", f.name, f.components, binary, f.values.empty());
    os += head;
    const std::string key = where + head;
    if (const std::string* t = cache ? cache->find(key, f.values) : nullptr) os += *t;
    else if (cache) os += cache->store(key, f.values, field_text(f, where, binary));
    else os += field_text(f, where, binary);
    os += "</DataArray>\n";
  }
}

// A DataArray of values v: binary, or (ascii, or empty) the text `ascii` appends.
template <class T, class Ascii>
std::string data_array(const char* type, const std::string& name, int components, bool binary,
                       const std::vector<T>& v, Ascii ascii) {
  std::string os = array_head(type, name, components, binary, v.empty());
  if (binary && !v.empty()) os += binary_text(v);
  else ascii(os);
  return os + "</DataArray>\n";
}

// The cells' connectivity (point indices; ascii: one cell a line), then their offsets.
std::string cells_text(const VtpPiece& p, bool binary) {
  std::vector<std::int64_t> conn, offsets;
  for (const auto& c : p.cells) {
    for (long i : c) {
      if (i < 0 || static_cast<std::size_t>(i) >= p.points.size())
        throw std::logic_error("VTK cell names point " + std::to_string(i) + " of " + std::to_string(p.points.size()));
      conn.push_back(i);
    }
    offsets.push_back(static_cast<std::int64_t>(conn.size()));
  }
  return data_array("Int64", "connectivity", 0, binary, conn,
                    [&](std::string& os) {
                      std::size_t k = 0;
                      for (auto end : offsets)
                        for (; k < static_cast<std::size_t>(end); ++k) {
                          append_integer(os, conn[k]);
                          os += k + 1 < static_cast<std::size_t>(end) ? ' ' : '\n';
                        }
                    }) +
         data_array("Int64", "offsets", 0, binary, offsets, [&](std::string& os) {
           for (auto o : offsets) {
             append_integer(os, o);
             os += '\n';
           }
         });
}

std::string points_text(const VtpPiece& p, bool binary) {
  std::vector<double> xyz;
  xyz.reserve(3 * p.points.size());
  for (const auto& x : p.points) {
    if (!is_finite(x)) throw std::runtime_error("refusing to write a non-finite VTK point");
    xyz.insert(xyz.end(), {x.x, x.y, x.z});
  }
  return data_array("Float64", "", 3, binary, xyz, [&](std::string& os) {
    for (std::size_t i = 0; i < xyz.size(); ++i) {
      append_number(os, xyz[i]);
      os += i % 3 == 2 ? '\n' : ' ';
    }
  });
}

// The <Points> and the cells of a piece.
void write_geometry(std::string& os, const VtpPiece& p, VtpTextCache* cache, bool binary) {
  os += "<Points>\n" + points_text(p, binary) + "</Points>\n";
  const std::string tag =
      p.kind == VtpPiece::Cells::Verts ? "Verts" : p.kind == VtpPiece::Cells::Lines ? "Lines" : "Polys";
  os += '<' + tag + ">\n";
  if (!cache) {
    os += cells_text(p, binary);
  } else {
    // The text depends on the cells and (through the index check) the number of points.
    std::vector<double> key{static_cast<double>(p.points.size())};
    for (const auto& c : p.cells) {
      key.push_back(static_cast<double>(c.size()));
      key.insert(key.end(), c.begin(), c.end());
    }
    const std::string* t = cache->find("cells", key);
    os += t ? *t : cache->store("cells", std::move(key), cells_text(p, binary));
  }
  os += "</" + tag + ">\n";
}

}  // namespace

const std::string* VtpTextCache::find(const std::string& key, const std::vector<double>& values) const {
  const auto it = entries_.find(key);
  if (it == entries_.end() || it->second.values.size() != values.size()) return nullptr;
  // Bitwise: -0 and 0 print differently.
  if (!values.empty() && std::memcmp(it->second.values.data(), values.data(), values.size() * sizeof(double)) != 0)
    return nullptr;
  return &it->second.text;
}

const std::string& VtpTextCache::store(const std::string& key, std::vector<double> values, std::string text) {
  Entry& e = entries_[key];
  e.values = std::move(values);
  e.text = std::move(text);
  return e.text;
}

std::string vtp_text(const VtpPiece& p, VtpTextCache* cache, bool binary) {
  std::string os;
  // ascii: about 12 characters a number, one reservation instead of the string's doublings
  // (binary arrays are a few per cent of that and grow the string themselves).
  std::size_t numbers = 4 * p.points.size() + 2 * p.cells.size();
  for (const auto& f : p.point_fields) numbers += f.values.size();
  for (const auto& f : p.cell_fields) numbers += f.values.size();
  for (const auto& c : p.cells) numbers += c.size();
  if (!binary) os.reserve(12 * numbers + 1024);
  const std::size_t nc = p.cells.size();
  const auto count = [&](VtpPiece::Cells k) { return std::to_string(p.kind == k ? nc : 0); };
  os += binary ? "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
                 "header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">\n"
               : "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n";
  os += "<PolyData>\n<Piece NumberOfPoints=\"" + std::to_string(p.points.size()) + "\" NumberOfVerts=\"" +
        count(VtpPiece::Cells::Verts) + "\" NumberOfLines=\"" + count(VtpPiece::Cells::Lines) +
        "\" NumberOfStrips=\"0\" NumberOfPolys=\"" + count(VtpPiece::Cells::Polys) + "\">\n";
  os += "<PointData>\n";
  write_fields(os, p.point_fields, p.points.size(), "point", cache, binary);
  os += "</PointData>\n<CellData>\n";
  write_fields(os, p.cell_fields, nc, "cell", cache, binary);
  os += "</CellData>\n";
  write_geometry(os, p, cache, binary);
  os += "</Piece>\n</PolyData>\n</VTKFile>\n";
  return os;
}

void PvdCollection::add(double time, const std::string& file) {
  std::ostringstream os;
  os << std::setprecision(12) << "  <DataSet timestep=\"" << time << '"';
  // Several files at one time (analyses of one check): one part each, so ParaView shows them together.
  if (parts_) os << " part=\"" << part_[time]++ << '"';
  os << " file=\"vtk/" << file << "\"/>\n";
  body_ += os.str();
}

std::string PvdCollection::text() const {
  return "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n" + body_ +
         "</Collection>\n</VTKFile>\n";
}

namespace {

std::string step_name(const char* prefix, long step, const char* ext) {
  char name[96];
  std::snprintf(name, sizeof name, "%s_%08ld.%s", prefix, step, ext);
  return name;
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

VtkWriter::VtkWriter(const std::string& dir, Settings settings, long resume_step,
                     std::shared_ptr<ShapeMetricsCache> metrics)
    : dir_(dir), set_(settings), metrics_(metrics ? std::move(metrics) : std::make_shared<ShapeMetricsCache>()) {
  fs::create_directories(dir_ + "/vtk");
  if (resume_step < 0) return;
  // Keep the earlier snapshots up to the resume step (file names carry the step).
  for (const auto& [t, f] : read_pvd(dir_ + "/grains.pvd")) {
    const long step = step_of(f);
    if (step >= 0 && step <= resume_step) add_to_collections(t, step);
  }
  last_ = resume_step;
}

void VtkWriter::add_to_collections(double time, long step) {
  grains_pvd_.add(time, step_name("grains", step, "vtp"));
  scene_pvd_.add(time, step_name("scene", step, "vtm"));
  collections_written_ = false;
}

void VtkWriter::write_collections() {
  if (collections_written_) return;  // the files on disk hold them already
  write_file_atomic(dir_ + "/grains.pvd", grains_pvd_.text());
  write_file_atomic(dir_ + "/scene.pvd", scene_pvd_.text());
  collections_written_ = true;
}

void VtkWriter::on_start(const Simulation& sim, const RunState& s) {
  // A resumed run counts the loading's parts from its checkpoint.
  if (s.step == last_) last_frame_ = frame_of(sim, s);
  else if (set_.every > 0 || set_.final_state) snapshot(sim, s);
}

void VtkWriter::on_sample(const Simulation& sim, const RunState& s) {
  if (due(sim, s)) snapshot(sim, s);
}

// The 1/max_frames part of the loading s is in (Loading::progress); -1 while the progress is
// 0 (not started, or a loading whose end is not known in advance: a stop force only).
long VtkWriter::frame_of(const Simulation& sim, const RunState& s) const {
  if (set_.max_frames <= 0) return -1;
  const double p = sim.loading().progress(s.time, s.platen_stress, s.axial_strain);
  return p > 0 ? static_cast<long>(std::floor(p * static_cast<double>(set_.max_frames))) : -1;
}

// every steps since the last snapshot, and (max_frames) a part of the loading not yet shown.
bool VtkWriter::due(const Simulation& sim, const RunState& s) const {
  if (set_.every <= 0 || (last_ >= 0 && s.step - last_ < set_.every)) return false;
  const long f = frame_of(sim, s);
  return f < 0 || f > last_frame_;
}

void VtkWriter::on_finish(const Simulation& sim, const RunState& s, RunSummary&) {
  if (set_.final_state && s.step != last_) snapshot(sim, s);
  write_collections();
}

namespace {

// The per-cell fields of the grains piece, created in the order ParaView lists them (what a
// user looks for first comes first), then filled grain by grain without a lookup by name.
struct GrainCellFields {
  std::vector<VtpPiece::Field*> ints, shape;  // grain, parent, origin, generation, crush_count
  VtpPiece::Field *diameter, *velocity, *angular_velocity, *load = nullptr;
  // Pose, volume and mass at full precision (crumble's Python reader sums the masses to the
  // summary's mass_final_kg): position (centroid, m), orientation (unit quaternion body →
  // world, w x y z), volume (m³; 2D: m² of the outline), mass (kg; 2D: per m of thickness).
  VtpPiece::Field *position, *orientation, *volume, *mass;
  std::vector<std::pair<std::string, VtpPiece::Field*>> strengths;

  GrainCellFields(VtpPiece& p, const Simulation& sim, const std::string& measure) {
    // Every strength value any grain carries (one model: the same names on every grain).
    std::set<std::string> strength_names;
    for (const auto& g : sim.grains())
      for (const auto& [k, v] : g.strength.values) strength_names.insert(k);
    const bool two_d = sim.context().dimension == 2;
    const char* shape_names[3] = {two_d ? "circularity" : "sphericity", two_d ? "aspect_ratio" : "zingg_ei",
                                  two_d ? "sieve_size" : "zingg_fi"};
    // Every field first, then the pointers: the vector of fields no longer grows.
    for (const char* n : {"grain", "parent", "origin", "generation", "crush_count"}) p.cell_field(n, 1, true);
    p.cell_field("diameter");
    p.cell_field("velocity", 3);
    p.cell_field("angular_velocity", 3);
    for (auto [n, c] : {std::pair{"position", 3}, {"orientation", 4}, {"volume", 1}, {"mass", 1}})
      p.cell_field(n, c).exact = true;
    if (!measure.empty()) p.cell_field(measure);
    for (const auto& n : strength_names) p.cell_field(n);
    for (const char* n : shape_names) p.cell_field(n);
    for (const char* n : {"grain", "parent", "origin", "generation", "crush_count"}) ints.push_back(&p.cell_field(n, 1, true));
    diameter = &p.cell_field("diameter");
    velocity = &p.cell_field("velocity", 3);
    angular_velocity = &p.cell_field("angular_velocity", 3);
    position = &p.cell_field("position", 3);
    orientation = &p.cell_field("orientation", 4);
    volume = &p.cell_field("volume");
    mass = &p.cell_field("mass");
    if (!measure.empty()) load = &p.cell_field(measure);
    for (const auto& n : strength_names) strengths.push_back({n, &p.cell_field(n)});
    for (const char* n : shape_names) shape.push_back(&p.cell_field(n));
  }

  // Grain g's values on each of its n cells.
  void add(const Grain& g, std::size_t n, double load_value, const double shp[3], double density) {
    const double id[5] = {static_cast<double>(g.id), static_cast<double>(g.parent), static_cast<double>(g.origin),
                          static_cast<double>(g.generation), static_cast<double>(g.crush_count)};
    for (int k = 0; k < 5; ++k) ints[k]->values.insert(ints[k]->values.end(), n, id[k]);
    diameter->values.insert(diameter->values.end(), n, g.shape->equivalent_diameter());
    for (std::size_t c = 0; c < n; ++c) {
      push3(velocity->values, g.velocity);
      push3(angular_velocity->values, g.angular_velocity);
      push3(position->values, g.position);
      orientation->values.insert(orientation->values.end(),
                                 {g.orientation.w, g.orientation.x, g.orientation.y, g.orientation.z});
    }
    volume->values.insert(volume->values.end(), n, g.shape->volume());
    mass->values.insert(mass->values.end(), n, g.mass(density));
    if (load) load->values.insert(load->values.end(), n, load_value);
    // -1: the grain has no such value (cannot happen with one model; kept explicit).
    for (auto& [name, f] : strengths) f->values.insert(f->values.end(), n, g.strength.get_or(name, -1.0));
    for (int k = 0; k < 3; ++k) shape[k]->values.insert(shape[k]->values.end(), n, shp[k]);
  }
};

// Grain g's surface (3D: its mesh's triangles; 2D: its outline as one polygon) in world
// coordinates; the number of cells added.
std::size_t add_grain_surface(VtpPiece& p, const Grain& g) {
  if (g.shape->dimension() != 3) {
    std::vector<Vec3> poly;
    for (const auto& v : g.shape->outline()) poly.push_back(g.to_world(v));
    add_polygon_cell(p, poly);
    return 1;
  }
  const TriMesh& m = g.shape->mesh();
  const long base = static_cast<long>(p.points.size());
  for (const auto& v : m.vertices) p.points.push_back(g.to_world(v));
  for (const auto& t : m.triangles) p.cells.push_back({base + t[0], base + t[1], base + t[2]});
  return m.triangles.size();
}

VtpPiece grains_piece(const Simulation& sim, const std::vector<std::vector<Contact>>& on, ShapeMetricsCache& metrics) {
  VtpPiece p;
  p.kind = VtpPiece::Cells::Polys;
  const BreakageModel& model = sim.model();
  const std::string measure = model.load_measure_name();
  GrainCellFields fields(p, sim, measure);
  const bool two_d = sim.context().dimension == 2;
  const auto& grains = sim.grains();
  for (std::size_t gi = 0; gi < grains.size(); ++gi) {
    const Grain& g = grains[gi];
    const GrainShapeMetrics& gm = metrics.get(g.shape);
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
    fields.add(g, add_grain_surface(p, g), load, shp, sim.context().materials[g.material].density);
  }
  metrics.sweep();
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
  last_frame_ = frame_of(sim, s);
  const bool need_contacts = set_.contacts || !sim.model().load_measure_name().empty();
  const std::vector<Contact> contacts = need_contacts ? sim.engine().contacts() : std::vector<Contact>{};
  const auto on = contacts_by_grain(sim.grains(), contacts);

  std::vector<std::pair<std::string, std::string>> blocks;  // (block name, file)
  auto put = [&](const char* block, const VtpPiece& piece) {
    const std::string name = step_name(block, s.step, "vtp");
    write_file_atomic(dir_ + "/vtk/" + name, vtp_text(piece, &text_[block], set_.binary));
    blocks.push_back({block, name});
  };
  put("grains", grains_piece(sim, on, *metrics_));
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
  add_to_collections(s.time, s.step);
  write_collections();
}

AnalysisVtkWriter::AnalysisVtkWriter(const std::string& dir, long resume_step, bool binary)
    : dir_(dir), binary_(binary) {
  fs::create_directories(dir_ + "/vtk");
  if (resume_step < 0) return;
  for (const auto& [t, f] : read_pvd(dir_ + "/analyses.pvd")) {
    const long step = step_of(f);
    if (step >= 0 && step <= resume_step) pvd_.add(t, f);
  }
}

void AnalysisVtkWriter::write_collection() {
  if (collection_written_) return;  // the file on disk holds it already
  write_file_atomic(dir_ + "/analyses.pvd", pvd_.text());
  collection_written_ = true;
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
  write_file_atomic(dir_ + "/vtk/" + name, vtp_text(p, nullptr, binary_));
  pvd_.add(e.time, name);
  collection_written_ = false;
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
