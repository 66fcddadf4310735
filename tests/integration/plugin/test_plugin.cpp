// A minimal out-of-tree breakage model, registered through the plugin entry points.
#include "breakage/none/NoBreakage.h"
#include "scenarios/Plugins.h"

namespace {
class PluginNever : public crumble::NoBreakage {
 public:
  std::string name() const override { return "plugin_never"; }
};
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
                         [](const crumble::Config&, const crumble::EngineContext&) {
                           return std::unique_ptr<crumble::BreakageModel>(new PluginNever());
                         },
                         {},
                         {2, 3}});
}
