#include "tests/fuzz/FuzzTargets.h"

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "core/Config.h"
#include "scenarios/ScenarioFactory.h"
#include "core/ShapeSpec.h"
#include "tools/ShapeCommand.h"

namespace crumble::fuzz {

namespace {

template <class F>
Outcome classify(F&& f, std::string* what) {
  try {
    f();
    return Outcome::Accepted;
  } catch (const ConfigError& e) {
    if (what) *what = e.what();
    return Outcome::InputError;
  } catch (const std::invalid_argument& e) {
    if (what) *what = e.what();
    return Outcome::InputError;
  } catch (const std::exception& e) {
    if (what) *what = e.what();
    return Outcome::OtherError;
  }
}

}  // namespace

Outcome scenario(const std::string& text, std::string* what) {
  return classify(
      [&] {
        nlohmann::json doc = parse_json_text(text, "fuzz.json");
        BuildOptions opt;
        opt.source_name = "fuzz.json";
        Scenario sc = build_scenario(std::move(doc), opt);
      },
      what);
}

Outcome shape(const std::string& text, std::string* what) {
  return classify(
      [&] {
        if (text.empty() || text.front() != '{') throw ConfigError("--json", "expected a shape object");
        for (const char* repr : {"mesh", "level_set"}) shape_report(text, repr, 0, 0);
      },
      what);
}

Outcome obj(const std::string& text, std::string* what) {
  char name[] = "/tmp/crumble_fuzz_XXXXXX";
  const int fd = mkstemp(name);
  if (fd < 0) throw std::runtime_error("fuzz: cannot create a temporary file");
  {
    std::ofstream out(name, std::ios::binary);
    out << text;
  }
  close(fd);
  const Outcome o = classify(
      [&] {
        nlohmann::json spec = {{"type", "polyhedron"}, {"file", name}};
        shape_report(spec.dump(), "mesh", 0, 0);
      },
      what);
  std::remove(name);
  return o;
}

}  // namespace crumble::fuzz
