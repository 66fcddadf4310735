// The discretisation and mechanics of the densely arrayed bonded-particle model (DA-BPM):
// a grain is filled with equal elements arrayed in the densest way (hexagonal in 2D, face-
// centred cubic in 3D; the DA-BPM paper, "Densely arrayed BPM"), neighbours joined by
// parallel bonds (normal and shear stiffness per area, bending and twisting through the bond's
// second moments; Potyondy & Cundall 2004, the bond the DA-BPM paper uses), integrated
// explicitly with local non-viscous damping until the bonds settle or break.
#pragma once
#include <cstdint>
#include <vector>

#include "geometry/Shape.h"
#include "geometry/Vec3.h"

namespace crumble::bpm {

// Densest packing fractions: hexagonal discs π/(2√3) (Thue), FCC/HCP spheres π/(3√2)
// (Kepler's conjecture, proved by Hales) — the DA-BPM paper's "densest stack".
double packing_fraction(int dimension);
// Area (2D, per metre of thickness) or volume (3D) of one element's cell of the array: the
// element plus its share of the inner pores, (√3/2)·d² or d³/√2.
double cell_volume(int dimension, double d);
// Area (per metre) or volume of one element, πd²/4 or πd³/6.
double element_volume(int dimension, double d);

struct Bond {
  std::int32_t i = 0, j = 0;  // i < j
  Vec3 n;                     // unit vector from element i to j (reference)
};

struct Array {
  int dimension = 3;
  double d = 0;                  // element diameter = centre distance of bonded neighbours, m
  std::vector<Vec3> points;      // element centres (array frame), m
  std::vector<Bond> bonds;       // nearest-neighbour pairs
  std::vector<int> coordination; // bonds per element (6 in 2D, 12 in 3D inside the grain)
  std::size_t size() const { return points.size(); }
  int full_coordination() const { return dimension == 2 ? 6 : 12; }
};

// Element centres of the densest array of diameter `d` through the shape's centroid (the
// origin), rotated into the body frame by `frame` (the array's own axes: 2D rows along x, 3D
// the FCC cube axes), kept where Shape::contains(frame.rotate(p)). Points are returned in the
// array frame. 2D shapes give a hexagonal array in the x–y plane.
Array dense_array(const Shape& shape, double d, const Quat& frame = Quat{});
// The same from given centres (tests: a bar): bonds between centres d apart (±1e-6 d).
Array array_from_points(int dimension, double d, std::vector<Vec3> points);

// Parallel-bond parameters (per unit area of the bond cross-section; 2D: per metre of
// thickness, the bond a rectangle 2R̄ × 1 m).
struct BondLaw {
  double kn = 0;                // normal stiffness, Pa/m
  double ks = 0;                // shear stiffness, Pa/m
  double radius = 0;            // bond radius R̄ = radius_multiplier × element radius, m
  double normal_strength = 0;   // tensile strength σ̄_c, Pa
  double shear_strength = 0;    // shear strength τ̄_c, Pa
  // Elements of a broken bond still touch: a compression-only contact with the bond's
  // normal and shear stiffness and Coulomb friction μ (the BPM's contact law), so a crushed
  // zone under a load keeps carrying it.
  double friction = 0.5;
};

// Shear-to-normal stiffness ratio whose affine (Voigt) estimate gives the Poisson ratio ν:
// 2D (1 − 3ν)/(1 + ν), 3D (1 − 4ν)/(1 + ν); 0 beyond ν = 1/3 (2D) or 1/4 (3D), the
// central-force limit (the array then has that ν).
double shear_ratio_for_poisson(int dimension, double poisson);
// Young's modulus of the array along the array frame's axis `axis` (0 x, 1 y, 2 z) from its
// bond stiffness, by the Cauchy–Born rule (uniform strain; exact for these Bravais lattices,
// whose elements do not rotate under a symmetric strain). 2D: plane stress per metre.
double array_young(int dimension, double d, const BondLaw& law, int axis);

// Explicit dynamics of one array: translations and rotations of every element, small
// displacements (bond geometry of the reference state), local non-viscous damping
// (Cundall's: each force component reduced by α·|F| against its velocity).
class System {
 public:
  System(const Array& a, const BondLaw& law, double density);
  // Fixed elements (no motion).
  void fix(const std::vector<std::int32_t>& elements);
  // A force (N; 2D N/m) spread equally over `elements`, scaled by the load factor.
  void add_load(const std::vector<std::int32_t>& elements, const Vec3& force);
  // Stable step: 0.8·min √(m/k) over translations and rotations (k: every bond's spring).
  double stable_dt() const;
  // One step at load factor λ with local damping α; broken bonds act as contacts (BondLaw);
  // breaks bonds whose peak stress passes a
  // strength (tension σ = F_n/A + |M_b| R̄/I; shear τ = |F_s|/A + |M_t| R̄/J). Returns the
  // number of bonds broken in this step.
  int step(double dt, double lambda, double alpha);
  // The static state under the loads at λ = 1 with every bond intact (linear elasticity;
  // preconditioned conjugate gradients to a relative residual `tol`), and the largest ratio
  // of a bond's peak stress to its strength in that state: the bonds are linear, so the first
  // bond breaks at λ = 1 / ratio. Returns the iterations (−1: not converged).
  int static_unit_solution(double tol, int max_iter);
  double unit_stress_ratio() const { return unit_ratio_; }
  // Start from λ0 × the static state, at rest.
  void start_from_static(double lambda0);
  double kinetic_energy() const;
  // Work of the applied loads at the current displacement (λ·F·u).
  double load_work(double lambda) const;
  long broken() const { return broken_count_; }
  const std::vector<char>& intact() const { return intact_; }
  const Vec3& displacement(std::size_t i) const { return u_[i]; }

 private:
  const Array& a_;
  BondLaw law_;
  double area_ = 0, inertia_ = 0, polar_ = 0;  // bond A, I, J
  double mass_ = 0, rot_inertia_ = 0;
  std::vector<Vec3> u_, v_, th_, w_, f_, m_, fext_;
  std::vector<char> fixed_, intact_;
  std::vector<Vec3> u1_, th1_;  // static state at λ = 1
  double unit_ratio_ = 0;
  // Forces and moments of the intact bonds at displacements u, rotations th (no breaking).
  void bond_forces(const std::vector<Vec3>& u, const std::vector<Vec3>& th, std::vector<Vec3>& f,
                   std::vector<Vec3>& m) const;
  double stress_ratio(const std::vector<Vec3>& u, const std::vector<Vec3>& th) const;
  long broken_count_ = 0;
};

// Union–find over the intact bonds: component label per element (numbered by first element),
// and the size of each.
struct Components {
  std::vector<int> label;
  std::vector<long> size;
  int count = 0;
};
Components components(const Array& a, const std::vector<char>& intact);
// Components holding at least `min_fraction` of the elements and at least `min_elements`.
int major_count(const Components& c, double min_fraction, long min_elements = 1);

}  // namespace crumble::bpm
