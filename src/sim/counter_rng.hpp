#pragma once
// Counter-based randomness: a value is a pure function of (seed, stream,
// index), never the state of a shared generator. The simulator's threads (the
// loop asking for encoder counts, the IMU thread asking for samples) can then
// ask in any order, any number of times, and get the same noise at the same
// sample, which is what makes a lockstep run bit-identical to the next one.
#include <cmath>
#include <cstdint>

namespace rtfuse::sim {

// The splitmix64 finaliser: a bijection on 64 bits with full avalanche.
constexpr std::uint64_t mix64(std::uint64_t x) noexcept {
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// Keys are folded in one at a time through the bijection, each scaled by a
// different odd constant, so (seed, stream, index) and its permutations land
// far apart.
constexpr std::uint64_t counter_hash(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) noexcept {
  std::uint64_t h = mix64(seed + 0x9E3779B97F4A7C15ULL);
  h = mix64(h ^ (stream * 0xD6E8FEB86659FD93ULL + 0x632BE59BD9B4E019ULL));
  return mix64(h ^ (index * 0xA0761D6478BD642FULL + 0xE7037ED1A0B428DBULL));
}

// Uniform in (0, 1): never 0, so log() is always finite.
constexpr double counter_uniform(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) noexcept {
  return (static_cast<double>(counter_hash(seed, stream, index) >> 11) + 0.5) * 0x1.0p-53;
}

// Standard normal by Box-Muller from two uniforms of the same stream
// (indices 2i and 2i+1), written out rather than std::normal_distribution
// so a seed gives the same numbers with any standard library.
inline double counter_normal(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) noexcept {
  constexpr double kTwoPi = 6.283185307179586476925;
  const double u1 = counter_uniform(seed, stream, 2 * index);
  const double u2 = counter_uniform(seed, stream, 2 * index + 1);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(kTwoPi * u2);
}

// Stream numbers: one per independent noise source, fixed forever so that a
// scenario's noise does not change when another source is added.
namespace stream {
constexpr std::uint64_t kWheelSlip = 0x100;  // + wheel index
constexpr std::uint64_t kGyro = 0x200;       // + axis
constexpr std::uint64_t kAccel = 0x300;      // + axis
constexpr std::uint64_t kGnss = 0x400;       // + 0..2 bias axes, 3..5 noise axes, 6..8 multipath
constexpr std::uint64_t kGyroVibration = 0x500;   // + axis
constexpr std::uint64_t kAccelVibration = 0x600;  // + axis
}  // namespace stream

}  // namespace rtfuse::sim
