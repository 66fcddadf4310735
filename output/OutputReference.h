// The one declaration of every table a run, `crumble compare` and `crumble sweep` write: each
// CSV file's columns and each summary.json key, with its unit and meaning. The writers take
// their headers (and summary.json its fixed keys) from these tables, and `crumble list
// --outputs --markdown` prints them (tools/OptionDocs.h) as the reference docs/output.md holds
// between its markers (scripts/update-option-docs.sh refreshes it; tests/integration/output_reference
// checks both), so a column cannot be written without being documented.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/Observer.h"

namespace crumble {

// One column of a CSV file. A name holding `<…>` declares a family: the writer expands it
// into as many columns as the run has (the breakage model's figures, the varied paths, …).
struct OutputColumn {
  std::string name;
  std::string unit;     // SI unit; "1" a number without unit, "" text
  std::string meaning;
  std::string only{};   // a variant of the file the column belongs to ("" every variant)
};

struct OutputCsv {
  std::string file;  // name in the output folder
  std::string when;  // who writes it and when
  std::vector<OutputColumn> columns;
};

// Every CSV file, in the order of the reference.
const std::vector<OutputCsv>& output_csv_files();
// The declaration of `file`; throws std::logic_error for an undeclared file.
const OutputCsv& output_csv(const std::string& file);

// Expands a family column (its declared name) into the names the writer writes.
using ColumnExpander = std::function<std::vector<std::string>(const std::string& family)>;
// The header line of `file` (no newline): the declared columns in order, those of another
// `variant` left out, families expanded by `expand` (left out without one).
std::string csv_header(const std::string& file, const std::string& variant = "", const ColumnExpander& expand = {});

// One summary.json key. Nested keys are named by their path with dots
// (`time_breakdown_s.engine`); `<…>` in a name declares a family as for columns.
struct SummaryKey {
  std::string name;
  std::string unit;
  std::string meaning;
  std::string when;  // "" in every summary of a finished run, else the condition it is written on
  // For the keys summary_json writes from RunSummary's own fields: their value.
  nlohmann::json (*value)(const RunSummary&) = nullptr;
};

const std::vector<SummaryKey>& summary_keys();
// True when `key` (dotted path) is declared, by name or as a member of a family.
bool summary_key_declared(const std::string& key);
// True when `name` is the declared `pattern` or a member of its family (`<…>` matches one or
// more characters).
bool matches_declared_name(const std::string& pattern, const std::string& name);

}  // namespace crumble
