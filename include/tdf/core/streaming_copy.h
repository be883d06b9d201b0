#pragma once
/// Copies for output that is written once and not read again soon (a rendered frame): the
/// stores bypass the cache, so they neither read each destination line first nor evict the
/// working set. Call streaming_fence() before another thread may read what was written.
#include <algorithm>
#include <cstddef>
#include <cstdint>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace tdf {

/// Copies `count` floats from `from` to `to` (non-overlapping).
inline void copy_streaming(const float* from, std::size_t count, float* to) {
#if defined(__SSE2__)
    // Non-temporal stores take whole 16-byte-aligned vectors; anything else is copied normally.
    if ((reinterpret_cast<std::uintptr_t>(to) & 15u) == 0 && count % 4 == 0) {
        for (std::size_t i = 0; i < count; i += 4) _mm_stream_ps(to + i, _mm_loadu_ps(from + i));
        return;
    }
#endif
    std::copy_n(from, count, to);
}

/// Orders the streaming stores before any later store (they are weakly ordered).
inline void streaming_fence() {
#if defined(__SSE2__)
    _mm_sfence();
#endif
}

}  // namespace tdf
