#include "study/linear_modes.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "core/beam.hpp"
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

// An orthonormal basis of the null space of Φ_q at the last evaluation (all of q without
// constraints): the tangent space of the constraints.
Eigen::MatrixXd tangent_basis(const Workspace& ws) {
  if (ws.m == 0) return Eigen::MatrixXd::Identity(ws.nq, ws.nq);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(ws.phi_q, Eigen::ComputeFullV);
  svd.setThreshold(1e-10);
  return svd.matrixV().rightCols(ws.nq - static_cast<int>(svd.rank()));
}

// The first `columns` columns of A = Bᵀ J B on the basis B = [(n, 0), (0, n)] (n = `null`, the
// tangent space at y): J b by central differences D(h) = (F(y + h b) − F(y − h b)) / 2h,
// extrapolated to h → 0 (ridders_column). A fixed step cannot suit every mechanism: 1e-6 moved
// a 1e-4 m pendulum 1 % of its length, and its 49.8488 Hz came out 49.8464.
Eigen::MatrixXd reduced_jacobian(const Model& m, Workspace& ws, const Eigen::VectorXd& y,
                                 const Eigen::MatrixXd& null, int columns,
                                 const std::atomic<int>* interrupt) {
  const int nq = ws.nq, dof = static_cast<int>(null.cols()), n2 = 2 * dof;
  std::vector<double> f(ws.ny), fm(ws.ny);
  Eigen::MatrixXd A(n2, columns);
  for (int c = 0; c < columns; ++c) {
    if (interrupt && interrupt->load() != 0) throw std::runtime_error("interrupted");
    Eigen::VectorXd b = Eigen::VectorXd::Zero(ws.ny);
    if (c < dof)
      b.head(nq) = null.col(c);
    else
      b.segment(nq, nq) = null.col(c - dof);
    auto difference = [&](double h, Eigen::VectorXd& d) {
      const Eigen::VectorXd yp = y + h * b, ym = y - h * b;
      if (!evaluate(m, ws, 0.0, yp.data(), f.data()) || !evaluate(m, ws, 0.0, ym.data(), fm.data()))
        return false;
      Eigen::VectorXd df(2 * nq);
      for (int i = 0; i < 2 * nq; ++i) df[i] = (f[i] - fm[i]) / (2 * h);
      d.resize(n2);
      d.head(dof) = null.transpose() * df.head(nq);
      d.tail(dof) = null.transpose() * df.tail(nq);
      return true;
    };
    A.col(c) = ridders_column(difference);
  }
  return A;
}

// y moved onto Φ = 0 by Gauss–Newton steps of least norm (Φ_q's complete orthogonal
// decomposition); false when an evaluation fails or the steps do not settle.
bool onto_constraints(const Model& m, Workspace& ws, Eigen::VectorXd& y, std::vector<double>& f) {
  const int nq = ws.nq;
  for (int k = 0; k < 30; ++k) {
    if (!evaluate(m, ws, 0.0, y.data(), f.data())) return false;
    if (ws.m == 0) return true;
    const Eigen::VectorXd step = ws.phi_q.completeOrthogonalDecomposition().solve(-ws.phi);
    y.head(nq) += step;
    if (step.cwiseAbs().maxCoeff() <= 1e-15 * (1.0 + y.head(nq).cwiseAbs().maxCoeff()))
      return evaluate(m, ws, 0.0, y.data(), f.data());
  }
  return false;
}

// A static equilibrium near the assembled state y (at rest): Newton's method on the
// accelerations in the tangent space, r(a) = Nᵀ q̈ = 0, with the tangent stiffness Nᵀ ∂q̈/∂q N
// (reduced_jacobian's position columns), each step put back onto the constraints. As in Adams'
// statics, a step is cut so that no angle (or flexible link's slope) changes by more than
// kTurnLimit and no position by more than a limit (from kMoveShare of the mechanism's size,
// doubled while it cuts steps that help), and then taken whole: a step judged by whether |r| falls was cut to nothing by a bent link's axial
// accelerations (second order in the bending, removed by the next step), and a step of any size
// from near a turning point sent a pendulum round several turns. Where the stiffness is singular
// along r (nothing holds the direction a load pushes) the step goes with the acceleration to
// the limits. Throws std::runtime_error when no equilibrium is found.
Eigen::VectorXd static_equilibrium(const Model& m, Workspace& ws, Eigen::VectorXd y,
                                   Equilibrium& info, const std::atomic<int>* interrupt) {
  constexpr int kSteps = 100;
  constexpr double kTurnLimit = 0.2, kMoveShare = 0.2, kSettled = 1e-10;
  const int nq = ws.nq;
  const Eigen::VectorXd q0 = y.head(nq);
  // Which coordinates are angles (a rigid body's φ) or slopes (a flexible link's r'), and the
  // mechanism's size: the box around its bodies' and nodes' positions and the ground points of
  // its joints and loads.
  std::vector<char> kind(nq, 'x');  // x: a position; a: a rigid body's angle; s: a slope
  Vec2 lo = Vec2::Constant(INFINITY), hi = Vec2::Constant(-INFINITY);
  auto extend = [&](const Vec2& p) { lo = lo.cwiseMin(p), hi = hi.cwiseMax(p); };
  for (int b = 0; b < ws.nb; ++b) {
    const BodyBlock& bl = ws.blocks[b];
    const int per = m.bodies[b].flexible() ? beam::kNodeCoordinates : bl.size;
    for (int i = 0; i < bl.size; ++i)
      if (i % per >= 2) kind[bl.offset + i] = m.bodies[b].flexible() ? 's' : 'a';
    for (int i = 0; i + 1 < bl.size; i += per) extend(y.segment<2>(bl.offset + i));
  }
  for (const Joint& j : m.joints)
    for (const PointRef* p : {&j.a, &j.b})
      if (p->body == kGround) extend(p->s);
  for (const Load& l : m.loads)
    for (const PointRef* p : {&l.a, &l.b})
      if (p->body == kGround) extend(p->s);
  const double size = (hi - lo).allFinite() && (hi - lo).norm() > 1e-12 ? (hi - lo).norm() : 1e-3;
  // The positions' limit doubles whenever it cut a step that then lowered |r|: an equilibrium
  // 33 sizes away (a soft spring's stretch) or a mechanism whose box is a point (its size taken
  // as 1 mm) is reached in a few more steps instead of never.
  double move_limit = kMoveShare * size;
  double largest_r = 0.0;  // the largest |r| met: what round-off in r is measured against

  std::vector<double> f(ws.ny);
  Eigen::MatrixXd null;
  auto residual = [&](Eigen::VectorXd& yy, Eigen::VectorXd& r) {
    if (!onto_constraints(m, ws, yy, f)) return false;
    null = tangent_basis(ws);
    r = null.transpose() * Eigen::Map<const Eigen::VectorXd>(f.data() + nq, nq);
    return true;
  };
  auto norm = [](const Eigen::VectorXd& v) { return v.size() ? v.cwiseAbs().maxCoeff() : 0.0; };
  Eigen::VectorXd r;
  if (!residual(y, r)) throw std::runtime_error("the initial configuration cannot be evaluated");
  const double scale = std::max({norm(r), m.gravity.norm(), 1e-300});
  // Converged when the accelerations are 1e-10 of their first size (or of g), or when Newton's
  // step, which would remove what is left, moves no position by more than kSettled of the
  // mechanism's size and no angle or slope by more than kSettled: a stiff link's accelerations
  // stay at their round-off (3e-6 m/s² for a steel wire, against 189 at the start; 2e-3 for
  // the compliant mechanism's flexure, against 1.6e5 after the first step).
  int step = 0;
  bool converged = norm(r) <= 1e-10 * scale, unheld = false;
  for (; step < kSteps && !converged; ++step) {
    if (interrupt && interrupt->load() != 0) throw std::runtime_error("interrupted");
    largest_r = std::max(largest_r, norm(r));
    const int dof = static_cast<int>(null.cols());
    const Eigen::MatrixXd K = reduced_jacobian(m, ws, y, null, dof, interrupt).bottomRows(dof);
    Eigen::VectorXd da = K.completeOrthogonalDecomposition().solve(-r);
    unheld = norm(K * da + r) > 0.5 * norm(r);
    Eigen::VectorXd move = null * da;
    bool negligible = !unheld;
    for (int i = 0; i < nq && negligible; ++i)
      negligible = std::abs(move[i]) <= kSettled * (kind[i] == 'x' ? size : 1.0);
    if (negligible) {  // taken, and the last
      Eigen::VectorXd trial = y, rt;
      trial.head(nq) += move;
      if (residual(trial, rt) && norm(rt) <= norm(r)) y = std::move(trial), r = std::move(rt), ++step;
      // What is left must be round-off of the largest accelerations met, not a load that a
      // spurious stiffness (a spring between coincident points) claims to hold.
      converged = norm(r) <= 1e-6 * largest_r;
      break;
    }
    if (unheld) move = null * r;  // with the acceleration, to the limits below
    double cut = unheld ? INFINITY : 1.0;
    bool moves_cut = false;
    for (int i = 0; i < nq; ++i)
      if (move[i] != 0.0) {
        const double c = (kind[i] == 'x' ? move_limit : kTurnLimit) / std::abs(move[i]);
        if (c < cut) cut = c, moves_cut = kind[i] == 'x';
      }
    if (!std::isfinite(cut)) break;
    bool taken = false;
    const double before = norm(r);
    for (int tries = 0; tries < 20 && !taken; ++tries, cut /= 2) {
      Eigen::VectorXd trial = y, rt;
      trial.head(nq) += cut * move;
      if (residual(trial, rt)) y = std::move(trial), r = std::move(rt), taken = true;
    }
    if (!taken) break;
    if (moves_cut && norm(r) < before) move_limit *= 2;
    converged = norm(r) <= 1e-10 * scale;
  }
  if (!converged) {
    std::ostringstream s;
    s.precision(3);
    s << "no static equilibrium found near the initial configuration: after " << step
      << (step == 1 ? " Newton step" : " Newton steps") << " the accelerations at rest are still "
      << norm(r) << " (m/s² or rad/s²)";
    if (unheld)
      s << "; nothing holds the direction the loads push (a slider pushed along its guide)";
    throw std::runtime_error(s.str());
  }
  info.newton_steps = step;
  info.residual = norm(r);
  const std::vector<std::string> names = state_names(m, ws);
  for (int i = 0; i < nq && step > 0; ++i) {
    const double d = std::abs(y[i] - q0[i]);
    if (kind[i] == 'x' && d > info.largest_move)
      info.largest_move = d, info.largest_move_coordinate = names[i];
    if (kind[i] == 'a' && d > info.largest_turn)
      info.largest_turn = d, info.largest_turn_coordinate = names[i];
  }
  return y;
}

}  // namespace

LinearModes linear_modes(const Model& model, bool at_equilibrium,
                        const std::atomic<int>* interrupt) {
  Model m = ideal_model(model);
  {
    // Every driven coordinate held where it starts: at initial + f(0) (a position profile's
    // f(0) = 0.5 was dropped, and a spring was linearised at the wrong length); a constant
    // speed's ω·0 and a speed profile's integral start at 0.
    const Workspace at_start(m);
    for (size_t d = 0; d < m.drivers.size(); ++d) {
      Driver& drv = m.drivers[d];
      if (drv.profile == DriverProfile::position) {
        double f = 0.0, fd = 0.0, fdd = 0.0;  // (f apart: driver_motion reads drv.initial)
        driver_motion(m, at_start, static_cast<int>(d), 0.0, nullptr, f, fd, fdd);
        drv.initial = f;
      }
      drv.profile = DriverProfile::constant_speed;
      drv.speed = 0.0;
      drv.expression.clear();
    }
  }
  // No constraint stabilisation: Baumgarte's terms are not the mechanism's, and the difference
  // steps leave the constraints by O(h²), which they answered with a spring of β² in every
  // direction the constraints' curvature turns: a point mass on a 1e-5 m rod swung at β/2π =
  // 15.9 Hz instead of 157.6, a parallelogram in line had a mode at 10.45 Hz.
  m.solver.baumgarte_alpha = m.solver.baumgarte_beta = 0.0;
  Workspace ws(m);
  Eigen::VectorXd y = initial_state(m, ws);
  const int nq = ws.nq;
  y.segment(nq, nq).setZero();
  LinearModes out;
  if (at_equilibrium) y = static_equilibrium(m, ws, y, out.equilibrium.emplace(), interrupt);
  std::vector<double> f(ws.ny);
  if (!evaluate(m, ws, 0.0, y.data(), f.data()))
    throw std::runtime_error("the initial configuration cannot be evaluated");
  const Eigen::MatrixXd null = tangent_basis(ws);
  out.dof = static_cast<int>(null.cols());
  if (out.dof == 0) return out;
  const int n2 = 2 * out.dof;
  Eigen::MatrixXd A = reduced_jacobian(m, ws, y, null, n2, interrupt);
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
