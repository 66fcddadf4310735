// What the engine tests share: a grain at a pose, its mass, steps, the state an engine reports,
// and an adapter built from its JSON options through its registered factory (unknown keys
// checked as a scenario would).
#pragma once
#include <memory>
#include <span>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "core/Config.h"
#include "core/Engine.h"
#include "geometry/Shape.h"

namespace crumble::testing_support {

constexpr double kG = 9.81;
constexpr double kDensity = 2650;  // kg/m³ (the default material's)
constexpr double kDt = 5e-5;       // s

inline Grain grain(GrainId id, Shape::Ptr s, Vec3 pos, Quat q = {}) {
  Grain g;
  g.id = id;
  g.shape = std::move(s);
  g.position = pos;
  g.orientation = q;
  return g;
}

// A level-set sphere of grid spacing h with `nodes` surface nodes.
inline Shape::Ptr level_set_sphere(double r, double h, int nodes) {
  ShapeResolution res;
  res.level_set_spacing = h;
  res.surface_nodes = nodes;
  return Shape::sphere(r, res);
}

inline double mass_of(const Shape::Ptr& s) { return kDensity * s->volume(); }

inline void run(Engine& e, int steps, double dt = kDt) {
  for (int i = 0; i < steps; ++i) e.step(dt);
}

inline Grain state_of(const Engine& e, const Grain& g0) {
  Grain g = g0;
  e.read_state(std::span<Grain>(&g, 1));
  return g;
}

// The adapter E that `make(cfg, ctx)` builds from {"type": type, opts…}.
template <class E, class Make>
std::unique_ptr<E> make_engine_as(const std::string& type, Make make, nlohmann::json opts, Vec3 gravity,
                                  const Material& mat) {
  opts["type"] = type;
  Config cfg(opts);
  EngineContext ctx;
  ctx.gravity = gravity;
  ctx.materials = {mat};
  auto e = make(cfg, ctx);
  cfg.check_unknown();
  return std::unique_ptr<E>(static_cast<E*>(e.release()));
}

}  // namespace crumble::testing_support
