#pragma once

#include <cstddef>

// The fits' hot loops are built twice, for baseline x86-64 (2-wide SSE2) and for x86-64-v3
// (4-wide AVX2), and the loader picks one for the CPU it runs on (GCC's target_clones): a
// portable binary that still uses the wide vectors of the machine in front of it.
// Both builds must give the same bits, or a refit on one machine would not reproduce the live
// fit of another: the files with such loops are compiled with -ffp-contract=off (no FMA in the
// AVX2 build; core/CMakeLists.txt), and their sums go through Lanes below, never through an
// `omp simd reduction`, whose partial sums follow the vector width (a max, exact in any order,
// may stay one).
// Not for sanitizer builds (their runtime starts after the clone is chosen) or other compilers.
// -DSPINDOWN_VECTOR_CLONES= builds the baseline alone (to check that both give the same bits).
#ifndef SPINDOWN_VECTOR_CLONES
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(__SANITIZE_ADDRESS__) && \
    !defined(__SANITIZE_THREAD__)
#define SPINDOWN_VECTOR_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define SPINDOWN_VECTOR_CLONES
#endif
#endif

namespace spindown {

// K sums over a range of samples kept in four lanes (sample i adds to lane i mod 4 counted from
// the range's start) and combined in one fixed order: the same rounding whatever vector width
// the compiler gives the loop. for_each_in_lanes(lo, hi, body) calls body(i, lane) for every
// sample; the body adds to sum[k][lane].
template <std::size_t K>
struct Lanes {
  static constexpr std::size_t count = 4;
  double sum[K][count] = {};
  double total(std::size_t k) const { return (sum[k][0] + sum[k][1]) + (sum[k][2] + sum[k][3]); }
};

// The loop and its body must be inlined into each build of the caller for the lane loop to be
// vectorised for that CPU: GCC will not inline a large lambda by itself.
#if defined(__GNUC__)
#define SPINDOWN_LANE_BODY __attribute__((always_inline))
#else
#define SPINDOWN_LANE_BODY
#endif

template <class Body>
SPINDOWN_LANE_BODY inline void for_each_in_lanes(std::size_t lo, std::size_t hi, Body&& body) {
  constexpr std::size_t lanes = 4;
  std::size_t i = lo;
  for (; i + lanes <= hi; i += lanes) {
#pragma omp simd
    for (std::size_t lane = 0; lane < lanes; ++lane) body(i + lane, lane);
  }
  for (std::size_t lane = 0; i < hi; ++i, ++lane) body(i, lane);
}

}  // namespace spindown
