/* -----------------------------------------------------------------------------
 * Implementation toggles for the library's tests and benchmarks.
 *
 * Not installed, not part of the API: no user program needs these functions,
 * and they may change or go away without notice. Each selects between two
 * implementations that give the same numbers, so that test/ and bench/ can
 * compare them. The functions are exported by the library (C linkage) so that
 * the tests and benchmarks link against it; their targets add src/ as a
 * PRIVATE include directory. Defaults are the library's behaviour.
 * ---------------------------------------------------------------------------*/
#ifndef CEODE_CEODE_TESTING_H_
#define CEODE_CEODE_TESTING_H_

#include <ceode/ceode.h>

#ifdef __cplusplus
extern "C" {
#endif

/* SUNTRUE (default): on serial vectors (and on NVECTOR_PARALLEL's local part) the post-solve
 * update runs in one pass over memory, the same floating-point operations in the same order as
 * the generic N_Vector path (so the same numbers); SUNFALSE: the generic path. Other vector
 * types always take the generic path. */
SUNDIALS_EXPORT int CEodeSetFusedKernel(void* mem, sunbooleantype on);

/* SUNTRUE (default): the fused explicit step may update D_1 and D_3..D_{d-2} in place on
 * vectors of at least 1024 (local) entries, and, in a run of many steps to a distant tout on
 * serial or NVECTOR_PARALLEL vectors without a mass matrix, the position too for every step
 * but the run's last. Same numbers either way; what a failure gives back differs (docs/api.md,
 * CEodeEvolve). SUNFALSE: two buffers per derivative, the exact last good state for every
 * failure. May be called during a run (the next step uses the new setting). */
SUNDIALS_EXPORT int CEodeSetInPlaceUpdate(void* mem, sunbooleantype on);

/* SUNTRUE (default): saddle systems with n + nc <= 200 are solved by the Schur complement of
 * a block factored once and kept across steps (docs/theory.md section 8.3); SUNFALSE: the full
 * saddle-point matrix is assembled and factored by the linear solver at every setup, the path
 * of larger systems. Takes effect at the next Newton setup. */
SUNDIALS_EXPORT int CEodeSetSchurComplement(void* mem, sunbooleantype use);

/* With error control on: every step is accepted and the next one is schedule(t, n, data) (t and
 * n of the last accepted step), instead of the controller's choice, so that the tests can run
 * the variable step on a prescribed step sequence (orders under varying steps, stability under
 * step ratios). NULL restores the controller. */
typedef sunrealtype (*CEodeStepScheduleFn)(sunrealtype t, long int n, void* data);
SUNDIALS_EXPORT int CEodeSetStepSchedule(void* mem, CEodeStepScheduleFn schedule, void* data);

#ifdef __cplusplus
}
#endif

#endif /* CEODE_CEODE_TESTING_H_ */
