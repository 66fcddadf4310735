// Observers that turn a finished run into the figures of summary.json and a few tables:
// the single-grain crushing force, the compression line (ncl.csv), the void ratio at the
// reported levels and the final size distribution.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "core/Observer.h"

namespace crumble {

// Single-grain crushing (Zhu & Zhao 2019 §4.2): the first breakage gives the crushing force,
// the characteristic strength F/d² and the fragments.
std::shared_ptr<Observer> make_crushing_recorder(std::string dir);

// ncl.csv (void ratio and grain count against log stress), and the NCL slope and fractal
// dimension for summary.json, read from the finished series.csv.
std::shared_ptr<Observer> make_compression_recorder(std::string dir);

// The void ratio at each reported stress or strain level, and d50 and the fines fraction
// (grains finer than `fines_size`, m, and removed fines) of the final size distribution by mass.
std::shared_ptr<Observer> make_report_recorder(std::string dir, std::vector<double> stresses,
                                               std::vector<double> strains, double fines_size);

// summary.json keys of the void ratio at a reported stress (Pa) or axial strain level.
std::string void_ratio_stress_key(double stress);
std::string void_ratio_strain_key(double strain);

}  // namespace crumble
