// `crumble list [--options NAME [--markdown]]`: the registered implementations of each seam,
// the methods and presets, and the option table an implementation declares. `crumble list --outputs
// [--markdown]`: every column and summary.json key a run writes (output/OutputReference.h, tools/OptionDocs.h).
#include <iostream>

#include "base/Errors.h"
#include "scenarios/Fidelity.h"
#include "scenarios/Methods.h"
#include "scenarios/Registry.h"
#include "tools/OptionDocs.h"
#include "tools/Subcommand.h"

namespace crumble {
namespace {

template <class T>
void list_table(const char* title, const T& t) {
  std::cout << title << ":\n";
  for (const auto& e : t.entries()) {
    std::cout << "  " << e.name << " — " << e.description << " [";
    for (std::size_t i = 0; i < e.dimensions.size(); ++i) std::cout << (i ? "," : "") << e.dimensions[i] << "D";
    std::cout << "]";
    if (!e.variants.empty()) {
      std::cout << " criteria:";
      for (const auto& v : e.variants) std::cout << " " << v;
    }
    std::cout << "\n";
    if (!e.options.empty()) {
      std::cout << "      options (" << e.options.size() << "):";
      for (std::size_t i = 0; i < e.options.size(); ++i) std::cout << (i ? ", " : " ") << e.options[i].key;
      std::cout << "\n";
    }
  }
}

class ListCommand : public Subcommand {
 public:
  CLI::App* add_to(CLI::App& app) override {
    auto* c = app.add_subcommand("list", "registered engines, breakage models and criteria, fragment builders");
    c->add_option("--options", options_,
                  "print the options one implementation declares (key, type, default, range, meaning), e.g. lsdem");
    c->add_flag("--outputs", outputs_,
                "print every CSV column and summary.json key a run, compare or sweep writes (unit, meaning)");
    c->add_flag("--markdown", markdown_,
                "with --options: as the Markdown table of docs/scenarios.md; with --outputs: as docs/output.md holds it");
    return c;
  }

  int run(const CommandContext&) override {
    if (outputs_ && !options_.empty()) throw InputError("list: give --outputs or --options NAME, not both");
    if (outputs_) {
      std::cout << (markdown_ ? output_reference_markdown() : output_reference_text());
      return 0;
    }
    if (markdown_ && options_.empty()) throw InputError("list --markdown needs --options NAME or --outputs");
    return options_.empty() ? list_all() : list_options();
  }

 private:
  static int list_all() {
    list_table("engines", engines());
    list_table("breakage models", breakage_models());
    list_table("fragment builders", fragment_builders());
    for (const auto& n : not_compiled())
      std::cout << "  (" << n.seam << " " << n.name << " not available: " << n.reason << ")\n";
    std::cout << methods_text();
    std::cout << fidelity_text();
    std::cout << "crumble list --options NAME: each option's type, default, range and meaning\n"
                 "crumble list --outputs: every column and summary.json key a run writes\n";
    return 0;
  }

  // The Markdown form is the one docs/scenarios.md holds between its markers.
  int list_options() const {
    for (const auto& n : find_options(options_, "--options " + options_)) {
      if (markdown_) std::cout << option_table_markdown(*n.options);
      else std::cout << n.name << " (" << n.seam << "): " << n.description << "\n" << option_table_text(*n.options);
    }
    return 0;
  }

  std::string options_;
  bool markdown_ = false;
  bool outputs_ = false;
};

}  // namespace

std::unique_ptr<Subcommand> make_list_command() { return std::make_unique<ListCommand>(); }

}  // namespace crumble
