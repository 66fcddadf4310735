#include "backends/rigid/RigidEngine.h"

#include "backends/rigid/RigidWorld.h"

namespace crumble {

RigidEngine::RigidEngine(std::unique_ptr<RigidWorld> world) : world_(std::move(world)) {}
RigidEngine::~RigidEngine() = default;

std::string RigidEngine::name() const { return world_->engine_name(); }

void RigidEngine::set_container(const Container& c) { world_->set_container(c); }
void RigidEngine::add_grain(const Grain& g) { world_->add_grain(g); }
bool RigidEngine::set_friction_scale(double scale) {
  if (!(scale >= 0 && scale <= 1)) return false;
  world_->set_friction_scale(scale);
  return true;
}
void RigidEngine::remove_grain(GrainId id) { world_->remove_grain(id); }
std::size_t RigidEngine::grain_count() const { return world_->grain_count(); }
void RigidEngine::step(double dt) { world_->step(dt); }
void RigidEngine::read_state(std::span<Grain> grains) const { world_->read_state(grains); }
std::vector<Contact> RigidEngine::contacts() const { return world_->contacts(); }
void RigidEngine::set_platen(const PlatenCommand& cmd) { world_->set_platen(cmd); }
double RigidEngine::platen_position() const { return world_->platen_position(); }
double RigidEngine::platen_force() const { return world_->platen_force(); }
double RigidEngine::floor_force() const { return world_->floor_force(); }
double RigidEngine::wall_force(int wall) const { return world_->wall_force(wall); }
std::map<std::string, double> RigidEngine::summary_figures() const { return world_->summary_figures(); }
double RigidEngine::length_scale() const { return world_->length_scale(); }

}  // namespace crumble
