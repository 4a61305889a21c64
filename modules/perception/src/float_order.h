// Floats in their order (internal to the perception module): thresholds on floats equivalent to
// a test the plain implementations run in double or after a sqrt, so that a fast loop compares
// floats and keeps exactly the same points (virtual_scans.cpp, fspf_plus.cpp); the vector clones
// of the loops that vectorise.
#pragma once

#include <cstdint>
#include <cstring>

/** Marks a loop-heavy function to be compiled three times, for AVX-512F (16 floats a
 *  vector), AVX2 (8) and the baseline x86-64, the loader choosing by the CPU (GCC / Clang
 *  function multi-versioning on x86-64 Linux). Neither target enables FMA: each element gets
 *  the same operations, hence the same result, in all three. */
#if defined(__x86_64__) && defined(__linux__) && defined(__has_attribute) && !defined(__AVX2__)
#if __has_attribute(target_clones)
#define CARENAV_VECTOR_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#endif
#endif
#ifndef CARENAV_VECTOR_CLONES
#define CARENAV_VECTOR_CLONES
#endif

namespace carenav::perception::detail {

/** The float as an unsigned integer in the same order (-0 just below +0; NaN outside). */
inline uint32_t floatKey(float f) {
  uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}
inline float keyFloat(uint32_t k) {
  const uint32_t u = (k & 0x80000000u) ? (k & 0x7fffffffu) : ~k;
  float f;
  std::memcpy(&f, &u, sizeof f);
  return f;
}

/** The float nearest to `outside` for which `in` holds, given in(inside), !in(outside) and `in`
 *  monotone between them (bisection over the float order: 32 steps at most). */
template <class In>
float lastInside(float inside, float outside, In in) {
  uint32_t a = floatKey(inside), b = floatKey(outside);
  while ((a > b ? a - b : b - a) > 1) {
    const uint32_t m = a < b ? a + (b - a) / 2 : b + (a - b) / 2;
    (in(keyFloat(m)) ? a : b) = m;
  }
  return keyFloat(a);
}

}  // namespace carenav::perception::detail
