// The option tables of the registered implementations as people read them: `crumble list
// --options NAME` (text or Markdown) and the generated blocks of docs/scenarios.md, so the
// documentation cannot drift from the code (tests/integration/option_docs checks it); and the
// same for the output reference (output/OutputReference.h): `crumble list --outputs` and the
// generated block of docs/output.md (tests/integration/output_reference).
#pragma once
#include <string>
#include <vector>

#include "core/Options.h"

namespace crumble {

// One Markdown table: | key | type | default | range | meaning |.
std::string option_table_markdown(const OptionTable& table);
// Aligned text for a terminal: one line per option and its meaning indented below.
std::string option_table_text(const OptionTable& table);

// The reference of docs/output.md: one Markdown table per CSV file, then summary.json's keys.
std::string output_reference_markdown();
// The same as text for a terminal.
std::string output_reference_text();

// docs/scenarios.md holds one generated block per implementation:
//   <!-- options:NAME -->
//   (option_table_markdown of NAME's table)
//   <!-- /options -->
struct OptionDocBlock {
  std::string name;
  std::string content;  // the lines between the markers, each ending in '\n'
  int line = 0;         // 1-based line of the opening marker
};
// Throws std::invalid_argument naming the line of a marker without its end.
std::vector<OptionDocBlock> option_doc_blocks(const std::string& markdown);

}  // namespace crumble
