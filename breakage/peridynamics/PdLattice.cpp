#include "breakage/peridynamics/PdLattice.h"
#include "base/Format.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

namespace crumble::pd {

namespace {

// Volume of the unit cube centred at (a, b, c) inside the ball of radius R centred at
// the origin: midpoint rule in x and y, exact chord length in z.
double cube_ball_fraction(int a, int b, int c, double R) {
  constexpr int n = 160;
  const double h = 1.0 / n;
  double sum = 0;
  for (int ix = 0; ix < n; ++ix) {
    const double x = a - 0.5 + (ix + 0.5) * h;
    for (int iy = 0; iy < n; ++iy) {
      const double y = b - 0.5 + (iy + 0.5) * h;
      const double s2 = R * R - x * x - y * y;
      if (s2 <= 0) continue;
      const double s = std::sqrt(s2);
      const double lo = std::max(c - 0.5, -s), hi = std::min(c + 0.5, s);
      if (hi > lo) sum += hi - lo;
    }
  }
  return sum * h * h;
}

std::vector<StencilEntry> make_stencil(double R, bool partial) {
  std::vector<StencilEntry> st;
  const int reach = static_cast<int>(std::ceil(R + 1.0));
  std::map<std::array<int, 3>, double> fractions;  // by sorted |offset|: identical for symmetric bonds
  for (int dz = -reach; dz <= reach; ++dz)
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dx = -reach; dx <= reach; ++dx) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        const double len = std::sqrt(double(dx * dx + dy * dy + dz * dz));
        double w = 0;
        if (!partial) {
          w = len <= R ? 1.0 : 0.0;
        } else {
          if (len > R + std::sqrt(3.0) / 2 + 1e-12) continue;
          std::array<int, 3> key{std::abs(dx), std::abs(dy), std::abs(dz)};
          std::sort(key.begin(), key.end());
          auto it = fractions.find(key);
          if (it == fractions.end()) it = fractions.emplace(key, cube_ball_fraction(key[0], key[1], key[2], R)).first;
          w = it->second;
          if (w > 1.0 - 1e-9) w = 1.0;
        }
        if (w < 1e-9) continue;
        st.push_back({dx, dy, dz, len, w});
      }
  return st;
}

}  // namespace

const std::vector<StencilEntry>& horizon_stencil(double horizon_factor, bool partial_volumes) {
  if (!(horizon_factor >= 1.0) || !(horizon_factor <= 8.0))
    throw std::invalid_argument("peridynamics: horizon_factor must lie in [1, 8] spacings, got " +
                                fmt_num(horizon_factor));
  static std::mutex mu;
  static std::map<std::pair<double, bool>, std::vector<StencilEntry>> cache;
  std::lock_guard<std::mutex> lock(mu);
  auto key = std::make_pair(horizon_factor, partial_volumes);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, make_stencil(horizon_factor, partial_volumes)).first;
  return it->second;  // std::map nodes are stable: the reference outlives the lock
}

bool Lattice::on_surface(std::size_t i) const {
  for (auto b : face_bond[i])
    if (b < 0) return true;
  return false;
}

Lattice build_lattice(const std::vector<Vec3>& pts, double spacing, double horizon_factor, bool partial_volumes,
                      double point_volume) {
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw std::invalid_argument("peridynamics: lattice spacing must be > 0");
  const auto& stencil = horizon_stencil(horizon_factor, partial_volumes);
  Lattice L;
  L.spacing = spacing;
  L.horizon = horizon_factor * spacing;
  L.point_volume = point_volume > 0 ? point_volume : spacing * spacing * spacing;
  const std::size_t n = pts.size();
  if (n == 0) throw std::invalid_argument("peridynamics: empty lattice");

  // Integer coordinates, sorted lexicographically (z, y, x) so neighbours in a row are
  // adjacent in memory.
  std::vector<std::array<int, 3>> ijk(n);
  std::array<int, 3> lo{INT32_MAX, INT32_MAX, INT32_MAX}, hi{INT32_MIN, INT32_MIN, INT32_MIN};
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) {
      const double q = pts[i][a] / spacing;
      const double r = std::round(q);
      if (!std::isfinite(q) || std::abs(q - r) > 1e-6 || std::abs(r) > 1e6)
        throw std::invalid_argument("peridynamics: point off the lattice of spacing " + fmt_num(spacing));
      ijk[i][a] = static_cast<int>(r);
      lo[a] = std::min(lo[a], ijk[i][a]);
      hi[a] = std::max(hi[a], ijk[i][a]);
    }
  }
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::array<int, 3>{ijk[a][2], ijk[a][1], ijk[a][0]} < std::array<int, 3>{ijk[b][2], ijk[b][1], ijk[b][0]};
  });
  L.points.resize(n);
  L.cell.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    L.cell[k] = ijk[order[k]];
    L.points[k] = Vec3{double(L.cell[k][0]), double(L.cell[k][1]), double(L.cell[k][2])} * spacing;
  }

  // Dense index grid over the bounding box (grains are ~20 spacings across).
  const long nx = hi[0] - lo[0] + 1, ny = hi[1] - lo[1] + 1, nz = hi[2] - lo[2] + 1;
  if (nx * ny * nz > 200'000'000L) throw std::invalid_argument("peridynamics: lattice too large");
  std::vector<std::int32_t> grid(static_cast<std::size_t>(nx * ny * nz), -1);
  auto at = [&](int x, int y, int z) -> std::int32_t {
    if (x < lo[0] || x > hi[0] || y < lo[1] || y > hi[1] || z < lo[2] || z > hi[2]) return -1;
    return grid[static_cast<std::size_t>(((z - lo[2]) * ny + (y - lo[1])) * nx + (x - lo[0]))];
  };
  for (std::size_t k = 0; k < n; ++k) {
    auto& g = grid[static_cast<std::size_t>(((L.cell[k][2] - lo[2]) * ny + (L.cell[k][1] - lo[1])) * nx +
                                            (L.cell[k][0] - lo[0]))];
    if (g >= 0) throw std::invalid_argument("peridynamics: duplicate lattice point");
    g = static_cast<std::int32_t>(k);
  }

  L.offsets.assign(n + 1, 0);
  L.face_bond.assign(n, {-1, -1, -1, -1, -1, -1});
  std::vector<std::pair<std::int32_t, std::size_t>> row;  // (neighbour, stencil entry)
  for (std::size_t k = 0; k < n; ++k) {
    row.clear();
    const auto& c = L.cell[k];
    for (std::size_t s = 0; s < stencil.size(); ++s) {
      const auto& e = stencil[s];
      const std::int32_t j = at(c[0] + e.dx, c[1] + e.dy, c[2] + e.dz);
      if (j >= 0) row.emplace_back(j, s);
    }
    std::sort(row.begin(), row.end());
    for (const auto& [j, s] : row) {
      const auto& e = stencil[s];
      const int manhattan = std::abs(e.dx) + std::abs(e.dy) + std::abs(e.dz);
      if (manhattan == 1) {
        const int dir = e.dx != 0 ? (e.dx > 0 ? 0 : 1) : e.dy != 0 ? (e.dy > 0 ? 2 : 3) : (e.dz > 0 ? 4 : 5);
        L.face_bond[k][dir] = static_cast<std::int32_t>(L.neighbours.size());
      }
      L.neighbours.push_back(j);
      L.length.push_back(e.length * spacing);
      L.weight.push_back(e.weight);
    }
    if (L.neighbours.size() > static_cast<std::size_t>(INT32_MAX))
      throw std::invalid_argument("peridynamics: too many bonds");
    L.offsets[k + 1] = static_cast<std::int32_t>(L.neighbours.size());
  }
  return L;
}

std::vector<Vec3> lattice_points(const Shape& shape, double spacing, const Quat& frame) {
  if (frame.w == 1 && frame.x == 0 && frame.y == 0 && frame.z == 0) return lattice_points(shape, spacing);
  if (shape.dimension() != 3) throw std::invalid_argument("peridynamics: needs a 3D shape, got " + shape.describe());
  if (!(spacing > 0)) throw std::invalid_argument("peridynamics: lattice spacing must be > 0");
  // Any rotation of the shape stays inside its bounding sphere.
  const double br = shape.bounding_radius();
  const int n = static_cast<int>(std::ceil(br / spacing)) + 1;
  const double cells = std::pow(2.0 * n + 1, 3);
  if (cells > 5e7)
    throw std::invalid_argument("peridynamics: lattice of " + std::to_string(cells) + " cells for " +
                                shape.describe() + " is too fine");
  std::vector<Vec3> pts;
  for (int z = -n; z <= n; ++z)
    for (int y = -n; y <= n; ++y)
      for (int x = -n; x <= n; ++x) {
        const Vec3 p{x * spacing, y * spacing, z * spacing};
        if (norm2(p) <= br * br * (1 + 1e-12) && shape.contains(frame.rotate(p))) pts.push_back(p);
      }
  return pts;
}

std::vector<Vec3> lattice_points(const Shape& shape, double spacing) {
  if (shape.dimension() != 3) throw std::invalid_argument("peridynamics: needs a 3D shape, got " + shape.describe());
  if (!(spacing > 0)) throw std::invalid_argument("peridynamics: lattice spacing must be > 0");
  const Aabb b = shape.bounds();
  std::array<int, 3> lo{}, hi{};
  for (int a = 0; a < 3; ++a) {
    lo[a] = static_cast<int>(std::floor(b.lo[a] / spacing)) - 1;
    hi[a] = static_cast<int>(std::ceil(b.hi[a] / spacing)) + 1;
  }
  const double cells = double(hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
  if (cells > 5e7)
    throw std::invalid_argument("peridynamics: lattice of " + std::to_string(cells) + " cells for " +
                                shape.describe() + " is too fine");
  std::vector<Vec3> pts;
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int x = lo[0]; x <= hi[0]; ++x) {
        const Vec3 p{x * spacing, y * spacing, z * spacing};
        if (shape.contains(p)) pts.push_back(p);
      }
  return pts;
}

}  // namespace crumble::pd
