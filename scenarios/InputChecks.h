// Checks of a scenario that need more than one key: everything `crumble validate` can know
// before anything runs (material indices, explicit grains inside the container and apart,
// the time step against an explicit engine's stable step). Each throws ConfigError naming
// the JSON path.
#pragma once
#include <string>
#include <vector>

#include "core/Engine.h"
#include "scenarios/Packing.h"

namespace crumble {

// Every grain's material index refers to one of the scenario's `n_materials`.
void check_packing_materials(const PackingSpec& spec, std::size_t n_materials);

// Explicit grains (packing.type "grains") start inside the container and do not overlap
// by more than `tolerance` × the smaller equivalent diameter (bounding radius for spheres
// and disks, shape signed distance otherwise).
void check_explicit_grains(const PackingSpec& spec, int dimension, double tolerance = 0.01);

// The stable step an explicit engine will require for this packing: `probe` (a fresh engine
// of the scenario's type) is given the packing's lightest, smallest and largest grains.
// Infinity for engines without a bound (or an empty packing).
double packing_stable_dt(Engine& probe, const PackingSpec& spec, const std::vector<Material>& materials);

}  // namespace crumble
