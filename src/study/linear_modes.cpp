#include "study/linear_modes.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/dynamics.hpp"
#include "study/run_analysis.hpp"

namespace lash {
namespace {

// The limit h → 0 of a central difference D(h), whose error is a series in h², by Ridders'
// method (C. J. F. Ridders, "Accurate computation of F'(x) and F'(x) F''(x)", Advances in
// Engineering Software 4(2), 1982): Neville's tableau of the polynomial extrapolations in h² of
// D at steps halving from h_s, and of its entries the one that differs least from its two
// neighbours of one order less (in the largest component, relative to the column's size), up
// to where the highest order begins to move by more than twice that. The
// tableau starts at the first step h_s where D has settled, |D(h_s) − D(h_s/2)| ≤ 1e-3 |D|:
// above it the difference is not yet a series in h², and a flexible link's element 7.5 mm long,
// its nodes moved 1e-3 m, gave extrapolations that agreed by chance and were wrong (its axial
// mode 7 359 Hz instead of 6 746.7). Steps run from 1e-2 (m or rad) down to 1e-2/2²⁹ ≈ 2e-11,
// so the scale of the mechanism need not be known: a fixed 1e-6 moved a 1e-4 m pendulum 1 % of
// its length (49.8464 Hz instead of 49.8488). A step whose evaluation fails (a configuration
// beyond the model's reach) and the larger ones are left out.
template <class Difference>
Eigen::VectorXd ridders_column(Difference&& difference) {
  constexpr int kLevels = 30;
  constexpr double kFirstStep = 1e-2, kSettled = 1e-3;
  auto norm = [](const Eigen::VectorXd& v) { return v.cwiseAbs().maxCoeff(); };
  std::vector<std::vector<Eigen::VectorXd>> table;  // table[i][j]: step i of the tableau, order j
  Eigen::VectorXd previous, best;                   // D at the step before; the answer
  double best_error = INFINITY;
  bool started = false;
  auto extend = [&](const Eigen::VectorXd& d) {  // one more step; false: round-off has set in
    table.push_back({d});
    const size_t i = table.size() - 1;
    double factor = 4.0;
    for (size_t j = 1; j <= i; ++j, factor *= 4.0) {
      table[i].push_back((factor * table[i][j - 1] - table[i - 1][j - 1]) / (factor - 1.0));
      const double error = std::max(norm(table[i][j] - table[i][j - 1]),
                                    norm(table[i][j] - table[i - 1][j - 1])) /
                           std::max(norm(table[i][j]), 1e-300);
      if (error < best_error) best_error = error, best = table[i][j];
    }
    if (i == 0) best = d;
    // Past the best steps round-off grows, and its noise can mimic agreement by chance: stop
    // once the highest order moves by twice the best error.
    return !(i > 0 && norm(table[i][i] - table[i - 1][i - 1]) >= 2 * best_error * norm(best));
  };
  std::vector<Eigen::VectorXd> unsettled;  // D at the steps before the difference settled
  double h = kFirstStep;
  for (int level = 0; level < kLevels; ++level, h /= 2) {
    Eigen::VectorXd d;
    if (!difference(h, d) || !d.allFinite()) {
      if (started) break;
      unsettled.clear(), previous.resize(0);  // begin again below this step
      continue;
    }
    if (!started && previous.size() && norm(previous - d) <= kSettled * norm(d)) {
      started = true;
      extend(previous);
    }
    if (started && !extend(d)) break;
    if (!started) unsettled.push_back(d);
    previous = std::move(d);
  }
  if (!started) {  // never settled (round-off at every step): the whole range
    if (unsettled.empty()) throw std::runtime_error("the linearisation cannot be evaluated");
    for (const Eigen::VectorXd& d : unsettled)
      if (!extend(d)) break;
  }
  return best;
}

// Balancing (B. N. Parlett and C. Reinsch, "Balancing a matrix for calculation of eigenvalues
// and eigenvectors", Numerische Mathematik 13, 1969): a similarity D⁻¹ A D by a diagonal D of
// powers of 2 (exact in floating point) that brings each row's and column's off-diagonal sums
// near each other. A flexible link's A spans 1e8 to 1e13 1/s² (bending against axial
// stiffness), and unbalanced, entries right to 1e-9 moved its first mode by up to 1 % (3 236
// to 3 270 Hz for the flexible-rod slider-crank as the difference step changed); balanced, the
// modes agree to six digits at every step from 1e-5 to 1e-8. Eigen's EigenSolver does not
// balance.
void balance(Eigen::MatrixXd& A) {
  const Eigen::Index n = A.rows();
  for (bool changed = true; changed;) {
    changed = false;
    for (Eigen::Index i = 0; i < n; ++i) {
      double column = 0.0, row = 0.0;
      for (Eigen::Index j = 0; j < n; ++j)
        if (j != i) column += std::abs(A(j, i)), row += std::abs(A(i, j));
      if (column == 0.0 || row == 0.0) continue;
      const double sum = column + row;
      double f = 1.0;
      while (column < row / 2) f *= 2, column *= 4;
      while (column > row * 2) f /= 2, column /= 4;
      if ((column + row) / f < 0.95 * sum) {
        changed = true;
        A.row(i) /= f;
        A.col(i) *= f;
      }
    }
  }
}

}  // namespace

LinearModes linear_modes(const Model& model) {
  Model m = ideal_model(model);
  {
    // Every driven coordinate held where it starts: at initial + f(0) (a position profile's
    // f(0) = 0.5 was dropped, and a spring was linearised at the wrong length).
    const Workspace at_start(m);
    for (size_t d = 0; d < m.drivers.size(); ++d) {
      double f = 0.0, fd = 0.0, fdd = 0.0;
      if (m.drivers[d].profile == DriverProfile::position)
        driver_motion(m, at_start, static_cast<int>(d), 0.0, nullptr, f, fd, fdd);
      else
        f = m.drivers[d].initial;  // constant speed: ω·0; speed: its integral starts at 0
      m.drivers[d].initial = f;
    }
  }
  for (Driver& d : m.drivers) {
    d.profile = DriverProfile::constant_speed;
    d.speed = 0.0;
    d.expression.clear();
  }
  // No constraint stabilisation: Baumgarte's terms are not the mechanism's, and the difference
  // steps leave the constraints by O(h²), which they answered with a spring of β² in every
  // direction the constraints' curvature turns: a point mass on a 1e-5 m rod swung at β/2π =
  // 15.9 Hz instead of 157.6, a parallelogram in line had a mode at 10.45 Hz.
  m.solver.baumgarte_alpha = m.solver.baumgarte_beta = 0.0;
  Workspace ws(m);
  Eigen::VectorXd y = initial_state(m, ws);
  const int nq = ws.nq, ny = ws.ny;
  y.segment(nq, nq).setZero();
  std::vector<double> f(ny), fm(ny);
  if (!evaluate(m, ws, 0.0, y.data(), f.data()))
    throw std::runtime_error("the initial configuration cannot be evaluated");

  // The tangent space: the null space of Φ_q (all of q without constraints).
  Eigen::MatrixXd null;
  if (ws.m == 0) {
    null = Eigen::MatrixXd::Identity(nq, nq);
  } else {
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(ws.phi_q, Eigen::ComputeFullV);
    svd.setThreshold(1e-10);
    null = svd.matrixV().rightCols(nq - static_cast<int>(svd.rank()));
  }
  LinearModes out;
  out.dof = static_cast<int>(null.cols());
  if (out.dof == 0) return out;

  // A = Bᵀ J B on the basis B = [(n, 0), (0, n)], each column J b by central differences
  // D(h) = (F(y + h b) − F(y − h b)) / 2h, extrapolated to h → 0 (ridders_column). A fixed
  // step cannot suit every mechanism: 1e-6 moved a 1e-4 m pendulum 1 % of its length, and its
  // 49.8488 Hz came out 49.8464.
  const int n2 = 2 * out.dof;
  Eigen::MatrixXd A(n2, n2);
  for (int c = 0; c < n2; ++c) {
    Eigen::VectorXd b = Eigen::VectorXd::Zero(ny);
    if (c < out.dof)
      b.head(nq) = null.col(c);
    else
      b.segment(nq, nq) = null.col(c - out.dof);
    auto difference = [&](double h, Eigen::VectorXd& d) {
      const Eigen::VectorXd yp = y + h * b, ym = y - h * b;
      if (!evaluate(m, ws, 0.0, yp.data(), f.data()) || !evaluate(m, ws, 0.0, ym.data(), fm.data()))
        return false;
      Eigen::VectorXd df(2 * nq);
      for (int i = 0; i < 2 * nq; ++i) df[i] = (f[i] - fm[i]) / (2 * h);
      d.resize(n2);
      d.head(out.dof) = null.transpose() * df.head(nq);
      d.tail(out.dof) = null.transpose() * df.tail(nq);
      return true;
    };
    A.col(c) = ridders_column(difference);
  }
  balance(A);
  const Eigen::EigenSolver<Eigen::MatrixXd> es(A, false);
  if (es.info() != Eigen::Success) throw std::runtime_error("the eigenvalue solver failed");
  for (int k = 0; k < n2; ++k) {
    const std::complex<double> lam = es.eigenvalues()[k];
    const double mag = std::abs(lam);
    if (std::abs(lam.imag()) <= 1e-9 * std::max(1.0, mag)) {
      out.real_rates.push_back(lam.real());
    } else if (lam.imag() > 0 && -lam.real() >= (1.0 - kCriticalShare) * mag) {
      // Overdamped roots that the linearisation cannot tell apart: a link's Kelvin–Voigt damping
      // sends every overdamped mode's slow root to −1/η, and k such roots, perturbed by the
      // difference quotient's error ε, split into pairs about ε^(1/k) off the real axis (seven
      // "modes" at 1/(2πη) = 15.9 Hz with ζ = 1 listed before the first bending mode, 16.6 Hz).
      out.real_rates.push_back(lam.real());
      out.real_rates.push_back(lam.real());
    } else if (lam.imag() > 0) {
      out.modes.push_back({mag / (2 * M_PI), -lam.real() / mag + 0.0, lam});  // + 0: no −0
    }
  }
  std::sort(out.modes.begin(), out.modes.end(),
            [](const LinearMode& a, const LinearMode& b) { return a.frequency < b.frequency; });
  std::sort(out.real_rates.begin(), out.real_rates.end());
  return out;
}

}  // namespace lash
