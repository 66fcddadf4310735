#include "breakage/block_beam/BbSystem.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace crumble::bb {

void triangle_section(const Vec3& p0, const Vec3& p1, const Vec3& p2, double* area, double* inertia, double* polar,
                      double* c_max, Vec3* centroid) {
  const Vec3 c = (p0 + p1 + p2) * (1.0 / 3.0);
  const double A = 0.5 * norm(cross(p1 - p0, p2 - p0));
  // ∫|r|² dA about the centroid of a triangle = (A/12) Σ |r_k|² over its vertices r_k
  // (relative to the centroid); the in-plane second moments about two perpendicular axes
  // sum to it, so their mean is half of it.
  const double s = norm2(p0 - c) + norm2(p1 - c) + norm2(p2 - c);
  *area = A;
  *polar = A * s / 12.0;
  *inertia = 0.5 * *polar;
  *c_max = std::sqrt(std::max({norm2(p0 - c), norm2(p1 - c), norm2(p2 - c)}));
  *centroid = c;
}

Blocks make_blocks(TetMesh mesh) {
  Blocks b;
  b.mesh = std::move(mesh);
  const int n = static_cast<int>(b.mesh.tets.size());
  b.centroid.resize(n);
  b.volume.resize(n);
  double edges = 0;
  for (int t = 0; t < n; ++t) {
    b.volume[t] = tet_volume(b.mesh, t);
    if (!(b.volume[t] > 0))
      throw std::invalid_argument("block–beam: tetrahedron " + std::to_string(t) + " has volume <= 0");
    b.centroid[t] = tet_centroid(b.mesh, t);
    const auto& v = b.mesh.tets[t];
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) edges += norm(b.mesh.vertices[v[i]] - b.mesh.vertices[v[j]]);
  }
  b.mean_edge = n > 0 ? edges / (6.0 * n) : 0;
  b.faces = shared_faces(b.mesh);
  b.beams.reserve(b.faces.size());
  for (int f = 0; f < static_cast<int>(b.faces.size()); ++f) {
    const TetFace& face = b.faces[f];
    Beam beam;
    beam.a = face.a;
    beam.b = face.b;
    beam.face = f;
    const Vec3 d = b.centroid[face.b] - b.centroid[face.a];
    beam.length = norm(d);
    if (!(beam.length > 0)) throw std::invalid_argument("block–beam: two blocks share a centroid");
    beam.axis = d * (1.0 / beam.length);
    const auto& V = b.mesh.vertices;
    triangle_section(V[face.vertices[0]], V[face.vertices[1]], V[face.vertices[2]], &beam.area, &beam.inertia,
                     &beam.polar, &beam.c_max, &beam.face_centroid);
    beam.x_face = std::clamp(dot(beam.face_centroid - b.centroid[face.a], beam.axis), 0.0, beam.length);
    b.beams.push_back(beam);
  }
  return b;
}

// Internal loads of the 3D Euler–Bernoulli frame element (local stiffness matrix of a
// prismatic beam, e.g. Przemieniecki 1968, ch. 5) written with vectors: e the axis, d = u_b −
// u_a; the beam's loads on its end nodes are −K·(u, θ).
BeamLoads beam_loads(const Beam& beam, const BeamMaterial& m, const Vec3& ua, const Vec3& ta, const Vec3& ub,
                     const Vec3& tb) {
  const Vec3& e = beam.axis;
  const double L = beam.length;
  const double EA = m.young * beam.area, EI = m.young * beam.inertia, GJ = m.shear * beam.polar;
  const Vec3 d = ub - ua;
  const double dn = dot(d, e);
  const Vec3 dt = d - e * dn;
  const auto perp = [&](const Vec3& v) { return v - e * dot(v, e); };
  const Vec3 ta_p = perp(ta), tb_p = perp(tb);
  BeamLoads l;
  l.force_a = e * (EA / L * dn) + dt * (12 * EI / (L * L * L)) - cross(ta + tb, e) * (6 * EI / (L * L));
  l.force_b = l.force_a * -1.0;
  const double twist = GJ / L * dot(tb - ta, e);
  const Vec3 dxe = cross(d, e) * (6 * EI / (L * L));
  l.moment_a = dxe * -1.0 - (ta_p * 4.0 + tb_p * 2.0) * (EI / L) + e * twist;
  l.moment_b = dxe * -1.0 - (ta_p * 2.0 + tb_p * 4.0) * (EI / L) - e * twist;
  l.axial = dot(l.force_a, e);
  l.shear = norm(perp(l.force_a));
  l.torsion = std::abs(twist);
  // Section moment at x (what the part [0, x] transmits): −M_a + x e × F_a.
  const Vec3 ms = l.moment_a * -1.0 + cross(e * beam.x_face, l.force_a);
  l.bending = norm(perp(ms));
  return l;
}

double beam_failure_ratio(const Beam& beam, const BeamMaterial& m, const BeamLoads& l) {
  const double sigma = l.axial / beam.area + l.bending * beam.c_max / beam.inertia;
  const double tau = l.shear / beam.area + l.torsion * beam.c_max / beam.polar;
  return std::max(sigma / m.tensile, tau / m.shear_strength);
}

BbSystem::BbSystem(const Blocks& blocks, const BeamMaterial& m, double mass_factor) : b_(blocks), m_(m) {
  const std::size_t n = b_.centroid.size();
  mass_.assign(n, 0.0);
  rot_inertia_.assign(n, 0.0);
  // Fictitious masses of dynamic relaxation: per block, the Gershgorin row sum of its
  // translational and rotational rows of the stiffness matrix (times mass_factor), so a
  // unit step is stable for every block whatever its size.
  for (const Beam& bm : b_.beams) {
    const double L = bm.length;
    const double EA = m_.young * bm.area, EI = m_.young * bm.inertia, GJ = m_.shear * bm.polar;
    const double kt = std::max(2 * EA / L, 24 * EI / (L * L * L) + 12 * EI / (L * L));
    const double kr = std::max(2 * GJ / L, 12 * EI / (L * L) + 6 * EI / L);
    for (int k : {bm.a, bm.b}) {
      mass_[k] += mass_factor * kt;
      rot_inertia_[k] += mass_factor * kr;
    }
  }
  for (std::size_t i = 0; i < n; ++i) {  // a block without beams still moves (it is a fragment)
    if (!(mass_[i] > 0)) mass_[i] = 1;
    if (!(rot_inertia_[i] > 0)) rot_inertia_[i] = 1;
  }
  u_.assign(n, Vec3{});
  th_ = v_ = w_ = load_ = f_ = mo_ = u_;
  fixed_.assign(n, 0);
  broken_.assign(b_.beams.size(), 0);
}

void BbSystem::add_load(int block, const Vec3& force) {
  load_[block] += force;
  max_load_ = std::max(max_load_, norm(load_[block]));
}

long BbSystem::step(double lambda, double alpha) {
  const std::size_t n = u_.size();
  for (std::size_t i = 0; i < n; ++i) {
    f_[i] = load_[i] * lambda;
    mo_[i] = Vec3{};
  }
  long newly = 0;
  for (std::size_t k = 0; k < b_.beams.size(); ++k) {
    const Beam& bm = b_.beams[k];
    if (broken_[k]) {
      // A broken face still closes: it carries compression along the axis only (the
      // contact between blocks that Liu et al. 2019 §2.2 detect), never tension or shear.
      const double dn = dot(u_[bm.b] - u_[bm.a], bm.axis);
      if (dn < 0) {
        const Vec3 f = bm.axis * (m_.young * bm.area / bm.length * dn);
        f_[bm.a] += f;
        f_[bm.b] += f * -1.0;
      }
      continue;
    }
    const BeamLoads l = beam_loads(bm, m_, u_[bm.a], th_[bm.a], u_[bm.b], th_[bm.b]);
    if (beam_failure_ratio(bm, m_, l) >= 1.0) {
      broken_[k] = 1;
      ++newly;
      continue;
    }
    f_[bm.a] += l.force_a;
    f_[bm.b] += l.force_b;
    mo_[bm.a] += l.moment_a;
    mo_[bm.b] += l.moment_b;
  }
  broken_count_ += newly;
  double worst = 0;
  // Local non-viscous damping (Cundall): each component of the out-of-balance load is
  // reduced by α against the direction of motion; semi-implicit Euler with a unit step.
  auto damp = [alpha](double f, double v) { return f - alpha * std::abs(f) * (v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0)); };
  for (std::size_t i = 0; i < n; ++i) {
    if (fixed_[i]) continue;
    worst = std::max(worst, norm(f_[i]));
    const Vec3 f{damp(f_[i].x, v_[i].x), damp(f_[i].y, v_[i].y), damp(f_[i].z, v_[i].z)};
    const Vec3 mo{damp(mo_[i].x, w_[i].x), damp(mo_[i].y, w_[i].y), damp(mo_[i].z, w_[i].z)};
    v_[i] += f * (1.0 / mass_[i]);
    w_[i] += mo * (1.0 / rot_inertia_[i]);
    u_[i] += v_[i];
    th_[i] += w_[i];
  }
  unbalance_ = max_load_ > 0 ? worst / (max_load_ * std::max(lambda, 1e-300)) : 0;
  return newly;
}

std::vector<int> components(const Blocks& b, const std::vector<char>& broken, int* count) {
  const int n = static_cast<int>(b.centroid.size());
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::size_t k = 0; k < b.beams.size(); ++k) {
    if (broken[k]) continue;
    const int a = find(b.beams[k].a), c = find(b.beams[k].b);
    if (a != c) parent[std::max(a, c)] = std::min(a, c);
  }
  std::vector<int> label(n, -1), id(n, -1);
  int k = 0;
  for (int i = 0; i < n; ++i) {
    const int r = find(i);
    if (id[r] < 0) id[r] = k++;
    label[i] = id[r];
  }
  *count = k;
  return label;
}

}  // namespace crumble::bb
