// Out-of-tree plugins (docs/architecture.md): a shared library
// exporting two C entry points,
//
//   extern "C" int crumble_plugin_abi();   // must return crumble::kPluginAbi
//   extern "C" void crumble_plugin_register(crumble::PluginRegistrar& r);
//
// loaded with `crumble --plugin path.so ...`. A library built against another ABI version
// is refused with a clear error before any of its code registers anything.
//
// A plugin's entries declare their options like the built-in ones (RegistryEntry::options,
// read through crumble::Options; `crumble list --options NAME` shows them). An entry with an
// empty table reads its section free-form through Config as before: its keys are still
// checked (a key it does not read is an error), but `crumble list --options` shows none and
// they are not accepted while another implementation of the seam is selected. A plugin may
// also register named methods (r.methods.add), which a scenario selects by "method".
#pragma once
#include <string>

#include "scenarios/Methods.h"
#include "scenarios/Registry.h"

namespace crumble {

// Bumped whenever a seam interface (core/Engine.h, BreakageModel.h, FragmentBuilder.h,
// Observer.h) or the registrar changes.
// 2: BreakageAnalysis, named strength values, model-owned screening.
// 3: RegistryEntry::options (core/Options.h), the implementation's declared option table.
// 4: BreakageModel::load_measure, BreakageAnalysis::points.
// 5: Engine::summary_figures, BreakageModel::set_analysis_threads (added without a bump).
// 6: Contact::torque (core/Contact.h), ScreeningSettings::moment_couples.
// 7: PluginRegistrar::methods (scenarios/Methods.h), named methods.
inline constexpr int kPluginAbi = 7;

struct PluginRegistrar {
  Table<EngineFactory>& engines;
  Table<ModelFactory>& breakage_models;
  Table<BuilderFactory>& fragment_builders;
  // A named method (scenario key "method"): the values it fills in, e.g.
  // r.methods.add({"my_method", "...", {{"engine.type", "lsdem", "source"}, ...}}).
  MethodTable& methods;
};

// Throws std::invalid_argument naming the file and the problem.
void load_plugin(const std::string& path);

}  // namespace crumble
