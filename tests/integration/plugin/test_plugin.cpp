// A minimal out-of-tree breakage model, registered through the plugin entry points, with
// one declared option (read through its table like the built-in implementations), and a
// named method that selects it.
#include "breakage/none/NoBreakage.h"
#include "scenarios/Plugins.h"

namespace {
class PluginNever : public crumble::NoBreakage {
 public:
  std::string name() const override { return "plugin_never"; }
};

const crumble::OptionTable& plugin_never_options() {
  static const crumble::OptionTable t{
      crumble::opt::integer("patience", 3, 0, 100, "checks a grain survives before it is asked again (unused)")};
  return t;
}
}  // namespace

extern "C" int crumble_plugin_abi() {
#ifdef CRUMBLE_TEST_BAD_ABI
  return 999;
#else
  return crumble::kPluginAbi;
#endif
}

extern "C" void crumble_plugin_register(crumble::PluginRegistrar& r) {
  r.breakage_models.add({"plugin_never", "a breakage model from a plugin",
                         [](const crumble::Config& cfg, const crumble::EngineContext&) {
                           crumble::Options(cfg, plugin_never_options()).integer("patience");
                           return std::unique_ptr<crumble::BreakageModel>(new PluginNever());
                         },
                         {},
                         {2, 3},
                         plugin_never_options()});
  r.methods.add({"plugin_method",
                 "a method from a plugin",
                 {{"breakage.type", "plugin_never", "the test plugin"}, {"breakage.patience", 7, "the test plugin"}}});
}
