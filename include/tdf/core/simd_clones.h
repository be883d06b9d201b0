#pragma once
/// TDF_SIMD_CLONES: compiles a function once per instruction set of the build's TDF_SIMD_CLONES
/// list (CMake cache variable; default AVX-512, AVX2 and the x86-64 baseline) and picks one at
/// load time for the CPU it runs on (GCC target_clones). For the lanes loops that vectorise
/// (shade_lanes, the paired texture lookups). Each such function must give the same bits in every
/// clone (no FMA contraction in its file: src/CMakeLists.txt); a build configured with
/// -DTDF_SIMD_CLONES="avx2;default" runs the AVX2 clones on an AVX-512 machine, so that their
/// bits and speed can be checked there (docs/measurements.md, "Rendering cost").
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#ifndef TDF_SIMD_CLONE_LIST
#define TDF_SIMD_CLONE_LIST "avx512f", "avx2", "default"
#endif
#define TDF_SIMD_CLONES __attribute__((target_clones(TDF_SIMD_CLONE_LIST)))
#else
#define TDF_SIMD_CLONES
#endif
