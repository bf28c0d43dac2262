// Position constraints: Phi(t, x, out) and G(t, x, out) as Python callables on views of
// CEODE's vectors and of the dense (nc x n) Jacobian CEODE zeroes before each call. G may
// instead return the matrix (a 2-D array or scipy.sparse), which is copied.
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <string>

#include "ceode_py.hpp"

namespace ceode_py {

namespace {

// G's returned value (when it returns one) into the dense matrix.
void CopyReturned(py::handle value, SUNMatrix G) {
  const sunindextype rows = SM_ROWS_D(G), cols = SM_COLUMNS_D(G);
  Csr A = ToCsr(value, "G");
  if (A.rows != rows || A.cols != cols) {
    throw py::value_error("G returned a " + std::to_string(A.rows) + " x " +
                          std::to_string(A.cols) + " matrix; expected " + std::to_string(rows) +
                          " x " + std::to_string(cols) + ".");
  }
  for (sunindextype i = 0; i < rows; ++i) {
    for (sunindextype k = A.ptr[i]; k < A.ptr[i + 1]; ++k) SM_ELEMENT_D(G, i, A.idx[k]) += A.val[k];
  }
}

// A sparse G (with a KLU saddle-point solver): G writes into a dense scratch array or
// returns its matrix; either is copied into G as CSR.
int SparseJac(CallbackData* cb, sunrealtype t, N_Vector x, SUNMatrix G) {
  int status = 0;
  const int r = cb->Guard([&] {
    ++cb->python_calls;
    const auto rows = static_cast<py::ssize_t>(SUNSparseMatrix_Rows(G));
    const auto cols = static_cast<py::ssize_t>(SUNSparseMatrix_Columns(G));
    py::array_t<sunrealtype> scratch({rows, cols});
    std::fill(scratch.mutable_data(), scratch.mutable_data() + scratch.size(), 0.0);
    py::object value = cb->constr.jac(t, cb->in.Vector(N_VGetArrayPointer(x), cb->n), scratch);
    Csr A = ToCsr(value.is_none() ? py::object(scratch) : value, "G");
    if (A.rows != rows || A.cols != cols) throw py::value_error("G has the wrong shape.");
    status = CopyCsr(A, G);
  });
  return r != 0 ? r : status;
}

}  // namespace

int PhiFn(sunrealtype t, N_Vector x, N_Vector phi, void* user_data) {
  auto* cb = static_cast<CallbackData*>(user_data);
  return cb->Guard([&] {
    ++cb->python_calls;
    cb->constr.phi(t, cb->in.Vector(N_VGetArrayPointer(x), cb->n),
                   cb->out.Vector(N_VGetArrayPointer(phi), N_VGetLength(phi)));
  });
}

int PhiJacFn(sunrealtype t, N_Vector x, SUNMatrix G, void* user_data) {
  auto* cb = static_cast<CallbackData*>(user_data);
  if (SUNMatGetID(G) == SUNMATRIX_SPARSE) return SparseJac(cb, t, x, G);
  if (SUNMatGetID(G) != SUNMATRIX_DENSE) return -1;
  return cb->Guard([&] {
    ++cb->python_calls;
    py::object value = cb->constr.jac(t, cb->in.Vector(N_VGetArrayPointer(x), cb->n),
                                      cb->out.Matrix(SM_DATA_D(G), SM_ROWS_D(G), SM_COLUMNS_D(G)));
    if (!value.is_none()) CopyReturned(value, G);
  });
}

}  // namespace ceode_py
