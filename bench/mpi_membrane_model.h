// The membrane partitioned over MPI ranks (docs/mpi.md): a 5-point Laplacian on an
// nx x ny grid (spacing 1/(nx+1) in both directions, fixed edges, lumped unit masses), the grid
// rows split into contiguous strips, one strip per rank, each strip one NVECTOR_PARALLEL local
// block (row-major). f exchanges one halo row with each neighbour strip (non-blocking, overlapped
// with the interior rows) and evaluates every entry with the same expression, in the same order,
// as the serial evaluation: a distributed run is bitwise equal to a serial one.
//
// Shared by bench/mpi_membrane.cpp (timing, N = 10^6) and test/mpi/mpi_membrane_halo.cpp.
#ifndef CEODE_BENCH_MPI_MEMBRANE_MODEL_H_
#define CEODE_BENCH_MPI_MEMBRANE_MODEL_H_

#include <mpi.h>
#include <nvector/nvector_parallel.h>
#include <nvector/nvector_serial.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "mpi_partition.h"

namespace membrane {

// One rank's strip: rows [row0, row0 + nrows) of the grid, with a halo row above and below
// (zero where the strip touches the fixed edge, so that edge rows need no special case).
struct Strip {
  MPI_Comm comm = MPI_COMM_NULL;  // MPI_COMM_NULL: the whole grid on one NVECTOR_SERIAL
  int rank = 0;
  int size = 1;
  int nx = 0;
  int ny = 0;
  int row0 = 0;
  int nrows = 0;
  int nactive = 1;         // ranks that own rows: min(size, ny); the others own none
  double k = 0;            // stiffness 1/dx^2
  std::vector<double> lo;  // the row below row0 (from rank - 1)
  std::vector<double> hi;  // the row above row0 + nrows - 1 (from rank + 1)
  long nexchange = 0;      // halo exchanges done (one per f evaluation with neighbours)
  bool exchange = true;    // false: stale halo rows (only the test's negative control)
};

// The balanced row partition: rank owns rows [*row0, *row0 + *nrows).
inline void RowRange(int ny, int size, int rank, int* row0, int* nrows) {
  mpi_partition::BalancedRange(ny, size, rank, row0, nrows);
}

inline Strip MakeStrip(MPI_Comm comm, int nx, int ny) {
  Strip s;
  s.comm = comm;
  if (comm != MPI_COMM_NULL) {
    MPI_Comm_rank(comm, &s.rank);
    MPI_Comm_size(comm, &s.size);
  }
  s.nx = nx;
  s.ny = ny;
  RowRange(ny, s.size, s.rank, &s.row0, &s.nrows);
  s.nactive = std::min(s.size, ny);
  s.k = static_cast<double>(nx + 1) * (nx + 1);
  s.lo.assign(static_cast<size_t>(nx), 0.0);
  s.hi.assign(static_cast<size_t>(nx), 0.0);
  return s;
}

inline long LocalLength(const Strip& s) { return static_cast<long>(s.nrows) * s.nx; }
inline long GlobalLength(const Strip& s) { return static_cast<long>(s.nx) * s.ny; }

// The square grid for about n DOFs (bench/mpi_membrane.cpp's --n).
inline Strip MakeStrip(MPI_Comm comm, long n) {
  const int side = static_cast<int>(std::lround(std::sqrt(static_cast<double>(n))));
  return MakeStrip(comm, side, side);
}

// Rank r's entries, for gathering a distributed state.
inline void Range(const Strip& s, int r, long* off, long* len) {
  int row0 = 0, nrows = 0;
  RowRange(s.ny, s.size, r, &row0, &nrows);
  *off = static_cast<long>(row0) * s.nx;
  *len = static_cast<long>(nrows) * s.nx;
}

inline std::string Describe(const Strip& s) {
  return "membrane " + std::to_string(s.nx) + " x " + std::to_string(s.ny);
}

// One grid row: a = k (w + e + n + s - 4 c), summed in this order for every entry; the missing
// neighbour at a side edge is a zero term, as in the serial loop.
inline void Row(const Strip& s, const double* dn, const double* c, const double* up, double* a) {
  const int nx = s.nx;
  const double k = s.k;
  if (nx == 1) {
    a[0] = k * ((((0.0 + 0.0) + dn[0]) + up[0]) - 4 * c[0]);
    return;
  }
  a[0] = k * ((((0.0 + c[1]) + dn[0]) + up[0]) - 4 * c[0]);
  for (int j = 1; j < nx - 1; ++j) {
    a[j] = k * ((((c[j - 1] + c[j + 1]) + dn[j]) + up[j]) - 4 * c[j]);
  }
  a[nx - 1] = k * ((((c[nx - 2] + 0.0) + dn[nx - 1]) + up[nx - 1]) - 4 * c[nx - 1]);
}

// Post the halo receives and sends of this strip's first and last rows (tag 0: travelling up
// the rank order, tag 1: down). Returns the number of requests.
inline int StartHalo(Strip* s, const double* u, MPI_Request* req) {
  int n = 0;
  if (!s->exchange) return 0;
  const int nx = s->nx;
  if (s->rank > 0 && s->nrows > 0) {
    MPI_Irecv(s->lo.data(), nx, MPI_DOUBLE, s->rank - 1, 0, s->comm, &req[n++]);
    MPI_Isend(u, nx, MPI_DOUBLE, s->rank - 1, 1, s->comm, &req[n++]);
  }
  if (s->rank + 1 < s->nactive) {
    MPI_Irecv(s->hi.data(), nx, MPI_DOUBLE, s->rank + 1, 1, s->comm, &req[n++]);
    MPI_Isend(u + static_cast<long>(s->nrows - 1) * nx, nx, MPI_DOUBLE, s->rank + 1, 0, s->comm,
              &req[n++]);
  }
  if (n > 0) ++s->nexchange;
  return n;
}

// M x'' = f(x) with M = I on the strip's arrays: the interior rows while the halo rows travel,
// then the two edge rows.
inline int Accel(Strip* s, const double* u, double* a) {
  const long nx = s->nx;
  const int nr = s->nrows;
  if (nr == 0) return 0;
  MPI_Request req[4];
  const int nreq = StartHalo(s, u, req);
  for (int r = 1; r < nr - 1; ++r)
    Row(*s, u + (r - 1) * nx, u + r * nx, u + (r + 1) * nx, a + r * nx);
  // Only req[0, nreq) were started, and only they are waited for.
  if (nreq > 0 &&
      MPI_Waitall(nreq, req, MPI_STATUSES_IGNORE) != MPI_SUCCESS) {  // NOLINT(*MPI-Checker)
    return -1;
  }
  const double* below = s->lo.data();
  const double* above = nr > 1 ? u + nx : s->hi.data();
  Row(*s, below, u, above, a);
  if (nr > 1) Row(*s, u + (nr - 2) * nx, u + (nr - 1) * nx, s->hi.data(), a + (nr - 1) * nx);
  return 0;
}

// CEODE's right-hand side: Accel on the vectors' local arrays.
inline int Rhs(sunrealtype, N_Vector x, N_Vector, N_Vector f, void* data) {
  return Accel(static_cast<Strip*>(data), N_VGetArrayPointer(x), N_VGetArrayPointer(f));
}

// The exact modes of the discrete operator: phi_pq(i, j) = sin(p pi (j+1)/(nx+1))
// sin(q pi (i+1)/(ny+1)) (row i, column j), omega_pq^2 = k (4 sin^2(p pi/(2(nx+1))) +
// 4 sin^2(q pi/(2(ny+1)))).
struct Mode {
  int p;
  int q;
  double amplitude;
};

inline double Phi(const Strip& s, const Mode& m, int i, int j) {
  return std::sin(M_PI * m.p * (j + 1) / (s.nx + 1)) * std::sin(M_PI * m.q * (i + 1) / (s.ny + 1));
}

inline double Omega(const Strip& s, const Mode& m) {
  const double sx = std::sin(M_PI * m.p / (2.0 * (s.nx + 1)));
  const double sy = std::sin(M_PI * m.q / (2.0 * (s.ny + 1)));
  return std::sqrt(s.k * (4 * sx * sx + 4 * sy * sy));
}

// The highest frequency of the grid (mode p = nx, q = ny).
inline double OmegaMax(const Strip& s) { return Omega(s, Mode{s.nx, s.ny, 0}); }

// Two modes: the lowest and one at about a third of omega_max, so that the run is not trivially
// smooth.
inline std::vector<Mode> InitialModes(const Strip& s) {
  return {Mode{1, 1, 1.0}, Mode{std::max(1, (s.nx + 1) / 3), std::max(1, (s.ny + 1) / 3), 0.25}};
}

// x0 = sum of the modes on this strip's rows (global indices), v0 = 0.
inline void InitialState(const Strip& s, double* x, double* v) {
  const auto modes = InitialModes(s);
  for (int r = 0; r < s.nrows; ++r) {
    for (int j = 0; j < s.nx; ++j) {
      double val = 0;
      for (const Mode& m : modes) val += m.amplitude * Phi(s, m, s.row0 + r, j);
      x[static_cast<long>(r) * s.nx + j] = val;
      v[static_cast<long>(r) * s.nx + j] = 0;
    }
  }
}

// The exact solution at t = steps * h: of the central-difference recurrence (discrete = true)
// or of the ODE; its largest deviation from x (the whole grid), relative to the amplitude.
inline double Accuracy(const Strip& s, const double* x, long steps, double h, bool discrete,
                       double* tol, const char** what) {
  const auto modes = InitialModes(s);
  std::vector<double> factor;
  double amp = 0;
  for (const auto& m : modes) {
    const double w = Omega(s, m);
    const double theta = std::acos(1 - 0.5 * (w * h) * (w * h));
    factor.push_back(m.amplitude * (discrete ? std::cos(steps * theta) : std::cos(w * steps * h)));
    amp += std::fabs(m.amplitude);
  }
  double err = 0;
  for (int i = 0; i < s.ny; ++i) {
    for (int j = 0; j < s.nx; ++j) {
      double e = 0;
      for (size_t k = 0; k < modes.size(); ++k) e += factor[k] * Phi(s, modes[k], i, j);
      err = std::max(err, std::fabs(x[static_cast<long>(i) * s.nx + j] - e));
    }
  }
  *tol = discrete ? 1e-9 : 1e-3;
  *what = discrete ? "max |x - exact| / amplitude against the exact central-difference solution"
                   : "max |x - exact| / amplitude against the exact ODE solution";
  return err / amp;
}

}  // namespace membrane

#endif  // CEODE_BENCH_MPI_MEMBRANE_MODEL_H_
