// texture_lanes.h's kernel with AVX-512 gathers, 16 lanes (compiled with -mavx512f: called only
// where the CPU has it).
#include "texture_lanes.h"

#if defined(__AVX512F__)
#include <immintrin.h>

namespace tdf::texture_lanes {
namespace {

struct Avx512 {
    static constexpr int kLanes = 16;
    using F = __m512;
    using I = __m512i;
    using M = __mmask16;
    static void store_lanes(float* p, M m, F x) { _mm512_mask_storeu_ps(p, m, x); }
    static void storei(int* p, I x) { _mm512_store_si512(p, x); }
    static F loadu(const float* p) { return _mm512_loadu_ps(p); }
    static F set(float x) { return _mm512_set1_ps(x); }
    static I seti(int x) { return _mm512_set1_epi32(x); }
    static F add(F a, F b) { return _mm512_add_ps(a, b); }
    static F sub(F a, F b) { return _mm512_sub_ps(a, b); }
    static F mul(F a, F b) { return _mm512_mul_ps(a, b); }
    static F min(F a, F b) { return _mm512_min_ps(a, b); }
    static F floor(F x) { return _mm512_roundscale_ps(x, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC); }
    static I cvtt(F x) { return _mm512_cvttps_epi32(x); }
    static F cvt(I x) { return _mm512_cvtepi32_ps(x); }
    static I addi(I a, I b) { return _mm512_add_epi32(a, b); }
    static I subi(I a, I b) { return _mm512_sub_epi32(a, b); }
    static I muli(I a, I b) { return _mm512_mullo_epi32(a, b); }
    static M gt(F a, F b) { return _mm512_cmp_ps_mask(a, b, _CMP_GT_OQ); }
    static M ge(F a, F b) { return _mm512_cmp_ps_mask(a, b, _CMP_GE_OQ); }
    static M le(F a, F b) { return _mm512_cmp_ps_mask(a, b, _CMP_LE_OQ); }
    static M lti(I a, I b) { return _mm512_cmplt_epi32_mask(a, b); }
    static M eqi(I a, I b) { return _mm512_cmpeq_epi32_mask(a, b); }
    static M mask_and(M a, M b) { return M(a & b); }
    static M none() { return 0; }
    static M mask_or(M a, M b) { return M(a | b); }
    static M mask_andnot(M a, M b) { return M(~a & b); }  // b without a
    static bool any(M m) { return m != 0; }
    static bool covers(M m, M lanes) { return (m & lanes) == lanes; }  // every lane of `lanes` is in m
    static unsigned bits(M m) { return m; }
    static int first(M m) { return __builtin_ctz(unsigned(m)); }
    static F select(M m, F a, F b) { return _mm512_mask_blend_ps(m, b, a); }
    static I selecti(M m, I a, I b) { return _mm512_mask_blend_epi32(m, b, a); }
    static F gather(M m, const float* base, I index) {
        return _mm512_mask_i32gather_ps(_mm512_setzero_ps(), m, index, base, 4);
    }
};

#include "texture_lanes_impl.h"

}  // namespace

void sample_pairs_avx512(PairLookups& q) { sample_pairs<Avx512>(q); }

}  // namespace tdf::texture_lanes
#endif
