// The parts of the Simulation loop that open scenes need (a jaw crusher, Harmon et al. 2020
// §4): prescribed motion of moving walls, feeding rocks one after another, and removing the
// grains that leave through the discharge as product.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <stdexcept>

#include "core/Measures.h"
#include "core/Simulation.h"

namespace crumble {

int Simulation::add_moving_wall(MovingWall w) {
  if (!w.shape) throw std::invalid_argument("moving wall '" + w.name + "' has no shape");
  if (w.shape->dimension() != ctx_.dimension)
    throw std::invalid_argument("moving wall '" + w.name + "' is " + std::to_string(w.shape->dimension()) +
                                "D but the scenario is " + std::to_string(ctx_.dimension) + "D");
  const int i = engine_->add_moving_wall(w);
  if (i != static_cast<int>(walls_.size()))
    throw std::logic_error("engine '" + engine_->name() + "' numbered moving walls out of order");
  wall_radius_.push_back(w.shape->bounding_radius());
  walls_.push_back(std::move(w));
  engine_->set_moving_wall(i, wall_step_kinematics(walls_.back(), time_, 1e-9));
  return i;
}

void Simulation::set_feed(FeedSettings f) {
  if (f.count > 0 && f.shapes.empty()) throw std::invalid_argument("feed: rocks to feed but no shapes");
  for (const auto& s : f.shapes)
    if (!s || s->dimension() != ctx_.dimension) throw std::invalid_argument("feed: a rock shape of the wrong dimension");
  if (f.material < 0 || f.material >= static_cast<int>(ctx_.materials.size()))
    throw std::invalid_argument("feed: material index out of range");
  feed_ = std::move(f);
}

void Simulation::drive_walls(double t, double dt) {
  for (std::size_t i = 0; i < walls_.size(); ++i) {
    engine_->set_moving_wall(static_cast<int>(i), wall_step_kinematics(walls_[i], t, dt));
    // Guards: the work a wall can have done on the grains over the step is at most
    // |F|·(its fastest point's speed)·dt.
    if (walls_[i].motion.type != WallMotion::Type::Fixed)
      energy_in_ += norm(engine_->moving_wall_force(static_cast<int>(i))) * wall_max_speed(walls_[i], wall_radius_[i]) * dt;
  }
}

void Simulation::update_open_scene() {
  if (!container_.open && feed_.count == 0) return;
  sync_grains();
  const int up = ctx_.dimension == 3 ? 2 : 1;
  if (container_.open) {
    // Grains whose centroid fell below the domain, or below the discharge level and out of it
    // sideways, leave through the discharge; grains above the frame's top were thrown out.
    std::vector<Grain> kept;
    kept.reserve(grains_.size());
    for (auto& g : grains_) {
      const double h = g.position[up];
      if (h < container_.domain.lo[up] ||
          (h < container_.discharge_level && container_.beside_domain(g.position, ctx_.dimension))) {
        discharge(g, product_, product_mass_);
      } else if (h > container_.eject_above) {
        discharge(g, ejected_, ejected_mass_);
        std::cerr << "crumble: warning: grain " << g.id << " (d = " << g.shape->equivalent_diameter()
                  << " m) was thrown out of the top of the scene at t = " << time_
                  << " s: removed, its mass counted as ejected (summary.json mass_ejected_kg)\n";
      } else {
        kept.push_back(std::move(g));
      }
    }
    grains_ = std::move(kept);
  }
  if (fed_ >= feed_.count) return;
  // Harmon et al. 2020 §4.1: the next rock is dropped once the last one has cleared the space.
  const std::size_t k = static_cast<std::size_t>(fed_) % feed_.shapes.size();
  const Shape::Ptr& shape = feed_.shapes[k];
  const double r = shape->bounding_radius();
  for (const auto& g : grains_)
    if (norm(g.position - feed_.spawn) < r + g.shape->bounding_radius()) return;
  Grain g;
  g.shape = shape;
  g.position = feed_.spawn;
  if (!feed_.orientations.empty()) g.orientation = feed_.orientations[k % feed_.orientations.size()];
  g.velocity = feed_.velocity;
  g.material = feed_.material;
  mass_fed_ += g.mass(ctx_.materials[g.material].density);
  add_grain(std::move(g));
  ++fed_;
}

// Takes grain g out of the engine and records it in `to` (product or ejected), adding its mass.
void Simulation::discharge(const Grain& g, std::vector<ProductGrain>& to, double& mass) {
  ProductGrain p;
  p.id = g.id;
  p.origin = g.origin;
  p.generation = g.generation;
  p.time = time_;
  p.volume = g.shape->volume();
  p.mass = g.mass(ctx_.materials[g.material].density);
  p.diameter = g.shape->equivalent_diameter();
  p.sieve = sieve_size(*g.shape);
  mass += p.mass;
  to.push_back(p);
  engine_->remove_grain(g.id);
}

void Simulation::finish_open_scene(RunSummary& sum) const {
  if (!container_.open && feed_.count == 0 && walls_.empty()) return;
  sum.extra["rocks_fed"] = static_cast<double>(fed_);
  sum.extra["mass_fed_kg"] = mass_fed_;
  if (!container_.open) return;
  sum.extra["product_grains"] = static_cast<double>(product_.size());
  sum.extra["product_mass_kg"] = product_mass_;
  sum.extra["ejected_grains"] = static_cast<double>(ejected_.size());
  sum.extra["mass_ejected_kg"] = ejected_mass_;
  // Mass budget of an open scene: what was fed (and present at the start) is in the engine,
  // removed as fines, left as product or was thrown out.
  const double in = sum.mass_initial + mass_fed_;
  const double out = sum.mass_final + sum.mass_removed + product_mass_ + ejected_mass_;
  sum.extra["mass_budget_error_kg"] = out - in;
}

}  // namespace crumble
