#pragma once

// The one seeded random draw of every fault layer (input faults, wire
// faults, scenarios): splitmix64 (Steele, Lea, Flood, "Fast splittable
// pseudorandom number generators", 2014) of (seed, index), stateless, so a
// draw depends only on the seed and the event's position — a scenario
// replays identically. No allocation, no throw: safe in the cyclic path.

#include <cstdint>

namespace rise::hil::io {

constexpr uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

/// 64 random bits from (seed, index).
constexpr uint64_t seeded_bits(uint64_t seed, uint64_t index) {
  return splitmix64(splitmix64(seed) ^ (index * 0xd1b54a32d192ed03ull));
}

/// A uniform number in [0, 1) from (seed, index): the top 53 bits.
constexpr double seeded_uniform(uint64_t seed, uint64_t index) {
  return static_cast<double>(seeded_bits(seed, index) >> 11) * 0x1.0p-53;
}

}  // namespace rise::hil::io
