// crumble._crumble: the compiled half of the Python package (python/crumble/, docs/python.md).
// The only translation unit that includes pybind11. It hands the Python side JSON text and
// calls what the command line calls: load_scenario_file and build_request (`crumble
// validate`), run_pipeline (`crumble run`), the registry and option tables (`crumble list`).
// Bad input raises crumble.InputError (a ValueError, defined in python/crumble/_errors.py)
// with the message the command line prints, which names the JSON path.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <csignal>
#include <mutex>
#include <optional>

#include "core/Options.h"
#include "crumble_config.h"
#include "run/RunPipeline.h"
#include "scenarios/Fidelity.h"
#include "scenarios/Methods.h"
#include "scenarios/Registry.h"

namespace py = pybind11;
using Json = nlohmann::json;

namespace crumble {
namespace {

void raise_input_error(const char* what, const std::string& path) {
  py::object cls = py::module_::import("crumble._errors").attr("InputError");
  py::object err = cls(what, path);
  PyErr_SetObject(cls.ptr(), err.ptr());
}

void translate(std::exception_ptr p) {
  try {
    if (p) std::rethrow_exception(p);
  } catch (const ConfigError& e) {
    raise_input_error(e.what(), e.path());
  } catch (const InputError& e) {
    raise_input_error(e.what(), "");
  } catch (const std::invalid_argument& e) {
    raise_input_error(e.what(), "");
  }
}

// ---- registry: what `crumble list` prints, as data

Json default_json(const OptionSpec& s) {
  return std::visit(
      [](const auto& v) -> Json {
        if constexpr (std::is_same_v<std::decay_t<decltype(v)>, std::monostate>) return nullptr;
        else return v;
      },
      s.def);
}

Json option_json(const OptionSpec& s) {
  return {{"key", s.key},           {"type", option_kind_name(s)},  {"default", default_json(s)},
          {"default_text", std::holds_alternative<std::monostate>(s.def) ? s.default_doc : option_default_text(s)},
          {"range", option_range_text(s)}, {"choices", s.choices}, {"unit", s.unit},
          {"doc", s.doc},           {"required", s.required},       {"optional", s.optional}};
}

Json table_json(const OptionTable& t) {
  Json a = Json::array();
  for (const auto& s : t) a.push_back(option_json(s));
  return a;
}

template <class T>
Json seam_json(const T& table) {
  Json a = Json::array();
  for (const auto& e : table.entries())
    a.push_back({{"name", e.name}, {"description", e.description}, {"dimensions", e.dimensions},
                 {"variants", e.variants}, {"options", table_json(e.options)}});
  return a;
}

std::string registry_json() {
  Json j = {{"engines", seam_json(engines())},
            {"models", seam_json(breakage_models())},
            {"builders", seam_json(fragment_builders())}};
  Json sections = Json::array(), presets = Json::array(), missing = Json::array();
  for (const auto& n : registered_options())
    if (n.seam == "scenario section")
      sections.push_back({{"name", n.name}, {"description", n.description}, {"options", table_json(*n.options)}});
  for (const auto& k : fidelity_knobs())
    presets.push_back({{"seam", k.seam}, {"implementation", k.implementation}, {"path", k.path}, {"fast", k.fast},
                       {"balanced", k.balanced}, {"accurate", k.accurate}, {"measured", k.measured}});
  for (const auto& n : not_compiled()) missing.push_back({{"seam", n.seam}, {"name", n.name}, {"reason", n.reason}});
  j["sections"] = sections;
  j["presets"] = {{"names", fidelity_presets()}, {"knobs", presets}};
  Json methods_list = Json::array();
  for (const auto& m : methods().entries()) {
    Json settings = Json::array();
    for (const auto& st : m.settings) settings.push_back({{"path", st.path}, {"value", st.value}, {"source", st.source}});
    methods_list.push_back({{"name", m.name}, {"description", m.description}, {"settings", settings}});
  }
  j["methods"] = methods_list;
  j["not_compiled"] = missing;
  return j.dump();
}

// ---- scenarios

RunRequest request_of(const std::string& text, const std::string& source, const std::vector<std::string>& sets) {
  RunRequest req;
  req.scenario = parse_json_text(text, source);
  req.source_name = source;
  req.sets = sets;
  return req;
}

std::string validate(const std::string& text, const std::string& source, const std::vector<std::string>& sets,
                     std::optional<std::uint64_t> seed, std::optional<int> threads) {
  RunRequest req = request_of(text, source, sets);
  req.seed = seed;
  req.threads = threads;
  Scenario sc = build_request(req);
  return Json{{"notes", sc.notes},          {"grains", sc.packing.grains.size()}, {"engine", sc.engine_name},
              {"breakage", sc.breakage_name}, {"fragments", sc.fragments_name},     {"effective", sc.effective}}
      .dump();
}

// ---- runs

// SIGINT / SIGTERM while runs are going: the pipeline's handlers (finish the step, write
// every output). The first run in remembers Python's handlers, the last one out puts them
// back and forgets the signal, so the next run of this process runs.
class SignalScope {
 public:
  SignalScope() {
    std::lock_guard<std::mutex> lock(mutex());
    if (active()++ > 0) return;
    clear_stop_request();
    sigaction(SIGINT, nullptr, &saved()[0]);
    sigaction(SIGTERM, nullptr, &saved()[1]);
  }
  ~SignalScope() {
    std::lock_guard<std::mutex> lock(mutex());
    if (--active() > 0) return;
    sigaction(SIGINT, &saved()[0], nullptr);
    sigaction(SIGTERM, &saved()[1], nullptr);
    clear_stop_request();
  }
  SignalScope(const SignalScope&) = delete;
  SignalScope& operator=(const SignalScope&) = delete;

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static int& active() {
    static int n = 0;
    return n;
  }
  static struct sigaction* saved() {
    static struct sigaction s[2];
    return s;
  }
};

py::dict progress_dict(const RunState& s, double fraction, double elapsed, double eta) {
  using namespace pybind11::literals;
  return py::dict("step"_a = s.step, "time_s"_a = s.time, "fraction"_a = fraction, "elapsed_s"_a = elapsed,
                  "eta_s"_a = eta, "platen_stress_Pa"_a = s.platen_stress, "axial_strain"_a = s.axial_strain,
                  "grains"_a = s.grains, "breakage_events"_a = s.breakage_events);
}

// (status, summary.json text or "", reason): the pipeline's RunResult. The GIL is released
// while it runs; `progress` (a callable or None) gets a dict about once a second.
py::tuple run(RunRequest req, const py::object& progress) {
  std::optional<py::error_already_set> raised;
  if (!progress.is_none())
    req.on_progress = [&](const RunState& s, double f, double el, double eta) {
      py::gil_scoped_acquire gil;
      try {
        progress(progress_dict(s, f, el, eta));
      } catch (py::error_already_set& e) {
        raised = e;
        throw std::runtime_error(std::string("the progress callback raised: ") + e.what());
      }
    };
  RunResult r;
  {
    SignalScope signals;
    py::gil_scoped_release release;
    r = run_pipeline(req);
  }
  if (raised) throw *raised;
  return py::make_tuple(r.status, r.summary.is_null() ? std::string() : r.summary.dump(), r.reason);
}

}  // namespace
}  // namespace crumble

PYBIND11_MODULE(_crumble, m) {
  using namespace crumble;
  m.doc() = "crumble's compiled module: the command line's own code paths (docs/python.md)";
  m.attr("version") = CRUMBLE_VERSION;
  py::register_exception_translator(&translate);
  m.def("registry_json", &registry_json, "the registry and option tables as JSON text");
  m.def(
      "load_scenario", [](const std::string& path) { return load_scenario_file(path).dump(); },
      "a scenario file as JSON text (the command line's reader: duplicate keys, ranges)");
  m.def(
      "document",
      [](const std::string& text, const std::string& source, const std::vector<std::string>& sets) {
        return request_document(request_of(text, source, sets)).dump();
      },
      "the scenario document with --set assignments applied");
  m.def("validate", &validate, py::arg("text"), py::arg("source"), py::arg("sets"), py::arg("seed") = py::none(),
        py::arg("threads") = py::none());
  // The request `crumble run` builds from its options; Python fills in the same fields.
  py::class_<RunRequest>(m, "RunRequest")
      .def(py::init(&request_of), py::arg("text"), py::arg("source"), py::arg("sets"))
      .def_readwrite("out", &RunRequest::out)
      .def_readwrite("seed", &RunRequest::seed)
      .def_readwrite("threads", &RunRequest::threads)
      .def_readwrite("force", &RunRequest::force)
      .def_readwrite("resume", &RunRequest::resume)
      .def_readwrite("quiet", &RunRequest::quiet)
      .def_readwrite("plots", &RunRequest::plots)
      .def_readwrite("packing_only", &RunRequest::packing_only);
  m.def("run", &run, py::arg("request"), py::arg("progress"));
}
