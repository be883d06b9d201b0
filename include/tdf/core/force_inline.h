#pragma once
/// TDF_FORCE_INLINE: inline even where the compiler's heuristics would not, for small helpers of
/// inner loops whose call would cost more than their body (texture blends, the shading lanes:
/// each target_clones clone must inline them to be compiled for its own instructions).
#if defined(__GNUC__)
#define TDF_FORCE_INLINE inline __attribute__((always_inline))
#else
#define TDF_FORCE_INLINE inline
#endif
