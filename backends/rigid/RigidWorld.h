// The library-independent half of a rigid-body adapter (bullet, ode). Both libraries see
// lengths multiplied by `scale` (a grain is about one unit: their collision tolerances are
// absolute lengths tuned for ~1-unit objects), seconds and kilograms; hence internal
// velocity = scale·v, force = scale·F, inertia = scale²·I. With the automatic scale a power
// of two these conversions are exact.
//
// A RigidWorld holds the container, the platen driver (core/Platen.h), the length scale,
// the grains' total mass and the friction scale, and runs the Engine calls whose rules do
// not depend on the library: argument checks, when the scale is fixed and the container
// (re)built, the platen's command and mass, the grains' poses read back. The adapter
// derives from it and supplies the library's bodies through the hooks below.
#pragma once
#include <iterator>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "backends/rigid/RigidOptions.h"
#include "core/Engine.h"
#include "core/Platen.h"

namespace crumble {

// A grain's body: the grain frame's orientation (normalised), its centre of mass and
// velocity in internal units, its angular velocity (rad/s, the same in both unit systems).
struct BodyMotion {
  Quat orientation;
  Vec3 com, velocity, angular_velocity;
};

// A shape's mass properties as a rigid body takes them (Bullet keeps a diagonal inertia, so
// its bodies live in the principal frame; ODE takes the full tensor); throws
// std::invalid_argument naming `engine` for a shape without volume or with a non-positive
// principal moment.
struct ShapeInertia {
  Vec3 centroid;   // shape frame, SI
  Mat3 inertia;    // about the centroid, per unit density, SI (m⁵)
  Vec3 moments;    // principal moments per unit density (m⁵)
  Quat principal;  // principal frame → shape frame (identity when the shape frame is principal)
};
ShapeInertia shape_inertia(const Shape& shape, const std::string& engine);

// What an adapter's per-shape entry starts from: the shape and its mass properties.
struct RigidShapeEntry : ShapeInertia {
  Shape::Ptr shape;
};

// The library data shared by every grain of one Shape (an Entry derived from
// RigidShapeEntry), built once per shape and dropped with its last grain.
template <class Entry>
class ShapeCache {
 public:
  // The cached entry of `shape`, or a new one holding the shape and its inertia that
  // `build(entry)` completes with the library's data.
  template <class Build>
  std::shared_ptr<Entry> get(const Shape::Ptr& shape, const std::string& engine, Build build) {
    auto it = map_.find(shape.get());
    if (it != map_.end())
      if (auto e = it->second.lock()) return e;
    // Drop stale entries now and then so the cache does not grow with fragments.
    for (auto i = map_.begin(); i != map_.end();) i = i->second.expired() ? map_.erase(i) : std::next(i);
    auto e = std::make_shared<Entry>();
    e->shape = shape;
    static_cast<ShapeInertia&>(*e) = shape_inertia(*shape, engine);
    build(*e);
    map_[shape.get()] = e;
    return e;
  }

 private:
  std::map<const Shape*, std::weak_ptr<Entry>> map_;
};

// One side of a touching pair: a grain (id >= 0, wall -1) or a container wall (id -1,
// wall its WallId).
struct PairSide {
  GrainId id = -1;
  int wall = -1;
};

// The Contact of a pair from its sums over the contact points, in internal units: `force0`
// and `couple0` act on side 0, `normal0` is a unit vector pointing into side 0. Force and
// couple are divided by `force_unit` and `couple_unit` (scale, or scale·Δt for impulses;
// scale², scale²·Δt); `point` and `overlap` are SI already. A wall is never `a`, and a
// grain pair is listed with `a` the smaller id, the vectors turned to act on it.
Contact pair_contact(PairSide s0, PairSide s1, const Vec3& force0, double force_unit, const Vec3& couple0,
                     double couple_unit, const Vec3& normal0, const Vec3& point, double overlap);

class RigidWorld {
 public:
  RigidWorld(std::string engine, const RigidOptions& o, const EngineContext& ctx);
  virtual ~RigidWorld() = default;

  void set_container(const Container& c);
  void set_platen(const PlatenCommand& cmd);
  double platen_position() const;  // m, the platen's bottom face
  void add_grain(const Grain& g);
  void remove_grain(GrainId id);
  void step(double dt);
  void set_friction_scale(double s);
  void read_state(std::span<Grain> grains) const;
  double length_scale() const { return scale; }
  const std::string& engine_name() const { return engine; }
  // "compound_shapes", "compound_pieces", "compound_failures": concave polyhedral shapes
  // collided as convex pieces, their pieces, and the shapes that could not be cut.
  virtual std::map<std::string, double> summary_figures() const;
  virtual std::size_t grain_count() const = 0;
  virtual std::vector<Contact> contacts() const = 0;
  // As Engine's: N, positive when the grains push the platen up, the floor down, a wall out.
  virtual double platen_force() const = 0;
  virtual double floor_force() const = 0;
  virtual double wall_force(int wall) const = 0;

 protected:
  // ---- what the library supplies
  // Before the first library call of a step or a new grain (a library with per-thread data).
  virtual void attach_thread() {}
  // The scale has just been fixed (before the container is built at it).
  virtual void scale_fixed() = 0;
  // The walls and the platen at the current scale, replacing any built before.
  virtual void build_container() = 0;
  virtual bool has_platen() const = 0;
  // Kinematic platen body under a velocity command, dynamic under a force command.
  virtual void configure_platen_body() = 0;
  virtual double platen_body_z() const = 0;  // internal, the platen body's centre
  virtual void set_platen_mass() = 0;        // platen_mass() on the dynamic platen body
  virtual bool has_grain(GrainId id) const = 0;
  // Adds the checked grain's body; returns its physical (unscaled) mass, kg.
  virtual double add_body(const Grain& g, const Material& m) = 0;
  // Removes a grain's body; returns its physical mass.
  virtual double remove_body(GrainId id) = 0;
  // The body of grain `id` and its shape's centroid (shape frame); false for an unknown id.
  virtual bool body_motion(GrainId id, BodyMotion& m, Vec3& centroid) const = 0;
  // One step of dt (the checks done, the scale fixed, the container built).
  virtual void advance(double dt) = 0;
  virtual void friction_scale_changed() {}

  // ---- shared rules
  double to_int(double si_length) const { return si_length * scale; }
  // The scale from engine.length_scale, or the power of two nearest to 1/d of the first
  // grain (so a grain is ≈ 1 unit and conversions are exact); 1 without a grain.
  void fix_scale(double first_diameter);
  // Mass of the force-driven platen (core/Platen.h's rule) times mass_scale, kg.
  double platen_mass() const;
  void platen_mass_changed();
  // Internal height of the platen body's centre where the driver has the platen.
  double platen_centre_z() const { return to_int(driver.position()) + platen_half_thickness; }
  // The platen: a thick box a little wider than the container (it only meets grains), its
  // bottom face at the driver's position. Sets platen_half_thickness; internal units.
  struct PlatenBox {
    Vec3 half_extents, centre;
  };
  PlatenBox platen_box();
  // Records the dynamic platen body's position and vertical velocity (internal) in the driver.
  void sync_platen(double body_vz) { driver.sync(platen_position(), body_vz / scale); }
  // The container's fixed walls (floor and sides), SI.
  std::vector<WallPlane> fixed_walls() const;
  BodyMotion initial_motion(const Grain& g, const Vec3& centroid) const;
  bool exact_sphere(const Shape& s) const;
  // concave_shape_pieces() with the adapter's options, counted in the summary figures.
  std::vector<TriMesh> convex_pieces(const Shape& s);

  const std::string engine;  // "bullet", "ode": the first word of every error message
  const RigidOptions rigid;
  const EngineContext ctx;
  double scale = 0;       // internal units per metre; 0 until fixed
  double ref_length = 1;  // internal length of the first grain (≈ 1)
  bool have_container = false;
  Container container;
  PlatenDriver driver;
  bool platen_dynamic = false;
  double platen_half_thickness = 0;  // internal
  double total_mass = 0;             // kg, physical
  double friction_scale = 1;         // set_friction_scale: multiplies every friction coefficient
  double last_dt = 0;
  long compound_shapes = 0, compound_pieces = 0, compound_failures = 0;

 private:
  void check_grain(const Grain& g) const;
};

}  // namespace crumble
