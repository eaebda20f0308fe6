// Stateless random numbers: every value is a hash of (pixel, sample, dimension, seed), so
// images never depend on thread count, tile order or crop (pbrt's approach).
#pragma once

#include <cstdint>

namespace bounce {

/// 64-bit finalizer (SplitMix64 / Stafford variant 13).
constexpr uint64_t mix64(uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

constexpr uint64_t hash_combine(uint64_t h, uint64_t v) { return mix64(h ^ (v + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2))); }

/// Uniform float in [0,1) from a 64-bit hash (24 high bits, so never rounds to 1).
constexpr float to_unit_float(uint64_t h) { return static_cast<float>(h >> 40) * (1.0f / 16777216.0f); }

/// Identifies one random stream: a key (pixel, record, ...) plus the seed.
/// `get(sample, dim)` is a pure function, safe from any thread.
class RandomStream {
  public:
    constexpr RandomStream(uint64_t seed, uint64_t key_a, uint64_t key_b = 0)
        : base_(hash_combine(hash_combine(mix64(seed + 0x5bd1e995ULL), key_a), key_b)) {}
    constexpr float get(uint64_t sample, uint32_t dim) const { return to_unit_float(hash_combine(hash_combine(base_, sample), dim)); }
    constexpr uint64_t bits(uint64_t sample, uint32_t dim) const { return hash_combine(hash_combine(base_, sample), dim); }

  private:
    uint64_t base_;
};

/// Dimension tags: each use of randomness has its own dimension so streams never collide.
enum Dim : uint32_t {
    kDimPixelX = 0,
    kDimPixelY = 1,
    kDimLensU = 2,  ///< depth of field: the subsample's point on the lens
    kDimLensV = 3,
    kDimTime = 4,                       ///< motion blur: the subsample's time in the shutter
    kDimTimeStratum = 5,                ///< motion blur: which time stratum each of a pixel's subsamples takes
    kDimLight = 10,                     ///< light i uses kDimLight + 16 i + (1, 2): far below kDimGather for any light count
    kDimLightPick = (1u << 30) - 4096,  ///< many lights: the k-th light picked at a point (DirectLighting)
    kDimGather = 1u << 30,              ///< the gather uses kDimGather + {0, 1, 3}
    kDimBackSide = (1u << 30) + 64,     ///< back_side_stream
};

/// The random stream of what a thin translucent surface takes in through its back side (its
/// direct light, its gathers), made from its front's: both sides are keyed by the same
/// pixel, fragment or hit, and the front's numbers are those of an opaque surface.
constexpr RandomStream back_side_stream(const RandomStream& front) { return RandomStream(front.bits(0, kDimBackSide), 1); }

}  // namespace bounce
