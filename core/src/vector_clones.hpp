#pragma once

// The fits' hot loops are built twice, for baseline x86-64 (2-wide SSE2) and for x86-64-v3
// (4-wide AVX2), and the loader picks one for the CPU it runs on (GCC's target_clones): a
// portable binary that still uses the wide vectors of the machine in front of it. spindown is
// compiled as ISO C++ (no fp-contract), so no FMA is formed and every operation rounds the same
// way in both; only the order in which a vectorised sum adds its lanes differs.
// Not for sanitizer builds (their runtime starts after the clone is chosen) or other compilers.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(__SANITIZE_ADDRESS__) && \
    !defined(__SANITIZE_THREAD__)
#define SPINDOWN_VECTOR_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define SPINDOWN_VECTOR_CLONES
#endif
