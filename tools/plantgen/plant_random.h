// A small deterministic PRNG for the plant generator.
//
// std::uniform_*_distribution output differs between standard libraries, so the generator uses
// SplitMix64 and its own range mapping: the same seed gives byte-identical plants everywhere.
#pragma once

#include <cstdint>

namespace tw::plant {

class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed) {}

  // Independent stream for sub-part `salt` of the thing this generator seeds (a module, a line),
  // so that generating one part never shifts the random numbers of another.
  static Random derive(uint64_t seed, uint64_t salt) {
    Random r(seed ^ (salt * 0xd1342543de82ef95ull + 0x2545f4914f6cdd1dull));
    r.next();
    return r;
  }

  uint64_t next() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1), from the top 24 bits so every value is exact in float.
  float uniform() { return static_cast<float>(next() >> 40) * (1.0f / 16777216.0f); }
  float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }
  // Uniform integer in [0, n) for n > 0 (the tiny modulo bias is irrelevant here).
  uint32_t below(uint32_t n) { return static_cast<uint32_t>(next() % n); }
  bool chance(float p) { return uniform() < p; }

 private:
  uint64_t state_;
};

}  // namespace tw::plant
