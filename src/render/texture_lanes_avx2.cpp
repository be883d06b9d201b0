// texture_lanes.h's kernel with AVX2 gathers, 8 lanes (compiled with -mavx2: called only where
// the CPU has it).
#include "texture_lanes.h"

#if defined(__AVX2__)
#include <immintrin.h>

namespace tdf::texture_lanes {
namespace {

struct Avx2 {
    static constexpr int kLanes = 8;
    using F = __m256;
    using I = __m256i;
    using M = __m256;  // all ones in a lane that is set
    static void store_lanes(float* p, M m, F x) { _mm256_maskstore_ps(p, _mm256_castps_si256(m), x); }
    static void storei(int* p, I x) { _mm256_store_si256(reinterpret_cast<__m256i*>(p), x); }
    static F loadu(const float* p) { return _mm256_loadu_ps(p); }
    static F set(float x) { return _mm256_set1_ps(x); }
    static I seti(int x) { return _mm256_set1_epi32(x); }
    static F add(F a, F b) { return _mm256_add_ps(a, b); }
    static F sub(F a, F b) { return _mm256_sub_ps(a, b); }
    static F mul(F a, F b) { return _mm256_mul_ps(a, b); }
    static F min(F a, F b) { return _mm256_min_ps(a, b); }
    static F floor(F x) { return _mm256_floor_ps(x); }
    static I cvtt(F x) { return _mm256_cvttps_epi32(x); }
    static F cvt(I x) { return _mm256_cvtepi32_ps(x); }
    static I addi(I a, I b) { return _mm256_add_epi32(a, b); }
    static I subi(I a, I b) { return _mm256_sub_epi32(a, b); }
    static I muli(I a, I b) { return _mm256_mullo_epi32(a, b); }
    static M gt(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
    static M ge(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_GE_OQ); }
    static M le(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_LE_OQ); }
    static M lti(I a, I b) { return _mm256_castsi256_ps(_mm256_cmpgt_epi32(b, a)); }
    static M eqi(I a, I b) { return _mm256_castsi256_ps(_mm256_cmpeq_epi32(a, b)); }
    static M mask_and(M a, M b) { return _mm256_and_ps(a, b); }
    static M none() { return _mm256_setzero_ps(); }
    static M mask_or(M a, M b) { return _mm256_or_ps(a, b); }
    static M mask_andnot(M a, M b) { return _mm256_andnot_ps(a, b); }  // b without a
    static bool any(M m) { return _mm256_movemask_ps(m) != 0; }
    static bool covers(M m, M lanes) { return (_mm256_movemask_ps(m) & bits(lanes)) == bits(lanes); }
    static unsigned bits(M m) { return unsigned(_mm256_movemask_ps(m)); }
    static int first(M m) { return __builtin_ctz(bits(m)); }
    static F select(M m, F a, F b) { return _mm256_blendv_ps(b, a, m); }
    static I selecti(M m, I a, I b) {
        return _mm256_castps_si256(_mm256_blendv_ps(_mm256_castsi256_ps(b), _mm256_castsi256_ps(a), m));
    }
    static F gather(M m, const float* base, I index) {
        return _mm256_mask_i32gather_ps(_mm256_setzero_ps(), base, index, m, 4);
    }
};

#include "texture_lanes_impl.h"

}  // namespace

void sample_pairs_avx2(PairLookups& q) { sample_pairs<Avx2>(q); }

}  // namespace tdf::texture_lanes
#endif
