#include "backends/rigid/RigidWorld.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "geometry/SymmetricEigen.h"

namespace crumble {

ShapeInertia shape_inertia(const Shape& shape, const std::string& engine) {
  const MassProperties& mp = shape.mass_properties();
  if (!(mp.volume > 0)) throw std::invalid_argument(engine + ": shape " + shape.describe() + " has no volume");
  ShapeInertia s;
  s.centroid = mp.centroid;
  s.inertia = mp.inertia;
  const Mat3& I = mp.inertia;
  const double tr = std::abs(I.trace());
  const double offdiag = std::max({std::abs(I(0, 1)), std::abs(I(0, 2)), std::abs(I(1, 2))});
  if (offdiag <= 1e-12 * tr) {
    s.moments = {I(0, 0), I(1, 1), I(2, 2)};
  } else {
    const auto pa = principal_axes(I);
    s.moments = pa.moments;
    s.principal = pa.rotation;
  }
  if (!(s.moments.x > 0 && s.moments.y > 0 && s.moments.z > 0))
    throw std::invalid_argument(engine + ": shape " + shape.describe() + " has a non-positive principal moment");
  return s;
}

Contact pair_contact(PairSide s0, PairSide s1, const Vec3& force0, double force_unit, const Vec3& couple0,
                     double couple_unit, const Vec3& normal0, const Vec3& point, double overlap) {
  Contact c;
  bool flip = false;
  if (s0.wall >= 0) {
    c.a = s1.id;
    c.wall = s0.wall;
    flip = true;
  } else if (s1.wall >= 0) {
    c.a = s0.id;
    c.wall = s1.wall;
  } else {
    flip = s1.id < s0.id;
    c.a = flip ? s1.id : s0.id;
    c.b = flip ? s0.id : s1.id;
  }
  const double sgn = flip ? -1.0 : 1.0;
  c.force = force0 * (sgn / force_unit);
  c.torque = couple0 * (sgn / couple_unit);
  c.normal = normal0 * sgn;
  c.point = point;
  c.overlap = overlap;
  return c;
}

RigidWorld::RigidWorld(std::string engine_name, const RigidOptions& o, const EngineContext& c)
    : engine(std::move(engine_name)), rigid(o), ctx(c) {}

void RigidWorld::set_container(const Container& c) {
  require_closed_box(c, engine);
  container = c;
  have_container = true;
  driver.reset(c.height);
  if (scale > 0) build_container();
}

void RigidWorld::set_platen(const PlatenCommand& cmd) {
  if (!std::isfinite(cmd.value)) throw std::invalid_argument(engine + ": platen command value is not finite");
  const bool mode_change = cmd.mode != driver.command().mode;
  driver.set_command(cmd);
  if (has_platen() && mode_change) configure_platen_body();
}

double RigidWorld::platen_position() const {
  if (!has_platen() || !platen_dynamic) return driver.position();
  return (platen_body_z() - platen_half_thickness) / scale;
}

void RigidWorld::check_grain(const Grain& g) const {
  const std::string grain = engine + ": grain " + std::to_string(g.id);
  if (!g.shape) throw std::invalid_argument(grain + " has no shape");
  if (g.shape->dimension() != 3) throw std::invalid_argument(grain + " has a 2D shape; the engine is 3D");
  if (g.material < 0 || g.material >= static_cast<int>(ctx.materials.size()))
    throw std::invalid_argument(grain + " has material index " + std::to_string(g.material) + " out of range");
  if (has_grain(g.id)) throw std::invalid_argument(engine + ": grain id " + std::to_string(g.id) + " added twice");
  const std::pair<const Vec3*, const char*> vectors[] = {
      {&g.position, "position"}, {&g.velocity, "velocity"}, {&g.angular_velocity, "angular velocity"}};
  for (const auto& [v, what] : vectors)
    if (!is_finite(*v)) throw std::invalid_argument(grain + " has a non-finite " + what);
  const Quat& q = g.orientation;
  const double qn = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!(qn > 0) || !std::isfinite(qn)) throw std::invalid_argument(grain + " has an invalid orientation");
}

void RigidWorld::add_grain(const Grain& g) {
  check_grain(g);
  attach_thread();
  fix_scale(g.shape->equivalent_diameter());
  total_mass += add_body(g, ctx.materials[g.material]);
  platen_mass_changed();
}

void RigidWorld::remove_grain(GrainId id) {
  if (!has_grain(id)) throw std::invalid_argument(engine + ": remove_grain: unknown grain id " + std::to_string(id));
  total_mass -= remove_body(id);
  if (grain_count() == 0) total_mass = 0;
  platen_mass_changed();
}

void RigidWorld::step(double dt) {
  if (!(dt > 0) || !std::isfinite(dt)) throw std::invalid_argument(engine + ": step needs a finite dt > 0");
  if (scale <= 0) fix_scale(0);
  if (!have_container) throw std::logic_error(engine + ": step() before set_container()");
  attach_thread();
  advance(dt);
  last_dt = dt;
}

void RigidWorld::set_friction_scale(double s) {
  friction_scale = s;
  friction_scale_changed();
}

void RigidWorld::read_state(std::span<Grain> grains) const {
  for (auto& g : grains) {
    BodyMotion m;
    Vec3 centroid;
    if (!body_motion(g.id, m, centroid)) continue;
    const Vec3 com = m.com / scale;
    const Vec3 arm = m.orientation.rotate(centroid);
    g.orientation = m.orientation;
    g.position = com - arm;
    g.angular_velocity = m.angular_velocity;
    g.velocity = m.velocity / scale - cross(m.angular_velocity, arm);
  }
}

std::map<std::string, double> RigidWorld::summary_figures() const {
  return {{"compound_shapes", static_cast<double>(compound_shapes)},
          {"compound_pieces", static_cast<double>(compound_pieces)},
          {"compound_failures", static_cast<double>(compound_failures)}};
}

void RigidWorld::fix_scale(double first_diameter) {
  if (scale > 0) return;
  if (rigid.length_scale > 0) {
    scale = rigid.length_scale;
  } else if (first_diameter > 0) {
    scale = std::exp2(std::round(std::log2(1.0 / first_diameter)));
  } else {
    scale = 1;
  }
  ref_length = first_diameter > 0 ? first_diameter * scale : 1.0;
  scale_fixed();
  if (have_container) build_container();
}

double RigidWorld::platen_mass() const {
  return std::max(crumble::platen_mass(container, total_mass), 1e-30) * rigid.mass_scale;
}

void RigidWorld::platen_mass_changed() {
  if (has_platen() && platen_dynamic && container.platen_mass <= 0) set_platen_mass();
}

RigidWorld::PlatenBox RigidWorld::platen_box() {
  const double lx = to_int(container.lx), ly = to_int(container.ly);
  platen_half_thickness = 0.25 * std::max(lx, ly);
  return {{0.55 * lx, 0.55 * ly, platen_half_thickness}, {0.5 * lx, 0.5 * ly, platen_centre_z()}};
}

std::vector<WallPlane> RigidWorld::fixed_walls() const {
  std::vector<WallPlane> walls = container_planes(container, 3);
  std::erase_if(walls, [](const WallPlane& w) { return w.id == kPlaten; });
  return walls;
}

BodyMotion RigidWorld::initial_motion(const Grain& g, const Vec3& centroid) const {
  BodyMotion m;
  m.orientation = g.orientation.normalized();
  const Vec3 arm = m.orientation.rotate(centroid);
  m.com = (g.position + arm) * scale;
  m.velocity = (g.velocity + cross(g.angular_velocity, arm)) * scale;
  m.angular_velocity = g.angular_velocity;
  return m;
}

bool RigidWorld::exact_sphere(const Shape& s) const { return s.kind() == ShapeKind::Sphere && rigid.exact_spheres; }

std::vector<TriMesh> RigidWorld::convex_pieces(const Shape& s) {
  std::vector<TriMesh> pieces = concave_shape_pieces(s, rigid.concave, engine, &compound_failures);
  if (!pieces.empty()) {
    ++compound_shapes;
    compound_pieces += static_cast<long>(pieces.size());
  }
  return pieces;
}

}  // namespace crumble
