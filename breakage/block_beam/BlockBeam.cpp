#include "breakage/block_beam/BlockBeam.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "breakage/block_beam/BbSystem.h"

namespace crumble {

namespace {

using Clock = std::chrono::steady_clock;

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("block_beam: " + what);
}

}  // namespace

// ---------------------------------------------------------------- options

const OptionTable& block_beam_options() {
  using S = BbOptions;
  static const OptionTable t = [] {
    const double inf = std::numeric_limits<double>::infinity();
    return OptionTable{
        // Mesh (Liu et al. 2019 §2.1).
        opt::number("blocks_per_diameter", &S::blocks_per_diameter, 1, 100, "",
                    "d_e / target edge of the tetrahedral blocks (CGAL Mesh_3; Liu et al. 2019 §2.1)"),
        opt::number("facet_distance", &S::facet_distance, 0, 1, "",
                    "largest distance of the meshed surface from the grain's, / target edge (0: edge / 10)"),
        opt::integer("min_blocks", &S::min_blocks, 2, 100'000'000, "fewer blocks: outcome too_few_blocks"),
        // Beams and strength (§2.3).
        opt::positive("tensile_strength", &S::tensile_strength, "Pa",
                      "a beam disappears when N/A + M c/I in its face section reaches this (Liu et al. 2019 §2.3)"),
        opt::positive("shear_strength", &S::shear_strength, "Pa", "… or when V/A + T c/J reaches this"),
        opt::number("weibull_modulus", &S::weibull_modulus, 0, 100, "",
                    "> 0: both strengths × one Weibull factor of mean 1 per grain; 0: nominal strengths"),
        opt::number("threshold_factor", &S::threshold_factor, 0, inf, "",
                    "screening force = this × tensile_strength × d_e² (the Brazilian splitting load is ≈ 1.1×)"),
        // Loading and relaxation.
        opt::number("zone_radius_factor", &S::zone_radius_factor, 0, 100, "",
                    "a contact loads the blocks within this × mean block edge of it (at least the nearest)"),
        opt::integer("ramp_steps", &S::ramp_steps, 1, 1'000'000'000, "relaxation steps over which the load grows to full"),
        opt::number("damping", &S::damping, 0, 0.99, "", "local (non-viscous) damping coefficient of the relaxation"),
        opt::number("mass_factor", &S::mass_factor, 0.3, 1e6, "",
                    "fictitious block mass / its stiffness row sum (dynamic relaxation; < 0.5 may be unstable)"),
        opt::positive_below("rest_tolerance", &S::rest_tolerance, 1, false, "",
                            "at rest when the largest out-of-balance force ≤ this × the largest block load"),
        opt::integer("post_split_steps", &S::post_split_steps, 0, 1'000'000'000, "steps after the first split (load held)"),
        opt::integer("quiet_steps", &S::quiet_steps, 1, 1'000'000'000,
                     "at full load, intact once no beam has broken for this many steps (loose blocks never rest)"),
        opt::integer("max_steps", &S::max_steps, 1, 1'000'000'000, "steps per analysis at most (outcome step_limit)"),
        opt::integer("check_interval", &S::check_interval, 1, 1'000'000, "steps between connectivity and rest checks"),
        opt::number("min_child_fraction", &S::min_child_fraction, 0, 0.5, "",
                    "smaller block sets (by volume) are fines, attached to the nearest piece"),
    };
  }();
  return t;
}

BbOptions bb_options_from_config(const Config& cfg) {
  cfg.string("type", "block_beam");
  BbOptions o;
  read_options(cfg, block_beam_options(), o);
  return o;
}

void validate(const BbOptions& o) {
  // Every option in its declared range (block_beam_options).
  check_options(block_beam_options(), o, "block_beam");
}

TetMesh bb_mesh(const Shape& shape, const BbOptions& o) {
  require(shape.dimension() == 3, "needs a 3D shape, got " + shape.describe());
  const double d = shape.equivalent_diameter();
  TetMeshOptions mo;
  mo.edge = d / o.blocks_per_diameter;
  mo.facet_distance = o.facet_distance * mo.edge;
  if (mo.facet_distance == 0) mo.facet_distance = mo.edge / 10;
  return tetrahedralise([&shape](const Vec3& p) { return shape.signed_distance(p); }, 1.02 * shape.bounding_radius(),
                        mo);
}

// ---------------------------------------------------------------- the model

BlockBeamModel::BlockBeamModel(BbOptions o) : o_(std::move(o)) { validate(o_); }

ScreeningSettings BlockBeamModel::default_screening() const {
  ScreeningSettings s;
  s.force_threshold = true;
  s.min_contacts = 2;
  return s;
}

void BlockBeamModel::assign_strength(Grain& g, const Material&, Rng& rng) const {
  require(g.shape != nullptr, "grain without a shape");
  double factor = 1;
  if (o_.weibull_modulus > 0) {
    // Weibull factor of mean 1: (−ln(1 − U))^(1/m) / Γ(1 + 1/m).
    const double u = rng.uniform();
    factor = std::pow(-std::log1p(-u), 1.0 / o_.weibull_modulus) / std::tgamma(1.0 + 1.0 / o_.weibull_modulus);
    factor = std::max(factor, 1e-6);
  }
  const double d = g.shape->equivalent_diameter();
  g.strength.set(kTensile, o_.tensile_strength * factor);
  g.strength.set(kShear, o_.shear_strength * factor);
  g.strength.set(kThreshold, o_.threshold_factor * o_.tensile_strength * factor * d * d);
}

void BlockBeamModel::inherit_strength(const Grain& parent, Grain& child, const Material&, Rng&) const {
  require(parent.shape && child.shape, "grain without a shape");
  const double t = parent.strength.get_or(kTensile, 0), s = parent.strength.get_or(kShear, 0);
  require(t > 0 && s > 0, "parent grain has no block–beam strength");
  const double d = child.shape->equivalent_diameter();
  child.strength.set(kTensile, t);
  child.strength.set(kShear, s);
  child.strength.set(kThreshold, o_.threshold_factor * t * d * d);
}

double BlockBeamModel::load_measure(const Grain&, const Material&, std::span<const Contact> contacts) const {
  double f = 0;
  for (const auto& c : contacts)
    if (is_finite(c.force)) f = std::max(f, norm(c.force));
  return f;
}

// ---------------------------------------------------------------- the analysis

namespace {

// Contact zones: blocks within zone_radius_factor × mean edge of the contact point (at
// least the nearest); the zone of the largest force is fixed, the others share their load.
void load_zones(bb::BbSystem& sys, const bb::Blocks& B, const std::vector<BodyLoad>& loads, double zone_radius_factor) {
  const int blocks = static_cast<int>(B.centroid.size());
  const std::size_t largest = largest_load(loads);
  const double zr2 = std::pow(zone_radius_factor * B.mean_edge, 2);
  for (std::size_t k = 0; k < loads.size(); ++k) {
    std::vector<int> zone;
    int nearest = 0;
    double best = std::numeric_limits<double>::infinity();
    for (int i = 0; i < blocks; ++i) {
      const double d2 = norm2(B.centroid[i] - loads[k].point);
      if (d2 <= zr2) zone.push_back(i);
      if (d2 < best) {
        best = d2;
        nearest = i;
      }
    }
    if (zone.empty()) zone.push_back(nearest);
    for (int i : zone) {
      if (k == largest)
        sys.fix(i);
      else
        sys.add_load(i, loads[k].force * (1.0 / static_cast<double>(zone.size())));
    }
  }
}

// Volume of each of the `count` connected block sets.
std::vector<double> component_volumes(const bb::Blocks& B, const std::vector<int>& label, int count) {
  std::vector<double> vol(count, 0.0);
  for (std::size_t i = 0; i < label.size(); ++i) vol[label[i]] += B.volume[i];
  return vol;
}

double sum_volume(const bb::Blocks& B) {
  double total_volume = 0;
  for (double v : B.volume) total_volume += v;
  return total_volume;
}

struct Relaxation {
  std::string outcome = "step_limit";
  bool split = false;
  long steps = 0;
  double lambda_at_split = 0;  // the load factor when the grain split
};

// Relaxation under a linear ramp of the load factor, then held, until two major block sets
// part (then post_split_steps more), the blocks rest, or max_steps.
Relaxation relax(bb::BbSystem& sys, const bb::Blocks& B, const BbOptions& o) {
  const double total_volume = sum_volume(B);
  Relaxation r;
  long split_step = -1;
  double lambda = 0;
  long broken_seen = 0, last_break = 0;
  for (long n = 1; n <= o.max_steps; ++n) {
    if (split_step < 0) lambda = std::min(1.0, static_cast<double>(n) / static_cast<double>(o.ramp_steps));
    if (sys.step(lambda, o.damping) > 0) last_break = n;
    r.steps = n;
    if (split_step >= 0) {
      if (n - split_step >= o.post_split_steps) break;
      continue;
    }
    if (n % o.check_interval != 0) continue;
    if (sys.broken() != broken_seen) {
      broken_seen = sys.broken();
      int count = 0;
      const auto label = bb::components(B, sys.broken_flags(), &count);
      int majors = 0;
      for (double v : component_volumes(B, label, count)) majors += v >= o.min_child_fraction * total_volume;
      if (count >= 2 && majors >= 2) {
        r.split = true;
        split_step = n;
        r.lambda_at_split = lambda;
        r.outcome = "split";
        if (o.post_split_steps == 0) break;
        continue;
      }
    }
    if (lambda >= 1.0 && (sys.unbalance() <= o.rest_tolerance || n - std::max(last_break, o.ramp_steps) >= o.quiet_steps)) {
      r.outcome = "intact";
      break;
    }
  }
  return r;
}

// The piece of every block: connected block sets at least min_child_fraction of the volume,
// largest first; fines join the nearest major piece. Sets `pieces` (< 2: no split).
std::vector<int> block_pieces(const bb::Blocks& B, const std::vector<char>& broken, double min_child_fraction,
                              int& pieces) {
  const int blocks = static_cast<int>(B.centroid.size());
  int count = 0;
  const auto label = bb::components(B, broken, &count);
  const std::vector<double> vol = component_volumes(B, label, count);
  std::vector<int> order(count);
  for (int c = 0; c < count; ++c) order[c] = c;
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return vol[x] > vol[y]; });
  std::vector<int> major_of(count, -1);
  pieces = 0;
  const double total_volume = sum_volume(B);
  for (int c : order)
    if (vol[c] >= min_child_fraction * total_volume) major_of[c] = pieces++;
  std::vector<int> piece(blocks, -1);
  if (pieces < 2) return piece;
  for (int i = 0; i < blocks; ++i) piece[i] = major_of[label[i]];
  std::vector<std::vector<int>> members(count);
  for (int i = 0; i < blocks; ++i)
    if (piece[i] < 0) members[label[i]].push_back(i);
  for (int c = 0; c < count; ++c) {
    if (members[c].empty()) continue;
    double best = std::numeric_limits<double>::infinity();
    int target = -1;
    for (int i : members[c])
      for (int j = 0; j < blocks; ++j) {
        if (major_of[label[j]] < 0) continue;
        const double d2 = norm2(B.centroid[j] - B.centroid[i]);
        if (d2 < best || (d2 == best && major_of[label[j]] < target)) {
          best = d2;
          target = major_of[label[j]];
        }
      }
    for (int i : members[c]) piece[i] = target;
  }
  return piece;
}

// The fracture of the split grain (see BlockBeamModel::analyse in the header).
PointClusters piece_clusters(const bb::Blocks& B, const std::vector<int>& piece, int pieces,
                             const std::vector<char>& broken) {
  const int blocks = static_cast<int>(B.centroid.size());
  PointClusters pc;
  pc.spacing = B.mean_edge;
  pc.clusters = pieces;
  pc.fracture_points.assign(pieces, {});
  // Per piece a copy of its blocks' vertices (the piece's surface for the alpha shape) and
  // its block centroids (so a nearest-point partition assigns the interior right).
  std::vector<std::map<int, char>> verts(pieces);
  for (int i = 0; i < blocks; ++i)
    for (int v : B.mesh.tets[i]) verts[piece[i]].emplace(v, 1);
  for (int c = 0; c < pieces; ++c) {
    for (const auto& [v, unused] : verts[c]) {
      pc.points.push_back(B.mesh.vertices[v]);
      pc.cluster.push_back(c);
      pc.on_surface.push_back(B.mesh.on_boundary[v]);
    }
  }
  for (int i = 0; i < blocks; ++i) {
    pc.points.push_back(B.centroid[i]);
    pc.cluster.push_back(piece[i]);
    pc.on_surface.push_back(0);
  }
  // Fracture points: centroid and vertices of each broken face between two pieces.
  for (std::size_t k = 0; k < B.beams.size(); ++k) {
    if (!broken[k]) continue;
    const auto& bmk = B.beams[k];
    const int ca = piece[bmk.a], cb = piece[bmk.b];
    if (ca == cb) continue;
    for (int c : {ca, cb}) {
      pc.fracture_points[c].push_back(bmk.face_centroid);
      for (int v : B.faces[bmk.face].vertices) pc.fracture_points[c].push_back(B.mesh.vertices[v]);
    }
  }
  return pc;
}

}  // namespace

BreakageAnalysis BlockBeamModel::analyse(const Grain& g, const Material& m, std::span<const Contact> contacts) const {
  const auto t0 = Clock::now();
  BreakageAnalysis a;
  long blocks = 0, beams = 0, steps = 0, broken_beams = 0;
  double force_at_split = 0;
  auto finish = [&](const std::string& outcome) {
    a.outcome = outcome;
    a.figures = {{"blocks", static_cast<double>(blocks)},
                 {"beams", static_cast<double>(beams)},
                 {"steps", static_cast<double>(steps)},
                 {"broken_beams", static_cast<double>(broken_beams)},
                 {"force_at_split_N", force_at_split}};
    a.wall_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    return a;
  };
  require(g.shape != nullptr, "grain " + std::to_string(g.id) + " has no shape");
  require(g.shape->dimension() == 3, "needs a 3D grain, got " + g.shape->describe());
  const double tensile = g.strength.get_or(kTensile, 0), shear = g.strength.get_or(kShear, 0);
  require(tensile > 0 && shear > 0 && std::isfinite(tensile) && std::isfinite(shear),
          "grain " + std::to_string(g.id) + " has no beam strength (assign_strength not called?)");
  require(m.young > 0 && m.poisson > -1 && m.poisson < 0.5, "material needs young > 0 and poisson in (-1, 0.5)");
  const std::vector<BodyLoad> loads = body_frame_loads(g, contacts, "block_beam");
  for (const auto& l : loads) a.load = std::max(a.load, norm(l.force));
  if (loads.size() < 2) return finish("no_load");

  // Blocks and beams (Liu et al. 2019 §2.1, §2.3).
  // A shape the mesher cannot fill (or a degenerate block) is an outcome, not an error: the
  // grain stays as it is and the run goes on.
  bb::Blocks B;
  try {
    B = bb::make_blocks(bb_mesh(*g.shape, o_));
  } catch (const std::runtime_error&) {
    return finish("mesh_failed");
  } catch (const std::invalid_argument&) {
    return finish("mesh_failed");
  }
  blocks = static_cast<long>(B.centroid.size());
  beams = static_cast<long>(B.beams.size());
  if (blocks < o_.min_blocks) return finish("too_few_blocks");
  bb::BeamMaterial bm{m.young, m.young / (2 * (1 + m.poisson)), tensile, shear};
  bb::BbSystem sys(B, bm, o_.mass_factor);
  load_zones(sys, B, loads, o_.zone_radius_factor);
  const Relaxation r = relax(sys, B, o_);
  steps = r.steps;
  if (r.split) force_at_split = r.lambda_at_split * a.load;
  broken_beams = sys.broken();
  if (!r.split) return finish(r.outcome);
  int pieces = 0;
  const std::vector<int> piece = block_pieces(B, sys.broken_flags(), o_.min_child_fraction, pieces);
  if (pieces < 2) return finish("split_into_fines");
  a.broken = true;
  a.fracture = piece_clusters(B, piece, pieces, sys.broken_flags());
  return finish("split");
}

std::unique_ptr<BreakageModel> make_block_beam(const Config& cfg, const EngineContext& ctx) {
  if (ctx.dimension != 3) cfg.fail("type", "block_beam needs a 3D scenario (Liu et al. 2019 meshes tetrahedra)");
  return std::make_unique<BlockBeamModel>(bb_options_from_config(cfg));
}

}  // namespace crumble
