// crumble: the command line. Parses, loads plugins and dispatches to the subcommands of
// tools/ (tools/Subcommand.h); `crumble --help` and `crumble SUBCOMMAND --help` list them.
// Exit status: 0 success, 2 bad input (scenario, option, mesh, output folder), 1 failure while
// running, 130 / 143 a run ended early by SIGINT / SIGTERM (every output written).
#include <CLI/CLI.hpp>

#include <iostream>

#include "base/Errors.h"
#include "core/Config.h"
#include "crumble_config.h"
#include "scenarios/Plugins.h"
#include "tools/Subcommand.h"
#if CRUMBLE_MPI
#include "parallel/MpiAnalyses.h"
#endif

using namespace crumble;

namespace {

// The selected subcommand, with the exceptions of bad input mapped to exit status 2.
int dispatch(std::vector<std::unique_ptr<Subcommand>>& commands, std::vector<CLI::App*>& apps,
             const CommandContext& ctx) {
  try {
    for (const auto& p : ctx.plugins) load_plugin(p);
    for (std::size_t i = 0; i < commands.size(); ++i)
      if (*apps[i]) return commands[i]->run(ctx);
  } catch (const ConfigError& e) {
    std::cerr << "crumble: error: " << e.what() << "\n";
    return 2;
  } catch (const InputError& e) {
    std::cerr << "crumble: error: " << e.what() << "\n";
    return 2;
  } catch (const std::invalid_argument& e) {
    std::cerr << "crumble: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "crumble: failed: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string version = std::string("crumble ") + CRUMBLE_VERSION;
  CommandContext ctx;
#if CRUMBLE_MPI
  // Ranks >= 1 only serve breakage analyses to rank 0, which parses the command line.
  mpi::Session mpi(&argc, &argv);
  if (mpi.worker()) return mpi.serve();
  version += " (built with MPI" +
             (mpi.active() ? ": " + mpi.describe() + ", analyses of `run` on every rank" : std::string()) + ")";
  ctx.mpi_ranks = mpi.size();
#endif
  CLI::App app{"crumble — particle breakage in granular materials (Zhu & Zhao 2019, Harmon et al. 2020)"};
  app.set_version_flag("--version", version);
  app.footer(kExitStatus);
  app.require_subcommand(1);
  app.add_option("--plugin", ctx.plugins, "load a plugin shared library (repeatable; before the subcommand)");
  auto commands = make_subcommands();
  std::vector<CLI::App*> apps;
  for (auto& c : commands) apps.push_back(c->add_to(app));
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  }
#if CRUMBLE_MPI
  if (mpi.size() > 1)
    ctx.analysis_executor = [&](const nlohmann::json& doc, const Scenario& sc) {
      return mpi.executor(doc, sc, ctx.plugins);
    };
#endif
  return dispatch(commands, apps, ctx);
}
