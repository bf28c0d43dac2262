/* -----------------------------------------------------------------------------
 * Linear stability of the conditionally explicit methods (method.md section 4).
 *
 * The amplification matrix is built from CEODE's own step applied to the test
 * equation x'' + 2 xi Omega x' + Omega^2 x = 0 with h = 1, so the analysis and the
 * integrator cannot disagree.
 * ---------------------------------------------------------------------------*/
#ifndef CEODE_CEODE_STABILITY_H_
#define CEODE_CEODE_STABILITY_H_

#include <sundials/sundials_types.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Spectral radius of the d x d amplification matrix at Omega = omega*h. */
SUNDIALS_EXPORT int CEodeSpectralRadius(int degree, const sunrealtype* params, sunrealtype Omega,
                                        sunrealtype xi, sunrealtype* rho);

/* Largest Omega with rho <= 1 on all of (0, Omega]; 0 when unstable for every step. */
SUNDIALS_EXPORT int CEodeStabilityLimit(int degree, const sunrealtype* params, sunrealtype xi,
                                        sunrealtype* Omega_max);

/* Writes the amplification matrix (row-major, degree*degree entries). */
SUNDIALS_EXPORT int CEodeAmplificationMatrix(int degree, const sunrealtype* params,
                                             sunrealtype Omega, sunrealtype xi, sunrealtype* A);

#ifdef __cplusplus
}
#endif

#endif /* CEODE_CEODE_STABILITY_H_ */
