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

/* ---- Order conditions (src/ceode_order.cpp, docs/theory.md section 9.4) -------------------
 * Orders in x and x' of the step with these parameters: the largest p such that the
 * method is exact on polynomial solutions of degree p + 1 (local error O(h^(p+2)) in x,
 * O(h^(p+1)) in x' per step; the principal root errs by O(Omega^(p+1))). Zero-stability is
 * not part of the order: check it with CEodeStabilityLimit. */
SUNDIALS_EXPORT int CEodeMethodOrder(int degree, const sunrealtype* params, int* order_x,
                                     int* order_v);

/* The first n Taylor coefficients (in s = h times the exponent of an exponential solution)
 * of the x and x' residuals; coef_x[order_x + 2] and coef_v[order_v + 2] are the error
 * constants (1/12 in magnitude for central differences). Affine in the parameters.
 * n <= 2 * 8 + 4. */
SUNDIALS_EXPORT int CEodeMethodErrorCoeffs(int degree, const sunrealtype* params, int n,
                                           sunrealtype* coef_x, sunrealtype* coef_v);
/* The local error constant of the position step that error control uses: a step of size h
 * from the exact consistent history errs by cerr h^(order+1) x^(order+1) + O(h^(order+2)),
 * with order the set's order in x (docs/theory.md section 12.3). */
SUNDIALS_EXPORT int CEodeMethodErrorConstant(int degree, const sunrealtype* params, int* order,
                                             sunrealtype* cerr);
/* ---- end of order conditions ---------------------------------------------------------- */

#ifdef __cplusplus
}
#endif

#endif /* CEODE_CEODE_STABILITY_H_ */
