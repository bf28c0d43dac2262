// ceode-stability find: given a degree and target orders, search the parameters
// left free by the order conditions for the largest stability interval.
//
//   ceode-stability find --degree 7 --order 7 [--order-v 6] [--samples 3000] [--seed 1]
//                        [--scale 30] [--tol 1e-9] [--omega-top 3] [--max-param 1000]
//
// The order conditions are linear in the parameters (CEodeMethodErrorCoeffs is affine in
// them, src/ceode_order.cpp), and so is rho(zeta) = 0 for a chosen parasitic root zeta (the
// parameters sit in one column of the step's symbol). A candidate is therefore fixed by
// where its parasitic roots go: y places them inside the unit disk (complex pairs, then real
// roots), and any freedom left moves along the null space of all these linear conditions.
// Deterministic samples (a fixed-seed splitmix64 sequence) are scored, then Nelder-Mead
// refines the best four. A candidate's score is the first Omega (scan 0.01 .. omega-top,
// step 0.01, then bisection) where the spectral radius of A(Omega) = A0 + Omega^2 (A1 - A0)
// exceeds 1 + tol (A is affine in Omega^2 for the undamped test equation); candidates that
// are not zero-stable, or have a parameter above max-param, score 0. The result is verified
// with the library's own CEodeMethodOrder and CEodeStabilityLimit.
#include "ceode_find.hpp"

#include <ceode/ceode.h>
#include <ceode/ceode_stability.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

namespace ceode_tools {

namespace {

struct FindOptions {
  int degree = 0;
  int order_x = 0;
  int order_v = -1;  // default order_x - 1
  int samples = 3000;
  std::uint64_t seed = 1;
  double scale = 0;  // 0: 2 (1 + max |p*|)
  double tol = 1e-9;
  double omega_top = 3;
  double max_param = 1000;  // larger parameters amplify round-off (docs/theory.md 10)
  std::string check;        // a named set the result must reproduce
};

constexpr int kCoefs = 20;  // 2 * 8 + 4, see CEodeMethodErrorCoeffs

// Deterministic uniform numbers in [-1, 1] (splitmix64), the same on every platform.
class Sequence {
 public:
  explicit Sequence(std::uint64_t seed) : s_(seed) {}
  double Next() {
    std::uint64_t z = (s_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return 2.0 * static_cast<double>(z >> 11) / 9007199254740992.0 - 1.0;
  }

 private:
  std::uint64_t s_;
};

// Row scaling does not change the solution set, but the high-order coefficients are
// small (1e-7 and below): unit rows make one tolerance fit every condition. Rows of
// conditions every set satisfies are rounding noise (below 1e-13) and are dropped.
void NormaliseRows(Eigen::MatrixXd* J, Eigen::VectorXd* r) {
  for (int i = 0; i < J->rows(); ++i) {
    const double n = J->row(i).norm();
    if (n > 1e-13) {
      J->row(i) /= n;
      (*r)(i) /= n;
    } else {  // satisfied by every set (the orders below d - 1): rounding noise only
      J->row(i).setZero();
      (*r)(i) = 0;
    }
  }
}

// Rows: the conditions coef_x[m] = 0 (m <= order_x + 1) and coef_v[m] = 0
// (m <= order_v + 1) as J p = r, from the affine coefficients at p = 1 and 1 + e_k.
bool Conditions(const FindOptions& o, Eigen::MatrixXd* J, Eigen::VectorXd* r) {
  const int np = o.degree - 1;
  const int nx = o.order_x + 2;
  const int nv = o.order_v + 2;
  std::vector<double> base(np, 1.0);
  double cx0[kCoefs], cv0[kCoefs], cx[kCoefs], cv[kCoefs];
  if (CEodeMethodErrorCoeffs(o.degree, base.data(), kCoefs, cx0, cv0) != CE_SUCCESS) return false;
  J->resize(nx + nv, np);
  r->resize(nx + nv);
  for (int k = 0; k < np; ++k) {
    std::vector<double> p = base;
    p[k] += 1;
    if (CEodeMethodErrorCoeffs(o.degree, p.data(), kCoefs, cx, cv) != CE_SUCCESS) return false;
    for (int m = 0; m < nx; ++m) (*J)(m, k) = cx[m] - cx0[m];
    for (int m = 0; m < nv; ++m) (*J)(nx + m, k) = cv[m] - cv0[m];
  }
  Eigen::VectorXd b = Eigen::VectorXd::Ones(np);
  for (int m = 0; m < nx; ++m) (*r)(m) = -cx0[m];
  for (int m = 0; m < nv; ++m) (*r)(nx + m) = -cv0[m];
  *r += *J * b;
  NormaliseRows(J, r);
  return true;
}

// rho(zeta) up to a unit factor: the determinant of the step's symbol at Omega = 0
// (relations (a) and (c) of docs/theory.md 2.2 for D_k,n = delta_k zeta^n, with
// D_2 = 0). The parameters all sit in the delta_{d-1} column, so it is affine in them.
std::complex<double> SymbolDet(int d, const std::vector<double>& p, std::complex<double> zeta) {
  using C = std::complex<double>;
  auto col = [](int var) { return var == 0 ? 0 : (var == 1 ? 1 : var - 1); };
  const int n = d - 1;
  Eigen::MatrixXcd M = Eigen::MatrixXcd::Zero(n, n);
  const C zi = 1.0 / zeta;
  auto add = [&](int row, int var, C v) {
    if (var != 2) M(row, col(var)) += v;
  };
  double fact[10] = {1, 1, 2, 6, 24, 120, 720, 5040, 40320, 362880};
  for (int k = 1; k <= d - 2; ++k) {
    add(k - 1, k, 1.0);
    for (int i = 0; i <= d - 2 - k; ++i) add(k - 1, k + i, -zi / fact[i]);
    add(k - 1, d - 1, -((1 - p[k]) * zi + p[k]) / fact[d - 1 - k]);
  }
  add(d - 2, 0, zeta - 1.0);
  for (int i = 1; i <= d - 2; ++i) add(d - 2, i, -1.0 / fact[i]);
  add(d - 2, d - 1, -((1 - p[0]) * zi + p[0]) / fact[d - 1]);
  return M.determinant();
}

// Two real rows (real and imaginary part of rho(zeta) = 0) per root, affine in p.
void RootRows(int d, const std::vector<std::complex<double>>& roots, Eigen::MatrixXd* J,
              Eigen::VectorXd* r) {
  const int np = d - 1;
  std::vector<double> base(np, 1.0);
  std::vector<std::pair<int, bool>> rows;  // (root, imaginary part?)
  for (int i = 0; i < static_cast<int>(roots.size()); ++i) {
    rows.push_back({i, false});
    if (roots[i].imag() != 0) rows.push_back({i, true});
  }
  J->resize(rows.size(), np);
  r->resize(rows.size());
  for (int i = 0; i < static_cast<int>(rows.size()); ++i) {
    const std::complex<double> z = roots[rows[i].first];
    auto part = [&](std::complex<double> v) { return rows[i].second ? v.imag() : v.real(); };
    const double f0 = part(SymbolDet(d, base, z));
    double acc = 0;
    for (int k = 0; k < np; ++k) {
      std::vector<double> p = base;
      p[k] += 1;
      (*J)(i, k) = part(SymbolDet(d, p, z)) - f0;
      acc += (*J)(i, k);
    }
    (*r)(i) = acc - f0;
  }
  NormaliseRows(J, r);
}

// Scores one parameter vector: the undamped stability limit of the fast scan.
class Scorer {
 public:
  Scorer(const FindOptions& o) : o_(o) {}

  double Score(const Eigen::VectorXd& p) {
    ++evals_;
    const int d = o_.degree;
    std::vector<double> a0(static_cast<size_t>(d) * d), a1(static_cast<size_t>(d) * d);
    if (p(1) == 0 || (d >= 4 && p(2) == 0) || p.cwiseAbs().maxCoeff() > o_.max_param) return 0;
    if (CEodeAmplificationMatrix(d, p.data(), 0, 0, a0.data()) != CE_SUCCESS ||
        CEodeAmplificationMatrix(d, p.data(), 1, 0, a1.data()) != CE_SUCCESS) {
      return 0;
    }
    A0_ = Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        a0.data(), d, d);
    B_ = Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
             a1.data(), d, d) -
         A0_;
    if (ParasiticRadius() >= 1 - 1e-6) return 0;
    double lo = 0;
    double hi = -1;
    // NOLINTNEXTLINE(clang-analyzer-security.FloatLoopCounter): the grid of the named sets
    for (double Om = 0.01; Om <= o_.omega_top + 1e-12; Om += 0.01) {
      if (!Stable(Om)) {
        hi = Om;
        break;
      }
      lo = Om;
    }
    if (hi < 0) return lo;
    for (int it = 0; it < 20; ++it) {
      const double mid = 0.5 * (lo + hi);
      (Stable(mid) ? lo : hi) = mid;
    }
    return lo;
  }
  long evals() const { return evals_; }

 private:
  // The two roots nearest 1 are the physical pair at Omega = 0; the rest are parasitic.
  double ParasiticRadius() const {
    const Eigen::VectorXcd ev = A0_.eigenvalues();
    std::vector<std::pair<double, double>> r;
    r.reserve(ev.size());
    for (int i = 0; i < ev.size(); ++i) r.push_back({std::abs(ev(i) - 1.0), std::abs(ev(i))});
    std::sort(r.begin(), r.end());
    double m = 0;
    for (size_t i = 2; i < r.size(); ++i) m = std::max(m, r[i].second);
    return m;
  }
  bool Stable(double Om) const {
    const Eigen::MatrixXd A = A0_ + Om * Om * B_;
    const Eigen::VectorXcd ev = A.eigenvalues();
    return ev.cwiseAbs().maxCoeff() <= 1 + o_.tol;
  }

  const FindOptions& o_;
  Eigen::MatrixXd A0_, B_;
  long evals_ = 0;
};

// Nelder-Mead (maximising), a fixed number of evaluations.
Eigen::VectorXd Refine(const std::function<double(const Eigen::VectorXd&)>& f,
                       const Eigen::VectorXd& y0, double step, int max_evals, double* best) {
  const int n = static_cast<int>(y0.size());
  std::vector<Eigen::VectorXd> s(n + 1, y0);
  std::vector<double> v(n + 1);
  for (int i = 0; i < n; ++i) s[i + 1](i) += step;
  for (int i = 0; i <= n; ++i) v[i] = f(s[i]);
  int evals = n + 1;
  while (evals < max_evals) {
    std::vector<int> idx(n + 1);
    for (int i = 0; i <= n; ++i) idx[i] = i;
    std::sort(idx.begin(), idx.end(), [&](int a, int b) { return v[a] > v[b]; });
    const int w = idx[n];
    Eigen::VectorXd c = Eigen::VectorXd::Zero(n);
    for (int i = 0; i < n; ++i) c += s[idx[i]] / n;
    const Eigen::VectorXd xr = c + (c - s[w]);
    const double fr = f(xr);
    ++evals;
    if (fr > v[idx[0]]) {
      const Eigen::VectorXd xe = c + 2 * (c - s[w]);
      const double fe = f(xe);
      ++evals;
      s[w] = fe > fr ? xe : xr;
      v[w] = std::max(fe, fr);
    } else if (fr > v[idx[n - 1]]) {
      s[w] = xr;
      v[w] = fr;
    } else {
      const Eigen::VectorXd xc = c + 0.5 * (s[w] - c);
      const double fc = f(xc);
      ++evals;
      if (fc > v[w]) {
        s[w] = xc;
        v[w] = fc;
      } else {
        for (int i = 1; i <= n; ++i) {
          s[idx[i]] = s[idx[0]] + 0.5 * (s[idx[i]] - s[idx[0]]);
          v[idx[i]] = f(s[idx[i]]);
          ++evals;
        }
      }
    }
  }
  const int b = static_cast<int>(std::max_element(v.begin(), v.end()) - v.begin());
  *best = v[b];
  return s[b];
}

bool ParseFind(int argc, char** argv, FindOptions* o) {
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    if (i + 1 >= argc) return false;
    const char* val = argv[++i];
    if (std::strcmp(a, "--degree") == 0) {
      o->degree = std::atoi(val);
    } else if (std::strcmp(a, "--order") == 0) {
      o->order_x = std::atoi(val);
    } else if (std::strcmp(a, "--order-v") == 0) {
      o->order_v = std::atoi(val);
    } else if (std::strcmp(a, "--samples") == 0) {
      o->samples = std::atoi(val);
    } else if (std::strcmp(a, "--seed") == 0) {
      o->seed = std::strtoull(val, nullptr, 10);
    } else if (std::strcmp(a, "--scale") == 0) {
      o->scale = std::atof(val);
    } else if (std::strcmp(a, "--tol") == 0) {
      o->tol = std::atof(val);
    } else if (std::strcmp(a, "--check") == 0) {
      o->check = val;
    } else if (std::strcmp(a, "--max-param") == 0) {
      o->max_param = std::atof(val);
    } else if (std::strcmp(a, "--omega-top") == 0) {
      o->omega_top = std::atof(val);
    } else {
      return false;
    }
  }
  if (o->order_v < 0) o->order_v = o->order_x - 1;
  return o->degree >= 3 && o->degree <= 8 && o->order_x >= 1 && o->order_v >= 1 &&
         o->order_x + 2 <= kCoefs && o->order_v + 2 <= kCoefs && o->samples >= 1 && o->tol > 0 &&
         o->omega_top > 0;
}

void Report(const FindOptions& o, const Eigen::VectorXd& p, double score) {
  const int d = o.degree;
  int ox = 0, ov = 0;
  CEodeMethodOrder(d, p.data(), &ox, &ov);
  double cx[kCoefs], cv[kCoefs];
  CEodeMethodErrorCoeffs(d, p.data(), kCoefs, cx, cv);
  double lim = 0, rho = 0;
  CEodeStabilityLimit(d, p.data(), 0, &lim);
  CEodeSpectralRadius(d, p.data(), 0.1, 0, &rho);
  std::printf("params    ");
  for (int i = 0; i < d - 1; ++i) std::printf("%s%.17g", i ? "," : "", p(i));
  std::printf("\norders    x %d, v %d (CEodeMethodOrder)\n", ox, ov);
  std::printf("errconst  x %.6g, v %.6g\n", ox + 2 < kCoefs ? cx[ox + 2] : 0.0,
              ov + 2 < kCoefs ? cv[ov + 2] : 0.0);
  std::printf("search    Omega limit %.6f (rho <= 1 + %g)\n", score, o.tol);
  std::printf("Omega_max %.6f (CEodeStabilityLimit, xi = 0)\n", lim);
  std::printf("rho(0.1)-1 %.3e\n", rho - 1);
}

// --check NAME: the named set must come out again, to 1e-6 in every parameter (the
// search is deterministic; the tolerance covers rounding differences between builds).
int Check(const FindOptions& o, const Eigen::VectorXd& p) {
  int d = 0;
  double q[8];
  if (CEodeGetMethodParams(o.check.c_str(), &d, q, 8) != CE_SUCCESS || d != o.degree) {
    std::printf("check     %s: not a named set of degree %d\n", o.check.c_str(), o.degree);
    return 1;
  }
  double diff = 0;
  for (int i = 0; i < d - 1; ++i)
    diff = std::max(diff, std::fabs(p(i) - q[i]) / (1 + std::fabs(q[i])));
  const bool ok = diff <= 1e-6;
  std::printf("check     %s %s (max relative parameter difference %.2e)\n", o.check.c_str(),
              ok ? "reproduced" : "NOT reproduced", diff);
  return ok ? 0 : 1;
}

}  // namespace

namespace {

// The search space: p = solution of [order conditions; rho(root_i) = 0] + free directions.
class Search {
 public:
  Search(const FindOptions& o, Eigen::MatrixXd J, Eigen::VectorXd r, int nfree, double scale)
      : o_(o), J_(std::move(J)), r_(std::move(r)), nfree_(nfree), scale_(scale), scorer_(o) {
    nroot_ = std::min(nfree, o.degree - 3);  // the parasitic roots of rho
  }

  // y -> parameters: the first nroot entries place parasitic roots (npairs complex pairs as
  // radius, angle; then real roots), the rest move along what the order and root
  // conditions leave free. False when the conditions cannot all hold.
  bool Params(const Eigen::VectorXd& y, int npairs, Eigen::VectorXd* p) const {
    const int np = o_.degree - 1;
    std::vector<std::complex<double>> roots;
    int k = 0;
    for (int q = 0; q < npairs; ++q, k += 2) {
      roots.push_back(std::polar(std::min(std::fabs(y(k)), 0.98), y(k + 1)));
    }
    for (; k < nroot_; ++k) roots.push_back(std::max(-0.98, std::min(0.98, y(k))));
    Eigen::MatrixXd Jr;
    Eigen::VectorXd rr;
    RootRows(o_.degree, roots, &Jr, &rr);
    Eigen::MatrixXd A(J_.rows() + Jr.rows(), np);
    A << J_, Jr;
    Eigen::VectorXd b(r_.size() + rr.size());
    b << r_, rr;
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
    svd.setThreshold(1e-10);
    *p = svd.solve(b);
    const int free2 = np - static_cast<int>(svd.rank());
    for (int e = 0; e < free2 && nroot_ + e < y.size(); ++e) {
      *p += svd.matrixV().col(np - 1 - e) * y(nroot_ + e);
    }
    return (A * *p - b).norm() <= 1e-9 * (1 + b.norm());
  }

  double Score(const Eigen::VectorXd& y, int layout) {
    Eigen::VectorXd p;
    return Params(y, layout, &p) ? scorer_.Score(p) : 0.0;
  }

  // The i-th deterministic sample, its root layout cycling through 0 .. nroot/2 pairs and
  // its free directions through four nested cubes.
  Eigen::VectorXd Sample(int i, Sequence* seq, int* layout) const {
    *layout = i % (nroot_ / 2 + 1);
    Eigen::VectorXd y(nfree_);
    for (int k = 0; k < nfree_; ++k) {
      const double u = seq->Next();
      if (k < 2 * *layout) {
        y(k) = k % 2 == 0 ? 0.49 * (u + 1) : 1.5707963267948966 * (u + 1);
      } else {
        y(k) = k < nroot_ ? 0.98 * u : scale_ / std::pow(3.0, i % 4) * u;
      }
    }
    return y;
  }

  // Samples, then Nelder-Mead from the best four; returns the best parameters.
  Eigen::VectorXd Run(double* score) {
    struct Cand {
      double score;
      Eigen::VectorXd y;
      int layout;
    };
    Sequence seq(o_.seed);
    std::vector<Cand> best;
    for (int i = 0; i < o_.samples; ++i) {
      int layout = 0;
      const Eigen::VectorXd y = Sample(i, &seq, &layout);
      best.push_back({Score(y, layout), y, layout});
      std::sort(best.begin(), best.end(),
                [](const Cand& a, const Cand& b) { return a.score > b.score; });
      if (best.size() > 4) best.pop_back();
    }
    Cand top{-1, Eigen::VectorXd(), 0};
    for (const Cand& c : best) {
      double v = 0;
      auto f = [&](const Eigen::VectorXd& y) { return Score(y, c.layout); };
      const Eigen::VectorXd y = Refine(f, c.y, 0.05, 400, &v);
      if (v > top.score) top = {v, y, c.layout};
    }
    Eigen::VectorXd p;
    Params(top.y, top.layout, &p);
    *score = top.score;
    return p;
  }

  long evals() const { return scorer_.evals(); }

 private:
  const FindOptions& o_;
  Eigen::MatrixXd J_;
  Eigen::VectorXd r_;
  int nfree_;
  int nroot_ = 0;
  double scale_;
  Scorer scorer_;
};

}  // namespace

int FindMain(int argc, char** argv) {
  FindOptions o;
  if (!ParseFind(argc, argv, &o)) {
    std::fprintf(stderr,
                 "usage: ceode-stability find --degree D --order P [--order-v Q] [--samples N]\n"
                 "       [--seed S] [--scale W] [--tol T] [--omega-top W] [--max-param M]\n"
                 "       [--check NAME]\n");
    return 2;
  }
  const auto t0 = std::chrono::steady_clock::now();
  Eigen::MatrixXd J;
  Eigen::VectorXd r;
  if (!Conditions(o, &J, &r)) return 1;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(J, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::VectorXd sv = svd.singularValues();
  int rank = 0;
  for (int i = 0; i < sv.size(); ++i) rank += sv(i) > 1e-10 * sv(0);
  svd.setThreshold(1e-10);
  const Eigen::VectorXd pstar = svd.solve(r);
  if ((J * pstar - r).norm() > 1e-8 * (1 + r.norm())) {
    std::printf("no parameter set of degree %d has orders x %d, v %d\n", o.degree, o.order_x,
                o.order_v);
    return 1;
  }
  const int nfree = o.degree - 1 - rank;
  std::printf("degree %d, orders x %d / v %d: %d conditions of rank %d, %d free parameters\n",
              o.degree, o.order_x, o.order_v, static_cast<int>(J.rows()), rank, nfree);
  if (nfree == 0) {
    Scorer scorer(o);
    Report(o, pstar, scorer.Score(pstar));
    return 0;
  }
  const double scale = o.scale > 0 ? o.scale : 2 * (1 + pstar.cwiseAbs().maxCoeff());
  Search search(o, J, r, nfree, scale);
  double score = 0;
  const Eigen::VectorXd pbest = search.Run(&score);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("search    %ld candidates scored, seed %llu, scale %g, %.1f s\n", search.evals(),
              static_cast<unsigned long long>(o.seed), scale, secs);
  Report(o, pbest, score);
  return o.check.empty() ? 0 : Check(o, pbest);
}

}  // namespace ceode_tools
