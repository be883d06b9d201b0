#pragma once
// TDF_MULTIVERSION compiles a function twice, for AVX2 and for the x86-64 baseline, and picks
// one at load time (GCC target_clones). Only used on loops that are elementwise across points
// and keep every per-point sum in its order; since neither target contracts a*b+c into an FMA
// (the avx2 target has no FMA, and ISO C++ mode disables contraction), both versions give the
// same bits.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define TDF_MULTIVERSION __attribute__((target_clones("avx2", "default")))
#else
#define TDF_MULTIVERSION
#endif
