#include "output/Plots.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <sstream>

namespace crumble {

namespace fs = std::filesystem;

namespace {

// crumble_plot.py's exit statuses (its docstring).
constexpr int kScriptBadInput = 2;
constexpr int kScriptNoMatplotlib = 3;
constexpr int kExecFailed = 127;

struct ChildResult {
  int status = -1;  // exit status, 128 + signal when killed
  std::string out, err;
  bool timed_out = false;
};

// Runs argv[0] (looked up on PATH) with stdout and stderr captured.
ChildResult run_child(const std::vector<std::string>& argv, double timeout_s) {
  ChildResult r;
  int po[2], pe[2];
  if (pipe(po) != 0) return r;
  if (pipe(pe) != 0) {
    close(po[0]);
    close(po[1]);
    return r;
  }
  std::cout.flush();
  std::cerr.flush();
  const pid_t pid = fork();
  if (pid < 0) {
    for (int fd : {po[0], po[1], pe[0], pe[1]}) close(fd);
    r.err = std::string("fork: ") + std::strerror(errno);
    return r;
  }
  if (pid == 0) {
    dup2(po[1], 1);
    dup2(pe[1], 2);
    for (int fd : {po[0], po[1], pe[0], pe[1]}) close(fd);
    const int devnull = open("/dev/null", O_RDONLY);
    if (devnull >= 0) dup2(devnull, 0);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    // The figures are drawn off-screen whatever the user's matplotlib configuration says.
    setenv("MPLBACKEND", "Agg", 1);
    execvp(args[0], args.data());
    _exit(kExecFailed);
  }
  close(po[1]);
  close(pe[1]);
  const auto t0 = std::chrono::steady_clock::now();
  pollfd fds[2] = {{po[0], POLLIN, 0}, {pe[0], POLLIN, 0}};
  int open_fds = 2;
  char buf[4096];
  while (open_fds > 0) {
    const double left = timeout_s - std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (left <= 0) {
      kill(pid, SIGKILL);
      r.timed_out = true;
      break;
    }
    const int n = poll(fds, 2, static_cast<int>(std::min(left * 1000.0, 1000.0)) + 1);
    if (n < 0 && errno != EINTR) break;
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      const ssize_t got = read(fds[i].fd, buf, sizeof buf);
      if (got > 0) {
        (i == 0 ? r.out : r.err).append(buf, static_cast<std::size_t>(got));
      } else if (got == 0 || errno != EINTR) {
        close(fds[i].fd);
        fds[i].fd = -1;
        --open_fds;
      }
    }
  }
  for (auto& f : fds)
    if (f.fd >= 0) close(f.fd);
  int st = 0;
  while (waitpid(pid, &st, 0) < 0 && errno == EINTR) {
  }
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
  return r;
}

std::string last_line(const std::string& s) {
  std::istringstream in(s);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  return last;
}

std::string executable_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string() : exe.parent_path().string();
}

}  // namespace

std::string plot_script_path(std::vector<std::string>* looked_in) {
  std::vector<std::string> places;
  if (const char* env = std::getenv("CRUMBLE_PLOT_SCRIPT"); env && *env) {
    places.push_back(env);  // an explicit choice: the only place looked in
  } else {
    const std::string exe = executable_dir();
    if (!exe.empty()) places.push_back((fs::path(exe) / ".." / "share" / "crumble" / "crumble_plot.py").lexically_normal().string());
#ifdef CRUMBLE_PLOT_SCRIPT_SOURCE
    places.push_back(CRUMBLE_PLOT_SCRIPT_SOURCE);
#endif
#ifdef CRUMBLE_PLOT_SCRIPT_INSTALLED
    places.push_back(CRUMBLE_PLOT_SCRIPT_INSTALLED);
#endif
  }
  if (looked_in) *looked_in = places;
  for (const auto& p : places) {
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) return p;
  }
  return "";
}

const std::vector<std::string>& plot_file_names() {
  static const std::vector<std::string> names = {
      "ncl.png",         "psd.png",           "breakage.png",          "fractal_dimension.png",
      "shape.png",       "load_displacement.png", "stress_strain.png", "product_psd.png",
      "compare_ncl.png", "compare_psd.png",   "compare_breakage.png",  "compare_stress_strain.png", "compare_load_displacement.png",
      "pareto.png"};
  return names;
}

PlotOutcome make_plots(const std::string& dir, double timeout_s) {
  PlotOutcome o;
  std::vector<std::string> looked;
  const std::string script = plot_script_path(&looked);
  if (script.empty()) {
    std::string where;
    for (const auto& p : looked) where += (where.empty() ? "" : ", ") + p;
    o.status = PlotOutcome::Status::Skipped;
    o.message = "the plotting script crumble_plot.py was not found (looked in " + where +
                "; set CRUMBLE_PLOT_SCRIPT to its path)";
    return o;
  }
  std::vector<std::string> pythons;
  const char* env = std::getenv("CRUMBLE_PYTHON");
  if (env && *env) {
    pythons.push_back(env);
  } else {
    pythons = {"python3", "/usr/bin/python3"};
  }
  std::string tried;
  for (const auto& py : pythons) {
    tried += (tried.empty() ? "" : ", ") + py;
    const ChildResult r = run_child({py, script, dir}, timeout_s);
    if (r.status == kExecFailed || r.status == kScriptNoMatplotlib) continue;  // try the next interpreter
    if (r.timed_out) {
      o.status = PlotOutcome::Status::Failed;
      o.message = script + " ran longer than " + std::to_string(static_cast<long>(timeout_s)) + " s and was stopped";
      return o;
    }
    std::istringstream in(r.out);
    for (std::string line; std::getline(in, line);)
      if (!line.empty()) o.files.push_back(line);
    if (r.status == 0) {
      o.status = PlotOutcome::Status::Written;
      return o;
    }
    o.status = r.status == kScriptBadInput ? PlotOutcome::Status::BadInput : PlotOutcome::Status::Failed;
    const std::string why = last_line(r.err);
    o.message = why.empty() ? py + " " + script + " ended with status " + std::to_string(r.status) : why;
    return o;
  }
  o.status = PlotOutcome::Status::Skipped;
  o.message = "no python3 with matplotlib (tried " + tried + "); install it (Debian: apt-get install python3-matplotlib)";
  return o;
}

void plots_after(const std::string& dir, bool quiet) {
  const PlotOutcome o = make_plots(dir);
  switch (o.status) {
    case PlotOutcome::Status::Written:
      if (!quiet) {
        std::string names;
        for (const auto& f : o.files) names += (names.empty() ? "" : ", ") + fs::path(f).filename().string();
        std::cerr << "crumble: plots: " << names << " in " << dir << "\n";
      }
      return;
    case PlotOutcome::Status::Skipped:
      std::cerr << "crumble: plots skipped, every CSV is written: " << o.message << ", then `crumble plot " << dir
                << "`\n";
      return;
    default:
      std::cerr << "crumble: plots failed, every CSV is written: " << o.message << " (retry: `crumble plot " << dir
                << "`)\n";
      return;
  }
}

}  // namespace crumble
