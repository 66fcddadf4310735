#pragma once
#include <cstdint>
#include <random>

namespace crumble {

// The one seeded generator of a run (deterministic for a seed). Per-grain streams are
// derived from (seed, grain id) so results do not depend on evaluation order or threads.
class Rng {
 public:
  explicit Rng(std::uint64_t seed = 1) : seed_(seed), gen_(seed) {}
  double uniform() { return std::uniform_real_distribution<double>(0.0, 1.0)(gen_); }
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(gen_); }
  double normal(double m, double s) { return std::normal_distribution<double>(m, s)(gen_); }
  std::uint64_t seed() const { return seed_; }
  std::mt19937_64& engine() { return gen_; }
  // Independent stream for an item, stable across thread counts.
  Rng derive(std::uint64_t key) const {
    std::uint64_t z = seed_ + 0x9E3779B97F4A7C15ull * (key + 1);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return Rng(z ^ (z >> 31));
  }

 private:
  std::uint64_t seed_;
  std::mt19937_64 gen_;
};

}  // namespace crumble
