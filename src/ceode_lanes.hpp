// Entry-wise arithmetic on one value, on a pair (SSE2) or on four entries (AVX, in the entries
// compiled for it): the same IEEE operations per entry at every width, so that a loop over
// vectors with a scalar tail gives the scalar loop's values bit for bit. The serial kernels of
// the fixed step and of the adaptive step's pass after f share these.
#ifndef CEODE_LANES_HPP
#define CEODE_LANES_HPP

#include <cmath>
#include <cstring>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <sundials/sundials_types.h>

namespace ceode {

inline sunrealtype Load(const sunrealtype* p, sunrealtype /*tag*/) { return *p; }
inline void Store(sunrealtype* p, sunrealtype v) { *p = v; }
inline sunrealtype Abs(sunrealtype v) { return std::fabs(v); }
inline sunrealtype Splat(sunrealtype c, sunrealtype /*tag*/) { return c; }

#if defined(__SSE2__) && defined(SUNDIALS_DOUBLE_PRECISION)
using Pair =
    double __attribute__((vector_size(16)));  // __m128d without may_alias: a template argument
inline Pair Load(const sunrealtype* p, Pair /*tag*/) { return _mm_loadu_pd(p); }
inline void Store(sunrealtype* p, Pair v) { _mm_storeu_pd(p, v); }
// |v| as v & mask: v's register is free afterwards, so (unlike andnot with the sign, which
// overwrites the sign) the constant needs no copy per use.
inline Pair Abs(Pair v) {
  return _mm_and_pd(v, _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL)));
}
inline Pair Splat(sunrealtype c, Pair /*tag*/) { return _mm_set1_pd(c); }
#endif

#if defined(__GNUC__) && defined(__SSE2__) && (defined(__x86_64__) || defined(__i386__)) && \
    defined(SUNDIALS_DOUBLE_PRECISION)
#define CEODE_AVX 1
// Four entries in AVX's 256-bit registers, in generic vector operations. Every function that
// takes or returns one is inlined (always_inline) into a target("avx") entry: out of line it
// would not be AVX code, and no call passes a 256-bit value (the ABI GCC warns of is never used).
#pragma GCC diagnostic ignored "-Wpsabi"
using Quad = double __attribute__((vector_size(32)));
using QuadBits = long long __attribute__((vector_size(32)));
__attribute__((always_inline)) inline Quad Load(const sunrealtype* p, const Quad& /*tag*/) {
  Quad v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
__attribute__((always_inline)) inline void Store(sunrealtype* p, const Quad& v) {
  std::memcpy(p, &v, sizeof v);
}
__attribute__((always_inline)) inline Quad Abs(const Quad& v) {
  constexpr long long kMagnitude = 0x7fffffffffffffffLL;
  return reinterpret_cast<Quad>(reinterpret_cast<QuadBits>(v) &
                                QuadBits{kMagnitude, kMagnitude, kMagnitude, kMagnitude});
}
__attribute__((always_inline)) inline Quad Splat(sunrealtype c, const Quad& /*tag*/) {
  return Quad{c, c, c, c};
}
#endif

}  // namespace ceode

#endif  // CEODE_LANES_HPP
