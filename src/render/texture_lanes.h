#pragma once
// The renderer's paired trilinear lookups (MipTexture::sample_trilinear_pairs, RGB albedo and
// RGB tactile map) a vector of points at a time with gather instructions: AVX-512 (16 lanes) or
// AVX2 (8), each in its own file compiled for that instruction set and called only where the CPU
// has it (texture.cpp). A group of lanes is done in vector form when all its covered points
// read the same mip level and their footprints need no wrapping beyond one texel (UVs in
// [0, 1], the atlas's); any other group is left to the scalar code. Every lane computes
// sample_pair's operations in its order (no FMA contraction), so the bits are the scalar ones.
//
// This header declares plain data and functions only: the files compiled for AVX-512 and AVX2
// must not instantiate inline functions that the rest of the program shares (the linker would
// keep one of the copies, possibly the AVX-512 one, for every caller).
#include <cstddef>
#include <cstdint>

namespace tdf::texture_lanes {

// One mip level of both maps (3 floats a texel, row-major).
struct PairLevel {
    const float* a;
    const float* b;
    int width;
    int height;
};

struct PairLookups {
    std::size_t n = 0;
    const float* covered = nullptr;  ///< n: > 0 where a point is looked up
    const float* u = nullptr;        ///< n: each point's UV, v up
    const float* v = nullptr;
    const float* lod = nullptr;  ///< n: each covered point's LOD, not yet clamped
    const PairLevel* levels = nullptr;
    int top = 0;                    ///< the highest level a lookup may read (max_level applied)
    float* out_a = nullptr;         ///< channel k of point i at out_a[k * plane + i]
    float* out_b = nullptr;         ///< likewise
    std::size_t plane = 0;
    std::uint32_t* left = nullptr;  ///< n of room: the covered points left to the scalar code
    std::size_t left_count = 0;
};

// Each covered point's texels of both maps, or its index in `left`.
void sample_pairs_avx512(PairLookups& q);
void sample_pairs_avx2(PairLookups& q);

}  // namespace tdf::texture_lanes
