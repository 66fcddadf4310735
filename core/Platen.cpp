#include "core/Platen.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace crumble {

Vec3 wall_inward_normal(int wall, int dimension) {
  Vec3 n;
  const int up = dimension == 3 ? 2 : 1;
  switch (wall) {
    case kFloor: n[up] = 1; break;
    case kPlaten: n[up] = -1; break;
    case kWallXMin: n.x = 1; break;
    case kWallXMax: n.x = -1; break;
    case kWallYMin:
    case kWallYMax:
      if (dimension != 3) throw std::invalid_argument("a 2D container has no y walls (wall " + std::to_string(wall) + ")");
      n.y = wall == kWallYMin ? 1 : -1;
      break;
    default: throw std::invalid_argument("no container wall with id " + std::to_string(wall));
  }
  return n;
}

std::vector<WallPlane> container_planes(const Container& c, int dimension, double platen_position,
                                        double platen_velocity) {
  std::vector<WallPlane> w;
  Vec3 e_up, e_x{1, 0, 0}, e_y{0, 1, 0};
  e_up[dimension == 3 ? 2 : 1] = 1;
  w.push_back({kFloor, {}, e_up, {}});
  if (c.height > 0) w.push_back({kPlaten, e_up * platen_position, -e_up, e_up * platen_velocity});
  if (c.lx > 0) {
    w.push_back({kWallXMin, {}, e_x, {}});
    w.push_back({kWallXMax, e_x * c.lx, -e_x, {}});
  }
  if (dimension == 3 && c.ly > 0) {
    w.push_back({kWallYMin, {}, e_y, {}});
    w.push_back({kWallYMax, e_y * c.ly, -e_y, {}});
  }
  return w;
}

double platen_mass(const Container& c, double grains_mass, double mass_scale) {
  return (c.platen_mass > 0 ? c.platen_mass : grains_mass) * mass_scale;
}

void PlatenDriver::reset(double position) {
  z_ = position;
  v_ = 0;
}

void PlatenDriver::set_command(const PlatenCommand& cmd) {
  if (!std::isfinite(cmd.value)) throw std::invalid_argument("platen command value is not finite");
  cmd_ = cmd;
}

void PlatenDriver::advance(double dt, double grain_force, double mass, double damping) {
  if (cmd_.mode == PlatenCommand::Mode::Velocity) {
    v_ = cmd_.value;
  } else if (mass > 0) {
    // Grains push it up with grain_force, the command pushes it down.
    const double acc = (grain_force - cmd_.value) / mass - damping * v_;
    v_ += acc * dt;
  }
  z_ += v_ * dt;
}

void require_closed_box(const Container& c, const std::string& engine) {
  if (c.open)
    throw std::invalid_argument(engine + ": open containers (no floor or walls, e.g. the jaw crusher scene) are not "
                                "supported; use engine \"lsdem\"");
  if (!(c.lx > 0) || !(c.ly > 0) || !(c.height > 0) || !std::isfinite(c.lx) || !std::isfinite(c.ly) ||
      !std::isfinite(c.height))
    throw std::invalid_argument(engine + ": container needs finite lx, ly, height > 0");
  if (!(c.platen_mass >= 0)) throw std::invalid_argument(engine + ": container platen_mass must be >= 0");
}

}  // namespace crumble
