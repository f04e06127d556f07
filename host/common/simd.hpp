#pragma once
// The CPU reference's vector code: functions compiled for AVX-512, AVX2 and the baseline, the
// loader picking the widest the machine has (GCC/Clang target_clones on x86-64 Linux), so the
// library stays one portable binary; and loops over SIMD lanes. The build has no FMA contraction
// (-ffp-contract=off), so each clone does the same operations in the same order: the same bits on
// any machine. Used by the element passes (elements/projections.hpp), L-BFGS's history passes
// (solver/lbfgs.cpp) and the rigid motions' two-level inverse (solver/rigid_modes.cpp).
#if defined(__x86_64__) && defined(__linux__) && (defined(__GNUC__) || defined(__clang__)) && \
    !defined(STABINT_NO_TARGET_CLONES)
#define STABINT_TARGET_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define STABINT_TARGET_CLONES
#endif
// Loops over the lanes of a group: vectorized as a whole (the compiler would otherwise unroll
// these short loops first and vectorize only parts of what is left). The library is built with
// -fopenmp-simd (the pragma only, no OpenMP runtime) and STABINT_OMP_SIMD; other code that
// includes this header (tests, benchmarks) gets plain loops.
#if defined(STABINT_OMP_SIMD)
#define STABINT_LANES _Pragma("omp simd")
#else
#define STABINT_LANES
#endif
// Clang (14) clones no function template: there, templates stay baseline code.
#if defined(__clang__)
#define STABINT_TARGET_CLONES_TEMPLATE
#else
#define STABINT_TARGET_CLONES_TEMPLATE STABINT_TARGET_CLONES
#endif

namespace stabint {

/// The sum of N lanes' partial sums (N a power of two) in a fixed tree: lane l + N/2 folded onto
/// lane l, then the same on the half, down to one. The same bits on any machine, for any clone.
template <int N>
inline double laneSum(const double* acc) {
  static_assert(N >= 1 && (N & (N - 1)) == 0, "a power of two");
  if constexpr (N == 1) {
    return acc[0];
  } else {
    double half[N / 2];
    for (int l = 0; l < N / 2; ++l) half[l] = acc[l] + acc[l + N / 2];
    return laneSum<N / 2>(half);
  }
}

}  // namespace stabint
