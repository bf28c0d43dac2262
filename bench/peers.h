// -----------------------------------------------------------------------------
// peers.h: the integrators users pick outside SUNDIALS, as curves of the
// work-precision scenes (bench/*/wp_*.cpp), driven and timed like every other
// curve (wp_common.h: one clock, one median rule, one equal-error routine).
//
//  * Boost.Odeint (header-only, Debian libboost-dev): runge_kutta4 (fixed h),
//    controlled runge_kutta_fehlberg78 and runge_kutta_dopri5, bulirsch_stoer,
//    and, only where the acceleration depends on x alone (a separable
//    Hamiltonian), velocity_verlet and symplectic_rkn_sb3a_mclachlan (fixed h).
//  * GSL (Debian libgsl-dev, gsl_odeiv2): rk8pd, rkf45, msadams, through one
//    gsl_odeiv2_driver (the standard y-control: eps_abs + eps_rel |y|).
//
// Every peer works from the scene's one problem description (wp::Problem: its acceleration
// a(t, x, x'), start, error function, separable, h0); the first-order peers integrate
// y = (x, x'). Each run is the whole user-visible job (allocate, integrate step by step, the
// scene's error function after every step, free), as wp::CeodeRun. Odeint's state
// is a std::array whose size is fixed at compile time (template argument N,
// the number of degrees of freedom), the fastest state type odeint offers for
// small systems. Adaptive peers use eps_rel = tol, eps_abs = atol_factor * tol.
//
// CheckPeerOrders turns "the curve is correct" into a check that fails the
// scene: a fixed-step peer's error must fall like h^p (log-log slope over its
// 3 smallest h above the floor in [p - 0.6, p + 0.9]), an adaptive one's like
// steps^-p (fixed-order pairs: slope in [p - 1.5, p + 3]; variable-order
// Bulirsch-Stoer and Adams: steeper than 3) and like tol^q, q in [0.6, 1.6],
// fitted on the points between the scene's round-off floor and a ceiling.
// -----------------------------------------------------------------------------
#ifndef CEODE_BENCH_PEERS_H_
#define CEODE_BENCH_PEERS_H_

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#include <array>
// odeint's steppers copy their (deliberately uninitialised) std::array scratch
// states on construction, which GCC reports as maybe-uninitialized.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <boost/numeric/odeint.hpp>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "wp_common.h"

namespace peers {

using wp::Problem;

enum class Kind {
  kRk4,
  kVerlet,
  kMcLachlan,
  kRkf78,
  kDopri5,
  kBulirschStoer,
  kRk8pd,
  kRkf45,
  kMsAdams
};

struct Info {
  Kind kind;
  const char* solver;  // CSV solver column: "odeint" or "GSL"
  const char* config;  // CSV config column
  bool fixed;          // swept over h (else over the tolerance)
  int order;           // 0: variable order
  bool needs_separable;
};

// order: the solution each library advances (odeint's rkf78 and GSL's rk8pd
// the 8th-order member of their pair, dopri5 the 5th); GSL's rkf45 is taken as
// 4, the window of CheckPeerOrders admits 5 as well.
constexpr Info kPeers[] = {
    {Kind::kRk4, "odeint", "rk4", true, 4, false},
    {Kind::kVerlet, "odeint", "velocity_verlet", true, 2, true},
    {Kind::kMcLachlan, "odeint", "sb3a_mclachlan", true, 4, true},
    {Kind::kRkf78, "odeint", "rkf78", false, 8, false},
    {Kind::kDopri5, "odeint", "dopri5", false, 5, false},
    {Kind::kBulirschStoer, "odeint", "bulirsch_stoer", false, 0, false},
    {Kind::kRk8pd, "GSL", "rk8pd", false, 8, false},
    {Kind::kRkf45, "GSL", "rkf45", false, 4, false},
    {Kind::kMsAdams, "GSL", "msadams", false, 0, false},
};

inline const Info& InfoOf(Kind k) {
  for (const Info& i : kPeers) {
    if (i.kind == k) return i;
  }
  return kPeers[0];  // unreachable: every Kind has its row
}

// GSL's default error handler aborts the process; the runners check flags.
inline void Setup() { gsl_set_error_handler_off(); }

// The scene's error (and drift, when the problem has one) after every step, and the step count.
struct Track {
  const Problem& p;
  double emax = 0, dmax = 0;
  long steps = 0;
  bool bad = false;
  explicit Track(const Problem& pr) : p(pr) {}
  void Observe(double t, const double* x, const double* v) {
    if (t <= p.t0) return;  // odeint also reports the initial state
    ++steps;
    const double e = p.err(t, x, v, p.user);
    if (!(e <= emax)) emax = e;  // also catches NaN
    const double d = p.drift != nullptr ? p.drift(t, x, v, p.user) : 0.0;
    if (!(d <= dmax)) dmax = d;
  }
  int Finish(long evals, wp::Outcome* out) const {
    out->error = emax;
    out->drift = dmax;
    out->steps = steps;
    out->rhs_evals = evals;
    return bad || !std::isfinite(emax) ? 1 : 0;
  }
};

inline long FixedSteps(const Problem& p, double h) { return std::lround((p.tend - p.t0) / h); }

// ------------------------------------------------------------------- odeint
// velocity_verlet and the McLachlan SB3A Nystrom method on (x, v).
template <int N>
int OdeintSymplecticOnce(const Problem& p, Kind k, double h, wp::Outcome* out) {
  namespace ode = boost::numeric::odeint;
  using Coor = std::array<double, N>;
  Track tr(p);
  long evals = 0;
  std::pair<Coor, Coor> xv;
  std::copy(p.x0.begin(), p.x0.end(), xv.first.begin());
  std::copy(p.v0.begin(), p.v0.end(), xv.second.begin());
  const long n = FixedSteps(p, h);
  if (k == Kind::kVerlet) {
    ode::velocity_verlet<Coor> st;
    auto sys = [&](const Coor& x, const Coor& v, Coor& a, double t) {
      ++evals;
      p.acc(t, x.data(), v.data(), a.data(), p.user);
    };
    for (long i = 0; i < n; ++i) {
      st.do_step(sys, xv, p.t0 + i * h, h);
      tr.Observe(p.t0 + (i + 1) * h, xv.first.data(), xv.second.data());
    }
  } else {
    ode::symplectic_rkn_sb3a_mclachlan<Coor> st;
    // Momentum form: dq/dt = p is implied; acc(x) takes no t (separable only).
    auto sys = [&](const Coor& x, Coor& a) {
      ++evals;
      p.acc(0.0, x.data(), nullptr, a.data(), p.user);
    };
    for (long i = 0; i < n; ++i) {
      st.do_step(sys, xv, p.t0 + i * h, h);
      tr.Observe(p.t0 + (i + 1) * h, xv.first.data(), xv.second.data());
    }
  }
  return tr.Finish(evals, out);
}

template <int N>
int OdeintOnce(const Problem& p, Kind k, double h_or_tol, double atol_factor, wp::Outcome* out) {
  namespace ode = boost::numeric::odeint;
  if (k == Kind::kVerlet || k == Kind::kMcLachlan)
    return OdeintSymplecticOnce<N>(p, k, h_or_tol, out);
  using State = std::array<double, 2 * N>;
  Track tr(p);
  long evals = 0;
  State y;
  std::copy(p.x0.begin(), p.x0.end(), y.begin());
  std::copy(p.v0.begin(), p.v0.end(), y.begin() + N);
  auto rhs = [&](const State& s, State& ds, double t) {
    ++evals;
    std::copy(s.begin() + N, s.end(), ds.begin());
    p.acc(t, s.data(), s.data() + N, ds.data() + N, p.user);
  };
  auto obs = [&](const State& s, double t) { tr.Observe(t, s.data(), s.data() + N); };
  const double rtol = h_or_tol, atol = atol_factor * h_or_tol;
  switch (k) {
    case Kind::kRk4: {
      ode::runge_kutta4<State> st;
      const long n = FixedSteps(p, h_or_tol);
      for (long i = 0; i < n; ++i) {
        st.do_step(rhs, y, p.t0 + i * h_or_tol, h_or_tol);
        obs(y, p.t0 + (i + 1) * h_or_tol);
      }
      break;
    }
    case Kind::kRkf78:
      ode::integrate_adaptive(
          ode::make_controlled(atol, rtol, ode::runge_kutta_fehlberg78<State>()), rhs, y, p.t0,
          p.tend, p.h0, obs);
      break;
    case Kind::kDopri5:
      ode::integrate_adaptive(ode::make_controlled(atol, rtol, ode::runge_kutta_dopri5<State>()),
                              rhs, y, p.t0, p.tend, p.h0, obs);
      break;
    case Kind::kBulirschStoer: {
      ode::bulirsch_stoer<State> st(atol, rtol);
      ode::integrate_adaptive(st, rhs, y, p.t0, p.tend, p.h0, obs);
      break;
    }
    default:
      tr.bad = true;
  }
  return tr.Finish(evals, out);
}

// ---------------------------------------------------------------------- GSL
struct GslData {
  const Problem* p;
  long evals;
};

inline int GslRhs(double t, const double y[], double dy[], void* data) {
  auto* d = static_cast<GslData*>(data);
  const std::ptrdiff_t n = d->p->n;
  ++d->evals;
  std::copy(y + n, y + 2 * n, dy);
  d->p->acc(t, y, y + n, dy + n, d->p->user);
  return GSL_SUCCESS;
}

// One gsl_odeiv2_evolve_apply per step (what gsl_odeiv2_driver_apply loops
// over), so that the error is seen after every step.
inline int GslOnce(const Problem& p, Kind k, double tol, double atol_factor, wp::Outcome* out) {
  GslData data{&p, 0};
  gsl_odeiv2_system sys = {GslRhs, nullptr, 2 * static_cast<size_t>(p.n), &data};
  const gsl_odeiv2_step_type* type = k == Kind::kRk8pd   ? gsl_odeiv2_step_rk8pd
                                     : k == Kind::kRkf45 ? gsl_odeiv2_step_rkf45
                                                         : gsl_odeiv2_step_msadams;
  gsl_odeiv2_driver* d = gsl_odeiv2_driver_alloc_y_new(&sys, type, p.h0, atol_factor * tol, tol);
  Track tr(p);
  if (d == nullptr) return 1;
  std::vector<double> y(2 * static_cast<size_t>(p.n));
  std::copy(p.x0.begin(), p.x0.end(), y.begin());
  std::copy(p.v0.begin(), p.v0.end(), y.begin() + p.n);
  double t = p.t0;
  while (t < p.tend) {
    if (gsl_odeiv2_evolve_apply(d->e, d->c, d->s, d->sys, &t, p.tend, &d->h, y.data()) !=
        GSL_SUCCESS) {
      tr.bad = true;
      break;
    }
    tr.Observe(t, y.data(), y.data() + p.n);
  }
  gsl_odeiv2_driver_free(d);
  return tr.Finish(data.evals, out);
}

// ----------------------------------------------------------------- measuring
template <int N>
int PeerOnce(const Problem& p, const Info& peer, double h_or_tol, double atol_factor,
             wp::Outcome* out) {
  if (std::string(peer.solver) == "GSL") return GslOnce(p, peer.kind, h_or_tol, atol_factor, out);
  return OdeintOnce<N>(p, peer.kind, h_or_tol, atol_factor, out);
}

// Every applicable peer: fixed-step ones over steps, adaptive ones over tols.
template <int N>
void MeasurePeers(wp::Table* table, const Problem& p, const std::vector<double>& steps,
                  const std::vector<double>& tols, double atol_factor) {
  static_assert(N > 0, "N is the number of degrees of freedom");
  if (p.n != N) {
    table->Fail("peers", "all", 0, "Problem::n differs from the template argument");
    return;
  }
  for (const Info& peer : kPeers) {
    if (peer.needs_separable && !p.separable) continue;
    for (double v : peer.fixed ? steps : tols) {
      wp::Measure(table, peer.solver, peer.config, v,
                  [&](wp::Outcome* o) { return PeerOnce<N>(p, peer, v, atol_factor, o); });
    }
  }
}

// Least-squares slope of log y against log x.
inline double LogLogSlope(const std::vector<double>& x, const std::vector<double>& y) {
  const size_t n = x.size();
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < n; ++i) {
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

// Slope windows of CheckPeerOrders (see the header comment).
struct Window {
  double lo, hi;
  bool Holds(double s) const { return s >= lo && s <= hi; }
  std::string Text() const {
    char buf[32];
    if (hi > 1e8) {
      std::snprintf(buf, sizeof buf, ">= %g", lo);
    } else {
      std::snprintf(buf, sizeof buf, "%g..%g", lo, hi);
    }
    return buf;
  }
};

inline Window OrderWindow(const Info& peer) {
  // Energy errors of non-symplectic methods can fall at the next order (the
  // local error's) until the accumulated error dominates: +0.9 above.
  if (peer.fixed) return {peer.order - 0.6, peer.order + 0.9};
  // Error per step control: steps ~ tol^(-1/p) or tol^(-1/(p+1)), so the
  // global error falls like steps^-p or steps^-(p+1); the loosest tolerances
  // are pre-asymptotic, hence the margin.
  if (peer.order > 0) return {peer.order - 1.5, peer.order + 3.0};
  return {3, 1e9};
}

// The points of one peer curve between the floor and the ceiling: x is h
// (fixed step) or the step count (adaptive); any: the curve has rows at all.
struct Curve {
  std::vector<double> x, tol, e;
  bool any = false;
};

inline Curve CollectCurve(const wp::Table& table, const Info& peer, double floor, double ceiling) {
  Curve c;
  for (const wp::Row& r : table.rows()) {
    if (r.solver != peer.solver || r.config != peer.config) continue;
    c.any = true;
    if (r.error > floor && r.error < ceiling) {
      c.x.push_back(peer.fixed ? r.h_or_tol : static_cast<double>(r.steps));
      c.tol.push_back(r.h_or_tol);
      c.e.push_back(r.error);
    }
  }
  if (peer.fixed && c.x.size() > 3) {  // the asymptotic order: the 3 smallest h above the floor
    for (std::vector<double>* v : {&c.x, &c.tol, &c.e}) v->erase(v->begin(), v->end() - 3);
  }
  return c;
}

// Fits and prints one curve; true when it converges as its method must.
inline bool CurveConverges(const Info& peer, const Curve& c) {
  const Window w = OrderWindow(peer), prop{0.6, 1.6};
  const bool fit = c.x.size() >= 2;
  double s = 0, q = 1;
  if (fit) {
    s = peer.fixed ? LogLogSlope(c.x, c.e) : -LogLogSlope(c.x, c.e);
    if (!peer.fixed) q = LogLogSlope(c.tol, c.e);
  }
  const bool ok = fit && w.Holds(s) && prop.Holds(q);
  std::printf("  %-7s %-16s %s %6.2f (expected %s)", peer.solver, peer.config,
              peer.fixed ? "error ~ h^p,      p =" : "error ~ steps^-p, p =", s, w.Text().c_str());
  if (!peer.fixed) std::printf(", error ~ tol^%.2f (expected %s)", q, prop.Text().c_str());
  std::printf(" over %zu points %s\n", c.x.size(), ok ? "ok" : "-- NONSENSE");
  return ok;
}

// Checks every peer curve of the table converges at its order (see the
// header comment), on the points with floor < error < ceiling; adaptive
// curves must also keep the error proportional to the tolerance (slope of log
// error against log tol in 0.6..1.6). Prints one line per curve; returns the
// number of curves that fail (fewer than 2 points in the window fails too).
inline int CheckPeerOrders(const wp::Table& table, double floor, double ceiling) {
  int bad = 0;
  std::printf("\npeer orders (log-log fit on errors in (%.0e, %.0e)):\n", floor, ceiling);
  for (const Info& peer : kPeers) {
    const Curve c = CollectCurve(table, peer, floor, ceiling);
    if (c.any && !CurveConverges(peer, c)) ++bad;
  }
  return bad;
}

}  // namespace peers

#endif  // CEODE_BENCH_PEERS_H_
