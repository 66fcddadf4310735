#include "scenarios/Walls.h"

#include <cmath>

#include "base/Format.h"
#include "core/ShapeSpec.h"
#include "scenarios/Sections.h"

namespace crumble {

namespace {

WallMotion motion_from(const Config& m, int dim) {
  const auto w = read_options<WallMotion>(m, motion_options());
  if (w.type == WallMotion::Type::Velocity) {
    if (dim == 2 && w.velocity.z != 0) m.fail("velocity", "a 2D wall moves in the x-y plane: the z component must be 0");
    if (dim == 2 && (w.angular_velocity.x != 0 || w.angular_velocity.y != 0))
      m.fail("angular_velocity", "a 2D wall turns about z only: give [0, 0, w_z]");
  }
  if (w.type != WallMotion::Type::Eccentric) return w;
  if (!(norm(w.axis) > 0)) m.fail("axis", "expected a non-zero rotation axis");
  if (dim == 2 && (w.axis.x != 0 || w.axis.y != 0)) m.fail("axis", "a 2D wall turns about z: give [0, 0, 1]");
  if (w.throw_ > 2 * w.lever)
    m.fail("throw", "the throw " + fmt_num(w.throw_) + " m exceeds twice the lever (" + fmt_num(2 * w.lever) +
                        " m): a point at the lever's distance from the pivot cannot travel that chord");
  return w;
}

}  // namespace

MovingWall wall_from_config(const Config& c, int dim, const std::string& default_name) {
  WallSettings ws;
  ws.name = default_name;
  read_options(c, {find_option(wall_options(), "name")}, ws);
  if (!c.has("shape")) c.fail("shape", "required: the wall's SHAPE (e.g. {\"type\": \"polygon\", \"vertices\": ...})");
  MovingWall w;
  w.shape = shape_from_config(c.child("shape"), dim);
  read_options(c, wall_options(), ws);
  w.name = ws.name;
  w.position = ws.position;
  if (dim == 2 && w.position.z != 0) c.fail("position", "a 2D wall lies in the x-y plane: z must be 0");
  w.orientation = quaternion_from(c, "orientation", ws.orientation);
  if (dim == 2 && (w.orientation.x != 0 || w.orientation.y != 0))
    c.fail("orientation", "a 2D wall turns about z only: [cos(a/2), 0, 0, sin(a/2)]");
  w.motion = motion_from(c.child("motion"), dim);
  c.check_unknown();
  return w;
}

namespace {

constexpr double kDeg = kPi / 180.0;

Shape::Ptr rectangle(double length, double thickness, double spacing) {
  ShapeResolution res;
  res.level_set_spacing = spacing;
  const double a = 0.5 * thickness, b = 0.5 * length;
  return Shape::polygon({{-a, -b, 0}, {a, -b, 0}, {a, b, 0}, {-a, b, 0}}, res);
}

}  // namespace

namespace {

// The jaw's geometry from Table 1's numbers. The swing jaw turns by ±var about its top (the
// eccentric shaft). Its face of length L spans OSS − CSS = 2·L·cos(nip)·sin(var) = throw at
// the discharge, so L follows from Table 1's throw and variation (50 mm, ±1.7°: L = 0.909 m).
// Mean pose: face from B (bottom) to T (pivot) at the nip angle from the vertical fixed face
// x = 0; T_x is set so that the gap at the bottom is css when the jaw is closed (θ = −var):
// B_x(θ) = T_x − L·sin(nip − θ).
struct JawGeometry {
  double nip, var;  // rad
  double L, H;      // face length; vertical extent of both plates, bottoms at y = 0
  double Tx;        // feed opening: the gap at y = H, the pivot
  Vec3 T, B, n_out;  // n_out: the swing face's normal, away from the chamber
};

JawGeometry jaw_geometry(const JawCrusherSettings& j) {
  JawGeometry g;
  g.nip = j.nip_angle * kDeg;
  g.var = j.nip_angle_variation * kDeg;
  g.L = j.throw_ / (2 * std::cos(g.nip) * std::sin(g.var));
  g.H = g.L * std::cos(g.nip);
  g.Tx = j.css + g.L * std::sin(g.nip + g.var);
  g.T = {g.Tx, g.H, 0};
  g.B = {g.Tx - g.L * std::sin(g.nip), 0, 0};
  g.n_out = {std::cos(g.nip), -std::sin(g.nip), 0};
  return g;
}

// The fixed jaw, the swing jaw on its eccentric and (hopper_height > 0) a hopper above the
// plates (fixed, vertical) that keeps fragments the squeeze throws up inside the crusher
// instead of letting them fall past its outside.
std::vector<MovingWall> jaw_walls(const JawCrusherSettings& j, const JawGeometry& g) {
  const double thick = j.plate_thickness;
  std::vector<MovingWall> walls;
  MovingWall fixed;
  fixed.name = "fixed_jaw";
  fixed.shape = rectangle(g.H, thick, j.plate_level_set_spacing);
  fixed.position = {-0.5 * thick, 0.5 * g.H, 0};
  walls.push_back(fixed);

  MovingWall swing;
  swing.name = "swing_jaw";
  swing.shape = rectangle(g.L, thick, j.plate_level_set_spacing);
  swing.position = (g.B + g.T) * 0.5 + g.n_out * (0.5 * thick);
  swing.orientation = Quat::from_axis_angle({0, 0, 1}, -g.nip);
  swing.motion.type = WallMotion::Type::Eccentric;
  swing.motion.pivot = g.T;
  swing.motion.axis = {0, 0, 1};
  // The point at the lever travels a chord of throw / cos(nip), whose horizontal part is the throw.
  swing.motion.lever = g.L;
  swing.motion.throw_ = j.throw_ / std::cos(g.nip);
  swing.motion.rpm = j.rpm;
  swing.motion.phase = j.phase;
  walls.push_back(swing);

  if (j.hopper_height > 0) {
    MovingWall left;
    left.name = "hopper_left";
    left.shape = rectangle(j.hopper_height, thick, j.plate_level_set_spacing);
    left.position = {-0.5 * thick, g.H + 0.5 * j.hopper_height, 0};
    walls.push_back(left);
    MovingWall right = left;
    right.name = "hopper_right";
    right.position = {g.Tx + 0.01 + 0.5 * thick, g.H + 0.5 * j.hopper_height, 0};
    walls.push_back(right);
  }
  return walls;
}

// Rocks: outlines in order (Harmon et al. 2020 §4.1: 25 outlines repeated cyclically), each
// scaled to an equivalent diameter drawn uniformly in rocks.diameter and turned by a random
// angle (the seed decides), rebuilt at the scene's level-set resolution (Table 1: 7 mm per
// pixel, 2 surface points per pixel), dropped from above the feed opening.
FeedSettings rock_feed(const Config& rc, const JawGeometry& g, int dim, Rng& rng) {
  const auto r = read_options<RockFeedSettings>(rc, rock_options());
  const auto& dr = r.diameter;
  if (dr.size() != 2 || !(dr[0] > 0) || !(dr[1] >= dr[0]))
    rc.fail("diameter", "expected [d_min, d_max] with 0 < d_min <= d_max (equivalent diameters, m)");
  auto shapes = rc.children("shapes");
  if (shapes.empty()) rc.fail("shapes", "expected a non-empty array of rock outlines (SHAPE, e.g. polygons)");
  const double top_gap = g.Tx;  // at y = H, the pivot: the fixed face is x = 0
  std::vector<Shape::Ptr> templates;
  for (auto& shc : shapes) templates.push_back(shape_from_config(shc, dim, /*unit_size=*/true));
  FeedSettings feed;
  feed.count = r.count;
  feed.material = static_cast<int>(r.material);
  double rmax = 0;
  for (long i = 0; i < r.count; ++i) {
    const Shape::Ptr& t = templates[static_cast<std::size_t>(i) % templates.size()];
    const double d = dr[0] + (dr[1] - dr[0]) * rng.uniform();
    const double f = d / t->equivalent_diameter();
    ShapeResolution res;
    res.level_set_spacing = r.level_set_spacing;
    Shape::Ptr s;
    if (t->kind() == ShapeKind::Polygon) {
      std::vector<Vec3> v = t->outline();
      double perim = 0;
      for (std::size_t k = 0; k < v.size(); ++k) perim += norm(v[(k + 1) % v.size()] - v[k]) * f;
      for (auto& p : v) p *= f;
      res.surface_nodes = static_cast<int>(std::ceil(perim * r.surface_points_per_cell / r.level_set_spacing));
      s = Shape::polygon(std::move(v), res);
    } else {
      s = t->scaled(f);
    }
    if (2 * s->bounding_radius() >= top_gap)
      rc.fail("diameter", "a rock of " + fmt_num(2 * s->bounding_radius()) + " m across does not fit the feed opening of " +
                              fmt_num(top_gap) + " m between the plates' tops");
    rmax = std::max(rmax, s->bounding_radius());
    feed.shapes.push_back(s);
    feed.orientations.push_back(Quat::from_axis_angle({0, 0, 1}, rng.uniform(0, 2 * kPi)));
  }
  feed.spawn = {0.5 * top_gap, g.H + r.spawn_height + rmax, 0};
  feed.velocity = {0, 0, 0};
  return feed;
}

}  // namespace

PackingSpec jaw_crusher_scene(const Config& sc, int dim, Rng& rng) {
  if (dim != 2) sc.fail("type", "the jaw_crusher scene is 2D (Harmon et al. 2020 §4): set \"dimension\": 2");
  const auto j = read_options<JawCrusherSettings>(sc, jaw_crusher_options());
  const JawGeometry g = jaw_geometry(j);
  PackingSpec spec;
  spec.type = "jaw_crusher";
  spec.settle = false;
  spec.walls = jaw_walls(j, g);
  spec.feed = rock_feed(sc.child("rocks"), g, dim, rng);
  // Open domain: the product leaves at discharge_depth below the plates' bottoms.
  double rmax = 0;
  for (const auto& s : spec.feed.shapes) rmax = std::max(rmax, s->bounding_radius());
  const double thick = j.plate_thickness;
  spec.container.open = true;
  spec.container.domain.lo = {-thick - 1.0, -j.discharge_depth, -1};
  spec.container.domain.hi = {g.Tx + thick + 1.0, std::max(spec.feed.spawn.y, g.H + j.hopper_height) + rmax + 3.0, 1};
  spec.container.height = spec.container.domain.hi.y - spec.container.domain.lo.y;
  // Below the plates' bottoms a grain has passed the gap, wherever it leaves the domain; above
  // the hopper (or the drop zone) it was thrown out of the crusher.
  spec.container.discharge_level = 0;
  spec.container.eject_above = std::max(spec.feed.spawn.y + rmax, g.H + j.hopper_height);
  spec.duration = j.cycles * 60.0 / j.rpm;
  spec.scene_figures = {{"jaw_plate_length_m", g.L},  {"jaw_plate_height_m", g.H},     {"jaw_css_m", j.css},
                        {"jaw_oss_m", j.css + j.throw_}, {"jaw_feed_opening_m", g.Tx}, {"jaw_cycles", j.cycles},
                        {"jaw_swing_amplitude_deg", spec.walls[1].motion.amplitude() / kDeg}};
  return spec;
}

PackingSpec scene_from_config(const Config& sc, int dim, Rng& rng) {
  SceneSettings ss;
  read_options(sc, {find_option(scene_options(), "type")}, ss);
  if (ss.type == "jaw_crusher") return jaw_crusher_scene(sc, dim, rng);
  read_options(sc, scene_options(), ss);
  const double d = ss.diameter;
  Config shc = sc.child("shape");
  const Shape::Ptr tmpl = shape_from_config(shc, dim, /*unit_size=*/true);
  PackingSpec spec;
  spec.type = ss.type;
  PlacedGrain g;
  g.shape = tmpl->scaled(d / tmpl->equivalent_diameter());
  g.shape_spec = scaled_spec(shc.doc(), d / tmpl->equivalent_diameter());
  g.material = static_cast<int>(ss.material);
  g.source = sc.path();
  const Aabb b = g.shape->bounds();
  const double half_height = dim == 3 ? -b.lo.z : -b.lo.y;
  const double height = dim == 3 ? b.hi.z - b.lo.z : b.hi.y - b.lo.y;
  spec.container.lx = 3 * d;
  spec.container.ly = dim == 3 ? 3 * d : 0;
  spec.container.height = height;
  spec.container.platen_mass = ss.platen_mass;
  g.position = dim == 3 ? Vec3{1.5 * d, 1.5 * d, half_height} : Vec3{1.5 * d, half_height, 0};
  spec.grains.push_back(std::move(g));
  spec.settle = false;
  return spec;
}

}  // namespace crumble
