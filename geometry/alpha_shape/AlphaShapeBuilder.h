// FragmentBuilder "alpha_shape" (Zhu & Zhao 2019 §3.2): child grains as
// alpha-shape polyhedra of the clusters' boundary points (PointClusters), or as the cells
// of the parent's mesh cut by planes (CuttingSurfaces); volumes rescaled so that the
// children's total equals the parent's.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "core/Config.h"
#include "core/Options.h"
#include "core/Engine.h"
#include "core/FragmentBuilder.h"
#include "geometry/cgal/AlphaShape.h"

namespace crumble {

struct AlphaShapeBuilderOptions {
  // Zhu & Zhao's simplification (Zhu & Zhao 2019 §3.2): a child whose equivalent diameter is
  // below hull_diameter (m), or whose convexity V / V_hull is >= hull_convexity, is
  // replaced by its convex hull. hull_convexity > 1 disables the convexity rule,
  // hull_diameter = 0 the size rule.
  double hull_diameter = 0.7e-3;
  double hull_convexity = 0.85;
  AlphaShapeOptions alpha;  // `spacing` is taken from each PointClusters
  // Points handed to the alpha shape. false (default): every material point of the
  // cluster plus its fracture points — the surface vertices are still exactly the
  // boundary vertices of Zhu & Zhao 2019 §3.2, and the inner layers give small Delaunay cells
  // under every flat patch of surface points. true: the boundary vertices only (the
  // paper's literal input); a single surface layer then has no small cell under a flat
  // lattice patch, and the shape stays open until alpha reaches about the piece's
  // inradius (measured on a half sphere of a 2 mm grain: sqrt(alpha) ≈ 3.8 spacings,
  // V/V_hull = 1.000, i.e. the convex hull; 4 hull fallbacks among 89 children of random
  // cuts, against 0 and sqrt(alpha) = 2 spacings with all points).
  bool alpha_boundary_only = false;
  // Centre of the uniform volume rescaling: true = the parent's centroid (the whole
  // assembly of children is scaled, so children that did not overlap still do not, and
  // the children's centroids move by the factor); false = each child's own centroid
  // (centroids stay where they were built).
  bool scale_about_parent = true;
  // CuttingSurfaces: pieces smaller than min_piece_volume_fraction × V_parent, or thinner
  // than min_piece_thickness_fraction × d_parent (twice the distance from the piece's
  // centroid to its hull's nearest face), are slivers of a plane grazing the surface: they
  // are removed as fines (FragmentResult::removed_volume) and counted as a fallback.
  // A parent mesh that cannot be cut (self-intersecting) is replaced by its convex hull
  // (method "plane_cut_hull", one fallback).
  double min_piece_volume_fraction = 1e-6;
  double min_piece_thickness_fraction = 0.02;
};

// Per-child diagnostics (benchmarks, tests).
struct ChildReport {
  std::string method;       // "alpha_shape", "convex_hull" (Zhu's rule), "hull_fallback", "plane_cut"
  int boundary_points = 0;  // points handed to the alpha shape / hull
  int cluster_points = 0;   // lattice points of the cluster
  double alpha = 0;         // accepted alpha (m²), 0 if none
  int alpha_steps = 0;      // candidate alphas examined
  double convexity = 0;     // V_alpha / V_hull of the alpha shape (0 when not built)
  double raw_volume = 0;    // volume of the mesh as built, before the rescaling (m³)
  double scale = 1;         // uniform length factor applied to every child of the parent
  double seconds = 0;       // wall time to build this child's mesh
  std::string note;         // why a fallback was taken
};

class AlphaShapeBuilder final : public FragmentBuilder {
 public:
  explicit AlphaShapeBuilder(AlphaShapeBuilderOptions opt = {});
  std::string name() const override { return "alpha_shape"; }
  // Thread-safe (const, no shared mutable state).
  FragmentResult build(const Shape& parent, const Fracture& fracture) const override;
  // The same, with one report per returned child (in the same order) when `reports`.
  FragmentResult build(const Shape& parent, const Fracture& fracture, std::vector<ChildReport>* reports) const;
  const AlphaShapeBuilderOptions& options() const { return opt_; }

 private:
  AlphaShapeBuilderOptions opt_;
  FragmentResult from_clusters(const Shape& parent, const PointClusters& pc, std::vector<ChildReport>* rep) const;
  FragmentResult from_planes(const Shape& parent, const CuttingSurfaces& cs, std::vector<ChildReport>* rep) const;
  // Rescales the meshes (parent frame) so that their volumes sum to `target` and wraps
  // them as Shape::polyhedron fragments.
  // `frame` rotates the meshes into the parent's body frame after scaling.
  std::vector<Fragment> finish(std::vector<TriMesh> meshes, double target, std::vector<ChildReport>* rep,
                               const Quat& frame = Quat{}) const;
};

// The options of the "fragments" object (`crumble list --options alpha_shape`).
const OptionTable& alpha_shape_options();
// Registry factory: cfg is the scenario's "fragments" object, read through alpha_shape_options().
std::unique_ptr<FragmentBuilder> make_alpha_shape_builder(const Config& cfg, const EngineContext& ctx);

}  // namespace crumble
