// The block–beam system of one grain (Liu et al. 2019 §2.1, §2.3; the three-dimensional
// block-element beam–particle model they build on): tetrahedral blocks are rigid bodies
// (6 DOF), every pair of blocks sharing a face is joined by a beam from centroid to
// centroid whose cross-section is the shared face; a beam disappears when the stress in
// that cross-section exceeds the material's tensile or shear strength.
//
// Our paper copy prints the algorithms only as figure titles (Algorithms 4 and 5): no beam
// equations, no strength criterion in symbols and no material table. What is written here
// is the standard 3D Euler–Bernoulli frame element and the beam-section stresses of a
// beam–particle model; the choices are listed in BlockBeam.h.
#pragma once
#include <cstdint>
#include <vector>

#include "geometry/cgal/TetMesh.h"
#include "geometry/Vec3.h"

namespace crumble::bb {

// A beam between blocks a and b.
struct Beam {
  int a = 0, b = 0;
  Vec3 axis;            // unit vector from centroid a to centroid b
  double length = 0;    // m
  double area = 0;      // m², the shared face
  double inertia = 0;   // m⁴, second moment of the face about an in-plane axis through its centroid (mean of the two principal values)
  double polar = 0;     // m⁴, polar moment of the face (sum of the principal values)
  double c_max = 0;     // m, largest distance of a face vertex from the face centroid
  double x_face = 0;    // m, position of the face centroid along the axis from a, in [0, length]
  Vec3 face_centroid;   // m
  int face = 0;         // index into Blocks::faces
};

struct Blocks {
  TetMesh mesh;
  std::vector<Vec3> centroid;   // per block
  std::vector<double> volume;   // per block, m³ (> 0)
  std::vector<TetFace> faces;   // shared faces
  std::vector<Beam> beams;      // one per shared face
  double mean_edge = 0;         // m, mean edge length of the blocks
};

// Blocks and beams of a tetrahedral mesh (every tetrahedron must have positive volume:
// std::invalid_argument otherwise).
Blocks make_blocks(TetMesh mesh);

// Beam-section properties of the triangle (p0, p1, p2): area, mean in-plane second moment
// and polar moment about its centroid, largest centroid–vertex distance.
void triangle_section(const Vec3& p0, const Vec3& p1, const Vec3& p2, double* area, double* inertia, double* polar,
                      double* c_max, Vec3* centroid);

struct BeamMaterial {
  double young = 0;    // Pa
  double shear = 0;    // Pa, G = E / (2 (1 + ν))
  double tensile = 0;  // Pa, tensile strength of a beam section
  double shear_strength = 0;  // Pa
};

// Loads a beam exerts on its two blocks for small displacements u and rotation vectors θ of
// the blocks (3D Euler–Bernoulli frame element in the beam's axis: axial EA/L, torsion GJ/L,
// bending 12EI/L³, 6EI/L², 4EI/L, 2EI/L), and the section resultants at the shared face.
struct BeamLoads {
  Vec3 force_a, moment_a, force_b, moment_b;  // on block a / b (N, N·m)
  double axial = 0;    // N, > 0 in tension
  double shear = 0;    // N, magnitude of the transverse force
  double torsion = 0;  // N·m, magnitude
  double bending = 0;  // N·m, magnitude at the shared face
};
BeamLoads beam_loads(const Beam& beam, const BeamMaterial& m, const Vec3& ua, const Vec3& ta, const Vec3& ub,
                     const Vec3& tb);

// Section stresses at the shared face: the largest tensile normal stress N/A + M c/I and the
// largest shear stress V/A + T c/J; the beam breaks when either exceeds its strength.
// Returns max(σ_t / tensile, τ / shear_strength) (≥ 1: broken).
double beam_failure_ratio(const Beam& beam, const BeamMaterial& m, const BeamLoads& l);

// Explicit dynamic relaxation of the block–beam system under loads applied to blocks.
class BbSystem {
 public:
  BbSystem(const Blocks& blocks, const BeamMaterial& m, double mass_factor);
  void fix(int block) { fixed_[block] = 1; }
  void add_load(int block, const Vec3& force);  // N at load factor 1, through the block centroid
  // One step at load factor `lambda` with local (Cundall) damping `alpha`; beams whose
  // failure ratio reaches 1 break (all of those found in this step). Returns the number
  // broken in this step.
  long step(double lambda, double alpha);
  // Largest out-of-balance force of a free block relative to the largest block load.
  double unbalance() const { return unbalance_; }
  long broken() const { return broken_count_; }
  const std::vector<char>& broken_flags() const { return broken_; }
  const std::vector<Vec3>& displacement() const { return u_; }
  const std::vector<Vec3>& rotation() const { return th_; }
  const Blocks& blocks() const { return b_; }

 private:
  const Blocks& b_;
  BeamMaterial m_;
  std::vector<double> mass_, rot_inertia_;  // fictitious (dynamic relaxation, step 1)
  std::vector<Vec3> u_, th_, v_, w_, load_, f_, mo_;
  std::vector<char> fixed_, broken_;
  long broken_count_ = 0;
  double unbalance_ = 0, max_load_ = 0;
};

// Connected block sets over intact beams: label per block, and count.
std::vector<int> components(const Blocks& b, const std::vector<char>& broken, int* count);

}  // namespace crumble::bb
