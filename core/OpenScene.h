// Open scenes (a jaw crusher): grains fed one after another into a region without a floor,
// moved by moving walls, and leaving it at the bottom as product (Harmon et al. 2020 §4.1).
#pragma once
#include <vector>

#include "core/Grain.h"
#include "geometry/Shape.h"

namespace crumble {

// Rocks dropped one after another from `spawn`, each once the previous one has cleared the
// space (no grain's bounding circle/sphere reaches the next rock's); rock i has shape
// shapes[i % n] and orientations[i % n] (Harmon et al. 2020 §4.1: 25 outlines repeated in
// order).
struct FeedSettings {
  std::vector<Shape::Ptr> shapes;
  std::vector<Quat> orientations;  // empty: identity
  long count = 0;                  // rocks in total; 0 = no feed
  Vec3 spawn;                      // m, centroid of a new rock
  Vec3 velocity;                   // m/s at release
  int material = 0;
};

// A grain that left the domain through its bottom (the crusher's discharge).
struct ProductGrain {
  GrainId id = -1, origin = -1;
  int generation = 0;
  double time = 0;       // s when it was removed
  double volume = 0;     // m³ (2D: m²)
  double mass = 0;       // kg (2D: kg/m)
  double diameter = 0;   // equivalent diameter (m)
  double sieve = 0;      // sieve size (m): Harmon et al. 2020 §4.2 (core/Measures.h sieve_size)
};

}  // namespace crumble
