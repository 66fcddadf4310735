// The Engine calls a rigid-body adapter (bullet, ode) answers from its RigidWorld
// (backends/rigid/RigidWorld.h) alone. An adapter derives from RigidEngine, hands it the
// world it built, and adds what its Engine face has of its own: the name, the solver's
// report, the advice of its guards. No library header appears here.
#pragma once
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/Config.h"
#include "core/Engine.h"

namespace crumble {

class RigidWorld;

class RigidEngine : public Engine {
 public:
  ~RigidEngine() override;

  std::string name() const override;  // the world's engine name
  void set_container(const Container& c) override;
  void add_grain(const Grain& g) override;
  // Any scale in [0, 1]; false otherwise.
  bool set_friction_scale(double scale) override;
  void remove_grain(GrainId id) override;
  std::size_t grain_count() const override;
  void step(double dt) override;
  void read_state(std::span<Grain> grains) const override;
  std::vector<Contact> contacts() const override;
  void set_platen(const PlatenCommand& cmd) override;
  double platen_position() const override;
  double platen_force() const override;
  double floor_force() const override;
  double wall_force(int wall) const override;
  std::map<std::string, double> summary_figures() const override;

  double length_scale() const;  // internal units per metre (0 until fixed)

 protected:
  explicit RigidEngine(std::unique_ptr<RigidWorld> world);
  RigidWorld& world() const { return *world_; }

 private:
  std::unique_ptr<RigidWorld> world_;
};

// The adapter E (BulletEngine, OdeEngine) of an "engine" object of type `type`: its
// options read (E::read_options), refused for a 2D scenario.
template <class E>
std::unique_ptr<Engine> make_rigid_engine(const Config& cfg, const EngineContext& ctx, const std::string& type) {
  const auto opts = E::read_options(cfg);
  if (ctx.dimension != 3)
    cfg.fail("", "the " + type + " engine is 3D only (scenario dimension " + std::to_string(ctx.dimension) + ")");
  return std::make_unique<E>(opts, ctx);
}

}  // namespace crumble
