/* -----------------------------------------------------------------------------
 * SUNDIALS 6.4 / 7.x shims for CEODE's own tests, examples and benchmarks (C and
 * C++). Not installed: CEODE's public API is the same on both versions, and an
 * installed header must not define SUNDIALS' names. A program of your own needs
 * only the first shim:
 *
 *   #if SUNDIALS_VERSION_MAJOR >= 7
 *     SUNContext_Create(SUN_COMM_NULL, &ctx);
 *   #else
 *     SUNContext_Create(NULL, &ctx);
 *   #endif
 *
 * Code is written the SUNDIALS 7 way (SUN_COMM_NULL); the per-class success
 * codes the examples compare with keep their 6.4 names (SUNLS_SUCCESS, ...).
 * ---------------------------------------------------------------------------*/
#ifndef CEODE_SUPPORT_CEODE_SUNDIALS_COMPAT_H_
#define CEODE_SUPPORT_CEODE_SUNDIALS_COMPAT_H_

#include <sundials/sundials_config.h>
#include <sundials/sundials_context.h>

#if SUNDIALS_VERSION_MAJOR >= 7
/* On an MPI build SUN_COMM_NULL is MPI_COMM_NULL: NULL would compile and abort. */
#ifndef SUNLS_SUCCESS
#define SUNLS_SUCCESS SUN_SUCCESS
#endif
#ifndef SUNMAT_SUCCESS
#define SUNMAT_SUCCESS SUN_SUCCESS
#endif
#ifndef SUN_NLS_SUCCESS
#define SUN_NLS_SUCCESS SUN_SUCCESS
#endif
/* SUNContext_Create's communicator from an MPI_Comm: by value on 7.x. */
#define CEODE_SUN_COMM_ARG(comm) (comm)
#else
/* SUNDIALS 6.4: SUNContext_Create takes a void* communicator, NULL for none. */
#ifndef SUN_COMM_NULL
#define SUN_COMM_NULL NULL
#endif
/* ... and by address (void*) on 6.4. */
#define CEODE_SUN_COMM_ARG(comm) ((void*)&(comm))
#endif

#endif /* CEODE_SUPPORT_CEODE_SUNDIALS_COMPAT_H_ */
