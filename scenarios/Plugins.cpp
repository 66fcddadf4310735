#include "scenarios/Plugins.h"

#include <dlfcn.h>

#include <stdexcept>

namespace crumble {

void load_plugin(const std::string& path) {
  void* h = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!h) throw std::invalid_argument("--plugin " + path + ": cannot load: " + dlerror());
  using AbiFn = int (*)();
  using RegFn = void (*)(PluginRegistrar&);
  auto abi = reinterpret_cast<AbiFn>(dlsym(h, "crumble_plugin_abi"));
  auto reg = reinterpret_cast<RegFn>(dlsym(h, "crumble_plugin_register"));
  if (!abi || !reg) {
    dlclose(h);
    throw std::invalid_argument("--plugin " + path +
                                ": not a crumble plugin (needs crumble_plugin_abi and crumble_plugin_register)");
  }
  const int v = abi();
  if (v != kPluginAbi) {
    dlclose(h);
    throw std::invalid_argument("--plugin " + path + ": built for plugin ABI " + std::to_string(v) +
                                ", this crumble has ABI " + std::to_string(kPluginAbi) + "; rebuild the plugin");
  }
  PluginRegistrar r{engines(), breakage_models(), fragment_builders(), methods()};
  reg(r);  // the library stays loaded for the life of the process
}

}  // namespace crumble
