// Mass matrices: a dense numpy array, a scipy.sparse matrix, a 1-D diagonal, or a callable
// M(t, x) returning one of those, mapped onto CEodeSetMassFn with the linear solver CEODE
// requires beside it (SUNLinSol_Dense on a dense M, KLU on a sparse one; with constraints the
// solver's matrix is the (n + nc) x (n + nc) saddle-point one).
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "ceode_py.hpp"

namespace ceode_py {

namespace {

Csr Diagonal(const RealArray& d) {
  Csr out;
  out.rows = out.cols = d.shape(0);
  for (sunindextype i = 0; i <= out.rows; ++i) out.ptr.push_back(i);
  for (sunindextype i = 0; i < out.rows; ++i) {
    out.idx.push_back(i);
    out.val.push_back(d.at(i));
  }
  return out;
}

// Any accepted value of M as CSR, checked: n x n and finite.
// The number of dimensions of a dense value, 0 for a sparse one or a non-array.
int DenseDims(py::handle value) {
  if (IsSparse(value)) return 0;
  py::array arr = py::array::ensure(value);
  return arr ? static_cast<int>(arr.ndim()) : 0;
}

Csr MassToCsr(py::handle value, sunindextype n) {
  Csr A = DenseDims(value) == 1 ? Diagonal(AsVector(value, "M (diagonal)", n)) : ToCsr(value, "M");
  if (A.rows != n || A.cols != n) {
    throw py::value_error("M is " + std::to_string(A.rows) + " x " + std::to_string(A.cols) +
                          "; expected " + std::to_string(n) + " x " + std::to_string(n) + ".");
  }
  for (sunrealtype a : A.val) {
    if (!std::isfinite(a)) throw py::value_error("M has a non-finite entry.");
  }
  return A;
}

MassSpec::Kind KindOf(py::handle value) {
  return DenseDims(value) == 2 ? MassSpec::kDense : MassSpec::kSparse;
}

// Fills M (zeroed by CEODE) from CSR.
int FillMatrix(const Csr& A, SUNMatrix M) {
  if (SUNMatGetID(M) == SUNMATRIX_SPARSE) return CopyCsr(A, M);
  for (sunindextype i = 0; i < A.rows; ++i) {
    for (sunindextype k = A.ptr[i]; k < A.ptr[i + 1]; ++k) SM_ELEMENT_D(M, i, A.idx[k]) += A.val[k];
  }
  return 0;
}

sunindextype SaddleNnz(const CallbackData& cb) {
  const sunindextype n = cb.n, nc = cb.constr.nc, N = n + nc;
  sunindextype nnz = static_cast<sunindextype>(cb.mass.sparse.val.size()) + n + 2 * nc * n;
  if (cb.structure) nnz += static_cast<sunindextype>(cb.structure->damping().val.size());
  return std::min(nnz, N * N);
}

// Creates M, A and LS for the mass kind; false when SUNDIALS could not allocate them.
bool CreateSolvers(SUNContext ctx, const CallbackData& cb, SolverSet* set) {
  const sunindextype n = cb.n, N = n + cb.constr.nc;
  N_Vector tmpl = N_VNew_Serial(N, ctx);
  if (tmpl == nullptr) return false;
  if (cb.mass.kind == MassSpec::kDense) {
    set->M = SUNDenseMatrix(n, n, ctx);
    set->A = SUNDenseMatrix(N, N, ctx);
    if (set->A != nullptr) set->LS = SUNLinSol_Dense(tmpl, set->A, ctx);
  } else {
    const auto nnz_m = std::max<sunindextype>(1, cb.mass.sparse.val.size());
    set->M = SUNSparseMatrix(n, n, nnz_m, CSR_MAT, ctx);
    set->A = SUNSparseMatrix(N, N, SaddleNnz(cb), CSR_MAT, ctx);
    if (set->A != nullptr) set->LS = SUNLinSol_KLU(tmpl, set->A, ctx);
  }
  N_VDestroy(tmpl);
  return set->M != nullptr && set->A != nullptr && set->LS != nullptr;
}

}  // namespace

void SolverSet::Free() {
  if (LS != nullptr) SUNLinSolFree(LS);
  if (A != nullptr) SUNMatDestroy(A);
  if (M != nullptr) SUNMatDestroy(M);
  LS = nullptr;
  A = M = nullptr;
}

int CopyCsr(const Csr& A, SUNMatrix M) {
  if (SUNSparseMatrix_SparseType(M) != CSR_MAT) return -1;
  const auto nnz = static_cast<sunindextype>(A.val.size());
  if (SUNSparseMatrix_NNZ(M) < nnz && SUNSparseMatrix_Reallocate(M, nnz) != 0) return -1;
  std::copy(A.ptr.begin(), A.ptr.end(), SUNSparseMatrix_IndexPointers(M));
  std::copy(A.idx.begin(), A.idx.end(), SUNSparseMatrix_IndexValues(M));
  std::copy(A.val.begin(), A.val.end(), SUNSparseMatrix_Data(M));
  return 0;
}

MassSpec ParseMass(py::handle M, py::handle constant, sunindextype n, sunrealtype t0,
                   py::handle x0) {
  MassSpec spec;
  if (M.is_none()) return spec;
  py::object value = py::reinterpret_borrow<py::object>(M);
  if (PyCallable_Check(M.ptr())) {
    spec.callable = value;
    spec.constant = !constant.is_none() && constant.cast<bool>();
    value = spec.callable(t0, x0);  // its first value tells the kind and the sparsity
  } else if (!constant.is_none() && !constant.cast<bool>()) {
    throw py::value_error("constant=False needs a callable M(t, x).");
  }
  spec.kind = KindOf(value);
  spec.sparse = MassToCsr(value, n);
  return spec;
}

int MassFn(sunrealtype t, N_Vector x, SUNMatrix M, void* user_data, N_Vector t1, N_Vector t2,
           N_Vector t3) {
  (void)t1, (void)t2, (void)t3;
  auto* cb = static_cast<CallbackData*>(user_data);
  if (cb->mass.callable.is_none()) return FillMatrix(cb->mass.sparse, M);
  int status = 0;
  const int r = cb->Guard([&] {
    ++cb->python_calls;
    py::object value = cb->mass.callable(t, cb->in.Vector(N_VGetArrayPointer(x), cb->n));
    status = FillMatrix(MassToCsr(value, cb->n), M);
  });
  return r != 0 ? r : status;
}

int AttachSolvers(void* mem, SUNContext ctx, const CallbackData& cb, SolverSet* set) {
  if (cb.mass.kind == MassSpec::kNone) return CEodeSetMassFn(mem, nullptr, nullptr, SUNFALSE);
  SolverSet fresh;
  if (!CreateSolvers(ctx, cb, &fresh)) {
    fresh.Free();
    return CE_MEM_FAIL;
  }
  int flag = CEodeSetMassFn(mem, MassFn, fresh.M, cb.mass.constant ? SUNTRUE : SUNFALSE);
  if (flag >= 0) flag = CEodeSetLinearSolver(mem, fresh.LS, fresh.A);
  if (flag < 0) {
    CEodeSetMassFn(mem, nullptr, nullptr, SUNFALSE);  // CEODE keeps no pointer to them
    fresh.Free();
    return flag;
  }
  set->Free();  // CEODE now holds the new ones
  *set = fresh;
  return flag;
}

}  // namespace ceode_py
