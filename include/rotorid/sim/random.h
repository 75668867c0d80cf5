#pragma once

// Portable random numbers for the simulator: the same seed gives the same numbers with any
// standard library. std::mt19937_64 is fully specified by the standard, but the distributions
// (std::normal_distribution, std::uniform_real_distribution) are not, so they are written here.

#include <cstdint>
#include <random>

namespace rotorid {

class RandomStream {
 public:
  // `stream` separates independent sequences drawn from one user seed (pilot, noise, jitter ...),
  // so that switching one feature on does not reshuffle the others.
  explicit RandomStream(std::uint64_t seed, std::uint64_t stream = 0);

  // Uniform in [0, 1) with 53 random bits.
  double Uniform();
  double Uniform(double low, double high) { return low + (high - low) * Uniform(); }
  // Standard normal by the Box-Muller transform (pairs, the second value is kept for the next call).
  double Normal();
  double Normal(double mean, double std) { return mean + std * Normal(); }

 private:
  std::mt19937_64 engine_;
  bool has_spare_normal_ = false;
  double spare_normal_ = 0.0;
};

}  // namespace rotorid
