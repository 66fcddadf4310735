#include "breakage/peridynamics/PdClusters.h"

#include <algorithm>
#include <limits>
#include <numeric>

namespace crumble::pd {

namespace {
int find(std::vector<int>& parent, int x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}
}  // namespace

Components face_components(const Lattice& L, const std::vector<double>& alive) {
  const int n = static_cast<int>(L.size());
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < 6; d += 2) {  // +x, +y, +z: each face bond once
      const auto q = L.face_bond[i][d];
      if (q < 0 || alive[q] == 0.0) continue;
      const int a = find(parent, i), b = find(parent, L.neighbours[q]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  Components c;
  c.label.assign(n, -1);
  std::vector<int> id(n, -1);
  for (int i = 0; i < n; ++i) {
    const int r = find(parent, i);
    if (id[r] < 0) {
      id[r] = c.count++;
      c.size.push_back(0);
    }
    c.label[i] = id[r];
    ++c.size[id[r]];
  }
  return c;
}

int major_count(const Components& c, double min_fraction) {
  long total = 0;
  for (long s : c.size) total += s;
  int k = 0;
  for (long s : c.size) k += static_cast<double>(s) >= min_fraction * static_cast<double>(total);
  return k;
}

PointClusters point_clusters(const Lattice& L, const std::vector<double>& alive, double min_fraction) {
  const Components comp = face_components(L, alive);
  const int n = static_cast<int>(L.size());
  // Majors, largest first (ties: lower component id, i.e. lower first point).
  std::vector<int> order(comp.count);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return comp.size[a] > comp.size[b]; });
  std::vector<int> major_of(comp.count, -1);
  int majors = 0;
  for (int c : order)
    if (static_cast<double>(comp.size[c]) >= min_fraction * n) major_of[c] = majors++;
  if (majors == 0) major_of[order[0]] = majors++;

  PointClusters pc;
  pc.spacing = L.spacing;
  pc.points = L.points;
  pc.clusters = majors;
  pc.cluster.assign(n, -1);
  pc.on_surface.assign(n, 0);
  for (int i = 0; i < n; ++i) {
    pc.cluster[i] = major_of[comp.label[i]];
    pc.on_surface[i] = L.on_surface(i) ? 1 : 0;
  }

  // Fines: each minor component joins the major piece nearest to it (over its points).
  std::vector<std::vector<int>> members(comp.count);
  for (int i = 0; i < n; ++i)
    if (pc.cluster[i] < 0) members[comp.label[i]].push_back(i);
  for (int c = 0; c < comp.count; ++c) {
    if (members[c].empty()) continue;
    double best = std::numeric_limits<double>::infinity();
    int target = -1;
    auto consider = [&](int i, int j) {
      const int t = pc.cluster[j];
      if (t < 0 || major_of[comp.label[j]] < 0) return;  // only points of major pieces
      const double d = norm2(L.points[j] - L.points[i]);
      if (d < best || (d == best && t < target)) {
        best = d;
        target = t;
      }
    };
    for (int i : members[c])  // within the horizon first
      for (auto q = L.offsets[i]; q < L.offsets[i + 1]; ++q) consider(i, L.neighbours[q]);
    if (target < 0)
      for (int i : members[c])
        for (int j = 0; j < n; ++j) consider(i, j);
    for (int i : members[c]) pc.cluster[i] = target;
  }

  pc.fracture_points.assign(majors, {});
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < 6; d += 2) {
      const auto q = L.face_bond[i][d];
      if (q < 0 || alive[q] != 0.0) continue;
      const int j = L.neighbours[q];
      const int ci = pc.cluster[i], cj = pc.cluster[j];
      if (ci == cj) continue;
      const Vec3 mid = (L.points[i] + L.points[j]) * 0.5;
      pc.fracture_points[ci].push_back(mid);
      pc.fracture_points[cj].push_back(mid);
    }
  return pc;
}

}  // namespace crumble::pd
