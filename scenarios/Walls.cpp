#include "scenarios/Walls.h"

#include <cmath>

#include "base/Format.h"
#include "core/ShapeSpec.h"

namespace crumble {

namespace {

Quat orientation_from(const Config& c, const std::string& key) {
  auto q = c.numbers(key, {1, 0, 0, 0});
  if (q.size() != 4) c.fail(key, "expected a quaternion [w, x, y, z]");
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(n > 0)) c.fail(key, "quaternion must be non-zero");
  return Quat{q[0] / n, q[1] / n, q[2] / n, q[3] / n};
}

WallMotion motion_from(const Config& m, int dim) {
  WallMotion w;
  const std::string type = m.choice("type", "fixed", {"fixed", "eccentric", "velocity"});
  if (type == "fixed") return w;
  if (type == "velocity") {
    w.type = WallMotion::Type::Velocity;
    w.velocity = m.vec3("velocity", {});
    w.angular_velocity = m.vec3("angular_velocity", {});
    if (dim == 2 && w.velocity.z != 0) m.fail("velocity", "a 2D wall moves in the x-y plane: the z component must be 0");
    if (dim == 2 && (w.angular_velocity.x != 0 || w.angular_velocity.y != 0))
      m.fail("angular_velocity", "a 2D wall turns about z only: give [0, 0, w_z]");
    return w;
  }
  w.type = WallMotion::Type::Eccentric;
  w.pivot = m.vec3("pivot", {});
  w.axis = dim == 2 ? m.vec3("axis", {0, 0, 1}) : m.vec3("axis", {0, 0, 1});
  if (!(norm(w.axis) > 0)) m.fail("axis", "expected a non-zero rotation axis");
  if (dim == 2 && (w.axis.x != 0 || w.axis.y != 0)) m.fail("axis", "a 2D wall turns about z: give [0, 0, 1]");
  w.throw_ = m.positive("throw");
  w.lever = m.positive("lever");
  if (w.throw_ > 2 * w.lever)
    m.fail("throw", "the throw " + fmt_num(w.throw_) + " m exceeds twice the lever (" + fmt_num(2 * w.lever) +
                        " m): a point at the lever's distance from the pivot cannot travel that chord");
  w.rpm = m.positive("rpm");
  w.phase = m.number("phase", 0.0);
  return w;
}

}  // namespace

MovingWall wall_from_config(const Config& c, int dim, const std::string& default_name) {
  MovingWall w;
  w.name = c.string("name", default_name);
  if (!c.has("shape")) c.fail("shape", "required: the wall's SHAPE (e.g. {\"type\": \"polygon\", \"vertices\": ...})");
  w.shape = shape_from_config(c.child("shape"), dim);
  w.position = c.vec3("position", {});
  if (dim == 2 && w.position.z != 0) c.fail("position", "a 2D wall lies in the x-y plane: z must be 0");
  w.orientation = orientation_from(c, "orientation");
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

PackingSpec jaw_crusher_scene(const Config& sc, int dim, Rng& rng) {
  if (dim != 2) sc.fail("type", "the jaw_crusher scene is 2D (Harmon et al. 2020 §4): set \"dimension\": 2");
  PackingSpec spec;
  spec.type = "jaw_crusher";
  spec.settle = false;
  // Harmon et al. 2020 Table 1 (after Johansson et al. 2017).
  const double css = sc.positive("css", 0.05);
  const double thr = sc.positive("throw", 0.05);
  const double rpm = sc.positive("rpm", 300);
  const double nip = sc.number("nip_angle", 22.0, 1.0, 60.0) * kDeg;
  const double var = sc.number("nip_angle_variation", 1.7, 0.01, 20.0) * kDeg;
  const double cycles = sc.positive("cycles", 40);
  const double thick = sc.positive("plate_thickness", 0.1);
  const double plate_spacing = sc.positive("plate_level_set_spacing", 0.007);
  // The swing jaw turns by ±var about its top (the eccentric shaft). Its face of length L
  // spans OSS − CSS = 2·L·cos(nip)·sin(var) = throw at the discharge, so L follows from
  // Table 1's throw and variation (50 mm, ±1.7°: L = 0.909 m).
  const double L = thr / (2 * std::cos(nip) * std::sin(var));
  const double H = L * std::cos(nip);  // vertical extent of both plates, bottoms at y = 0
  // Mean pose: face from B (bottom) to T (pivot) at the nip angle from the vertical fixed
  // face x = 0; T_x is set so that the gap at the bottom is css when the jaw is closed
  // (θ = −var): B_x(θ) = T_x − L·sin(nip − θ).
  const double Tx = css + L * std::sin(nip + var);
  const Vec3 T{Tx, H, 0}, B{Tx - L * std::sin(nip), 0, 0};
  const Vec3 n_out{std::cos(nip), -std::sin(nip), 0};  // away from the chamber

  MovingWall fixed;
  fixed.name = "fixed_jaw";
  fixed.shape = rectangle(H, thick, plate_spacing);
  fixed.position = {-0.5 * thick, 0.5 * H, 0};
  spec.walls.push_back(fixed);

  MovingWall swing;
  swing.name = "swing_jaw";
  swing.shape = rectangle(L, thick, plate_spacing);
  swing.position = (B + T) * 0.5 + n_out * (0.5 * thick);
  swing.orientation = Quat::from_axis_angle({0, 0, 1}, -nip);
  swing.motion.type = WallMotion::Type::Eccentric;
  swing.motion.pivot = T;
  swing.motion.axis = {0, 0, 1};
  // The point at the lever travels a chord of throw / cos(nip), whose horizontal part is the throw.
  swing.motion.lever = L;
  swing.motion.throw_ = thr / std::cos(nip);
  swing.motion.rpm = rpm;
  swing.motion.phase = sc.number("phase", 0.0);
  spec.walls.push_back(swing);

  // A hopper above the plates (fixed, vertical) keeps fragments that the squeeze throws up
  // inside the crusher instead of letting them fall past its outside.
  const double hopper = sc.number("hopper_height", 1.5, 0.0);
  if (hopper > 0) {
    MovingWall left;
    left.name = "hopper_left";
    left.shape = rectangle(hopper, thick, plate_spacing);
    left.position = {-0.5 * thick, H + 0.5 * hopper, 0};
    spec.walls.push_back(left);
    MovingWall right = left;
    right.name = "hopper_right";
    right.position = {Tx + 0.01 + 0.5 * thick, H + 0.5 * hopper, 0};
    spec.walls.push_back(right);
  }

  // Rocks: outlines in order (Harmon et al. 2020 §4.1: 25 outlines repeated cyclically),
  // each scaled to an equivalent diameter drawn uniformly in rocks.diameter and turned by
  // a random angle (the seed decides), rebuilt at the scene's level-set resolution (Table 1:
  // 7 mm per pixel, 2 surface points per pixel).
  Config rc = sc.child("rocks");
  const long count = rc.integer("count", 40, 0);
  auto dr = rc.numbers("diameter", {0.15, 0.25});
  if (dr.size() != 2 || !(dr[0] > 0) || !(dr[1] >= dr[0]))
    rc.fail("diameter", "expected [d_min, d_max] with 0 < d_min <= d_max (equivalent diameters, m)");
  const double ls_spacing = rc.positive("level_set_spacing", 0.007);
  const double nodes_per_cell = rc.positive("surface_points_per_cell", 2.0);
  const int material = static_cast<int>(rc.integer("material", 0, 0));
  const double spawn_height = rc.number("spawn_height", 0.3, 0.0);
  auto shapes = rc.children("shapes");
  if (shapes.empty()) rc.fail("shapes", "expected a non-empty array of rock outlines (SHAPE, e.g. polygons)");
  const double top_gap = Tx;  // at y = H, the pivot: the fixed face is x = 0
  std::vector<Shape::Ptr> templates;
  for (auto& shc : shapes) templates.push_back(shape_from_config(shc, dim, /*unit_size=*/true));
  FeedSettings& feed = spec.feed;
  feed.count = count;
  feed.material = material;
  double rmax = 0;
  for (long i = 0; i < count; ++i) {
    const Shape::Ptr& t = templates[static_cast<std::size_t>(i) % templates.size()];
    const double d = dr[0] + (dr[1] - dr[0]) * rng.uniform();
    const double f = d / t->equivalent_diameter();
    ShapeResolution res;
    res.level_set_spacing = ls_spacing;
    Shape::Ptr s;
    if (t->kind() == ShapeKind::Polygon) {
      std::vector<Vec3> v = t->outline();
      double perim = 0;
      for (std::size_t k = 0; k < v.size(); ++k) perim += norm(v[(k + 1) % v.size()] - v[k]) * f;
      for (auto& p : v) p *= f;
      res.surface_nodes = static_cast<int>(std::ceil(perim * nodes_per_cell / ls_spacing));
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
  feed.spawn = {0.5 * top_gap, H + spawn_height + rmax, 0};
  feed.velocity = {0, 0, 0};

  // Open domain: the product leaves at discharge_depth below the plates' bottoms.
  const double depth = sc.positive("discharge_depth", 0.2);
  spec.container.open = true;
  spec.container.domain.lo = {-thick - 1.0, -depth, -1};
  spec.container.domain.hi = {Tx + thick + 1.0, std::max(feed.spawn.y, H + hopper) + rmax + 3.0, 1};
  spec.container.height = spec.container.domain.hi.y - spec.container.domain.lo.y;
  spec.duration = cycles * 60.0 / rpm;
  spec.scene_figures = {{"jaw_plate_length_m", L},  {"jaw_plate_height_m", H},   {"jaw_css_m", css},
                        {"jaw_oss_m", css + thr},    {"jaw_feed_opening_m", Tx}, {"jaw_cycles", cycles},
                        {"jaw_swing_amplitude_deg", swing.motion.amplitude() / kDeg}};
  return spec;
}

PackingSpec scene_from_config(const Config& sc, int dim, Rng& rng) {
  PackingSpec spec;
  spec.type = sc.choice("type", "single_grain", {"single_grain", "jaw_crusher"});
  if (spec.type == "jaw_crusher") return jaw_crusher_scene(sc, dim, rng);
  const double d = sc.positive("diameter", 2e-3);
  Config shc = sc.child("shape");
  const Shape::Ptr tmpl = shape_from_config(shc, dim, /*unit_size=*/true);
  PlacedGrain g;
  g.shape = tmpl->scaled(d / tmpl->equivalent_diameter());
  g.shape_spec = scaled_spec(shc.doc(), d / tmpl->equivalent_diameter());
  g.material = static_cast<int>(sc.integer("material", 0, 0));
  g.source = sc.path();
  const Aabb b = g.shape->bounds();
  const double half_height = dim == 3 ? -b.lo.z : -b.lo.y;
  const double height = dim == 3 ? b.hi.z - b.lo.z : b.hi.y - b.lo.y;
  spec.container.lx = 3 * d;
  spec.container.ly = dim == 3 ? 3 * d : 0;
  spec.container.height = height;
  spec.container.platen_mass = sc.number("platen_mass", 0.0, 0.0);
  g.position = dim == 3 ? Vec3{1.5 * d, 1.5 * d, half_height} : Vec3{1.5 * d, half_height, 0};
  spec.grains.push_back(std::move(g));
  spec.settle = false;
  return spec;
}

}  // namespace crumble
