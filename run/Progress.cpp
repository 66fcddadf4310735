#include "run/Progress.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <sstream>

namespace crumble {

namespace {
constexpr std::size_t kMaxSamples = 4096;

// Wall seconds per unit fraction between two samples; < 0 when the fraction did not move.
double cost(const std::pair<double, double>& a, const std::pair<double, double>& b) {
  const double df = b.second - a.second;
  return df > 1e-12 ? (b.first - a.first) / df : -1;
}
}  // namespace

void EtaEstimator::add(double wall_s, double fraction) {
  if (!std::isfinite(wall_s) || !std::isfinite(fraction)) return;
  fraction = std::clamp(fraction, 0.0, 1.0);
  if (!s_.empty() && wall_s < s_.back().first) return;
  s_.push_back({wall_s, fraction});
  if (s_.size() > kMaxSamples) {
    // Keep the history bounded: drop every other sample of the older half.
    std::deque<std::pair<double, double>> t;
    for (std::size_t i = 0; i < s_.size(); ++i)
      if (i >= s_.size() / 2 || i % 2 == 0) t.push_back(s_[i]);
    s_ = std::move(t);
  }
}

double EtaEstimator::recent_cost() const {
  if (s_.size() < 2) return 0;
  const auto& last = s_.back();
  // The recent window: the last quarter of the elapsed wall time (at least the last two
  // samples), long enough to average over breakage bursts, short enough to follow the trend.
  const double span = 0.25 * (last.first - s_.front().first);
  std::size_t i = s_.size() - 2;
  while (i > 0 && last.first - s_[i].first < span) --i;
  const double c = cost(s_[i], last);
  return c > 0 ? c : 0;
}

double EtaEstimator::eta_s() const {
  if (s_.size() < 2) return -1;
  const auto& first = s_.front();
  const auto& last = s_.back();
  const double remaining = 1 - last.second;
  if (remaining <= 0) return 0;
  const double span = 0.25 * (last.first - first.first);
  // Recent window [i, last] and the window before it [k, i] of the same wall-time length.
  std::size_t i = s_.size() - 2;
  while (i > 0 && last.first - s_[i].first < span) --i;
  const double c1 = cost(s_[i], last);
  if (c1 <= 0) {
    // No progress lately: the average since the start, if any.
    const double c0 = cost(first, last);
    return c0 > 0 ? c0 * remaining : -1;
  }
  std::size_t k = i;
  while (k > 0 && s_[i].first - s_[k].first < span) --k;
  const double c0 = k < i ? cost(s_[k], s_[i]) : -1;
  double slope = 0;  // d(cost)/d(fraction)
  if (c0 > 0) {
    const double f1 = 0.5 * (s_[i].second + last.second), f0 = 0.5 * (s_[k].second + s_[i].second);
    if (f1 - f0 > 1e-12) slope = (c1 - c0) / (f1 - f0);
  }
  // The cost at the last sample and at the end, extrapolated linearly from the two windows;
  // a falling cost is not extrapolated (bursts of breakage make it noisy) and the growth is
  // capped at 4x over the rest of the loading. Remaining time: the integral of the cost.
  const double f1 = 0.5 * (s_[i].second + last.second);
  const double c_now = std::max(c1, c1 + std::max(0.0, slope) * (last.second - f1));
  const double c_end = std::min(c_now + std::max(0.0, slope) * remaining, 4 * c_now);
  return 0.5 * (c_now + c_end) * remaining;
}

std::string format_duration(double sec) {
  char b[64];
  if (!(sec >= 0) || !std::isfinite(sec)) return "?";
  const long s = std::lround(sec);
  if (s < 60) std::snprintf(b, sizeof b, "%ld s", s);
  else if (s < 3600) std::snprintf(b, sizeof b, "%ld m %02ld s", s / 60, s % 60);
  else std::snprintf(b, sizeof b, "%ld h %02ld m", s / 3600, (s % 3600) / 60);
  return b;
}

std::string format_done(double wall_s, long steps, std::size_t grains, long breakage_events, const std::string& dir) {
  return "done in " + format_duration(wall_s) + ": " + std::to_string(steps) + " steps, " + std::to_string(grains) +
         " grains, " + std::to_string(breakage_events) + " breakage events; results in " + dir;
}

std::string what_to_open(const std::string& dir) {
  namespace fs = std::filesystem;
  const fs::path d(dir);
  std::string figure;
  for (const char* f : {"ncl.png", "load_displacement.png", "stress_strain.png", "product_psd.png", "psd.png"})
    if (fs::exists(d / f)) {
      figure = (d / f).string();
      break;
    }
  const bool scene = fs::exists(d / "scene.pvd");
  if (figure.empty() && !scene) return "";
  std::string s = figure.empty() ? "" : "open " + figure + " first";
  if (scene)
    s += (figure.empty() ? "open " : ", then ") + (d / "scene.pvd").string() +
         " in ParaView (the grains at each snapshot; docs/output.md)";
  return s;
}

std::string format_progress(const RunState& s, double fraction, double elapsed, double eta) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(1) << "[" << std::setw(5) << 100 * fraction << "%] t=" << std::setprecision(5)
     << s.time << " s step " << s.step << " | stress " << std::setprecision(3) << s.platen_stress / 1e6
     << " MPa, strain " << std::setprecision(4) << s.axial_strain << " | " << s.grains << " grains, "
     << s.breakage_events << " breakages (" << s.analyses << " analyses) | elapsed " << format_duration(elapsed)
     << ", ETA " << (eta >= 0 ? format_duration(eta) : std::string("?"));
  return os.str();
}

}  // namespace crumble
