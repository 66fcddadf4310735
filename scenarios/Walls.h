// Moving walls and the jaw-crusher scene from the scenario JSON (errors name the JSON path).
#pragma once
#include <vector>

#include "core/Config.h"
#include "core/MovingWall.h"
#include "core/Rng.h"
#include "scenarios/Packing.h"

namespace crumble {

// One entry of "walls": {"name", "shape": SHAPE, "position": [x,y,z], "orientation":
// [w,x,y,z], "motion": {"type": "fixed" | "eccentric" | "velocity", ...}}.
MovingWall wall_from_config(const Config& c, int dimension, const std::string& default_name);

// {"type": "jaw_crusher", ...}: the 2D jaw crusher of Harmon et al. 2020 §4 (Table 1): a
// fixed jaw, a swing jaw on an eccentric (nip angle, ±variation, throw, rpm, closed-side
// setting), rocks fed one after another from above, product leaving below the plates.
PackingSpec jaw_crusher_scene(const Config& sc, int dimension, Rng& rng);

// Scene builders: a whole set-up from a few numbers.
//   {"type": "single_grain", "diameter": d, "shape": SHAPE (template, default sphere)}:
//   one grain resting on the floor of a 3d × 3d box, the platen touching its top
//   (Zhu & Zhao 2019 §4.2: a grain crushed between two plates).
//   {"type": "jaw_crusher", ...}: jaw_crusher_scene above.
PackingSpec scene_from_config(const Config& scene, int dimension, Rng& rng);

}  // namespace crumble
