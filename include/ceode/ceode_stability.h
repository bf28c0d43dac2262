/* -----------------------------------------------------------------------------
 * Linear stability of the conditionally explicit methods (docs/theory.md section 9).
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

/* Largest Omega with rho <= 1 on all of (0, Omega]; 0 when unstable for every step.
 * |lambda| = 1 is judged with a per-eigenvalue rounding tolerance (about 1e-13 for
 * well-conditioned eigenvalues); the scan's grid is 1e-3 wide, up to Omega = 20
 * (returned when stable on the whole range). xi > 0 analyses the damped equation
 * with the velocity coupling solved implicitly, as CEodeSetVelocityDependence does. */
SUNDIALS_EXPORT int CEodeStabilityLimit(int degree, const sunrealtype* params, sunrealtype xi,
                                        sunrealtype* Omega_max);

/* Writes the amplification matrix (row-major, degree*degree entries). */
SUNDIALS_EXPORT int CEodeAmplificationMatrix(int degree, const sunrealtype* params,
                                             sunrealtype Omega, sunrealtype xi, sunrealtype* A);

/* rho[i] = spectral radius at Omega[i], i < n: one setup for many points. */
SUNDIALS_EXPORT int CEodeSpectralRadii(int degree, const sunrealtype* params, sunrealtype xi, int n,
                                       const sunrealtype* Omega, sunrealtype* rho);

#ifdef __cplusplus
}
#endif

#endif /* CEODE_CEODE_STABILITY_H_ */
