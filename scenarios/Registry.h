// The three registration tables (docs/architecture.md): the name in the
// scenario JSON is the name in the table. Built-in entries are listed explicitly in
// Registry.cpp; plugins add theirs at run time through `add`.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/BreakageModel.h"
#include "core/Config.h"
#include "core/Engine.h"
#include "core/Options.h"
#include "core/FragmentBuilder.h"

namespace crumble {

using EngineFactory = std::function<std::unique_ptr<Engine>(const Config&, const EngineContext&)>;
using ModelFactory = std::function<std::unique_ptr<BreakageModel>(const Config&, const EngineContext&)>;
using BuilderFactory = std::function<std::unique_ptr<FragmentBuilder>(const Config&, const EngineContext&)>;

template <class Factory>
struct RegistryEntry {
  std::string name;
  std::string description;
  Factory make;
  std::vector<std::string> variants;  // e.g. the criteria of the stress model
  std::vector<int> dimensions{3};     // which scenario dimensions it supports
  // Its options, declared once (core/Options.h): read by the implementation, by the
  // scenario factory (a sibling's keys are accepted with a note), by `crumble list
  // --options NAME` and by the generated tables of docs/scenarios.md. Empty: the entry
  // declares none (`none`), or a plugin reads its section free-form through Config; either
  // way no key of it is accepted while another implementation is selected.
  OptionTable options;
};

template <class Factory>
class Table {
 public:
  explicit Table(std::string seam) : seam_(std::move(seam)) {}
  void add(RegistryEntry<Factory> e);
  // Throws ConfigError at `where` naming the known entries when `name` is not registered.
  const RegistryEntry<Factory>& find(const std::string& name, const std::string& where) const;
  const std::vector<RegistryEntry<Factory>>& entries() const { return entries_; }
  std::string names() const;

 private:
  std::string seam_;
  std::vector<RegistryEntry<Factory>> entries_;
};

Table<EngineFactory>& engines();
Table<ModelFactory>& breakage_models();
Table<BuilderFactory>& fragment_builders();

// The registered implementations (of any seam) called `name`, each as "seam: table".
struct NamedOptions {
  std::string seam;  // "engine", "breakage model", "fragment builder", "scenario section"
  std::string name;
  std::string description;
  const OptionTable* options;
};
std::vector<NamedOptions> registered_options();
// Throws ConfigError at `where` listing every registered name when `name` is unknown.
std::vector<NamedOptions> find_options(const std::string& name, const std::string& where);

// Implementations known to the design but not compiled into this binary, with the reason
// (e.g. engine bullet: "built with CRUMBLE_WITH_BULLET=OFF"), so errors and `crumble list`
// can say so.
struct NotCompiled {
  std::string seam, name, reason;
};
std::vector<NotCompiled> not_compiled();
// The reason `name` of `seam` is not in this build; "" when it is (or is unknown).
std::string not_compiled_reason(const std::string& seam, const std::string& name);

}  // namespace crumble
