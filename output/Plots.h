// PNG figures of an output folder: scripts/crumble_plot.py, run with python3 and
// matplotlib (Debian: python3-matplotlib) as a child process, after `crumble run`, `compare` and
// `sweep`, and by `crumble plot DIR`. The figures are an output writer's business, so they live
// in scenarios/; no CSV depends on them: a machine without matplotlib gets every CSV.
//
// Where the script is found, first match wins:
//   1. $CRUMBLE_PLOT_SCRIPT (a file);
//   2. <directory of the crumble binary>/../share/crumble/crumble_plot.py (an installed tree:
//      `cmake --install build --prefix P` puts it in P/share/crumble/);
//   3. the source tree the binary was built from, scripts/crumble_plot.py (a build tree);
//   4. the install prefix configured at build time, .../share/crumble/crumble_plot.py (an
//      installed binary that was moved, or whose source tree is gone).
// The interpreter: $CRUMBLE_PYTHON when set (only that one); otherwise `python3` on PATH, then
// /usr/bin/python3 (Debian's python3-matplotlib installs into the system interpreter, which a
// python3 earlier on PATH, e.g. pyenv's, may not see).
#pragma once
#include <string>
#include <vector>

namespace crumble {

struct PlotOutcome {
  enum class Status {
    Written,   // the figures are in the folder
    Skipped,   // no script, or no python3 that imports matplotlib: nothing written
    BadInput,  // the folder or one of its files cannot be read (message names the file)
    Failed,    // the script failed otherwise
  };
  Status status = Status::Failed;
  std::vector<std::string> files;  // the PNG files written (paths as the script printed them)
  std::string message;             // why, when not Written (one line)
};

// Writes the figures of DIR (a run, compare or sweep folder). Never throws for a plotting
// problem: the outcome says what happened. A script running longer than `timeout_s` is killed.
PlotOutcome make_plots(const std::string& dir, double timeout_s = 600);

// The script make_plots runs ("" when none of the places above holds it), and the places looked in.
std::string plot_script_path(std::vector<std::string>* looked_in = nullptr);

// The PNG files crumble_plot.py may write into a run folder and into a compare/sweep folder
// (what `--force` removes besides the CSVs).
const std::vector<std::string>& plot_file_names();

// After a run, compare or sweep: make the plots and report in one line on stderr: the figures
// written (unless `quiet`), or why they were skipped or failed and how to get them. Never
// changes the caller's exit status.
void plots_after(const std::string& dir, bool quiet);

}  // namespace crumble
