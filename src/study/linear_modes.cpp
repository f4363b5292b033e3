#include "study/linear_modes.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/dynamics.hpp"
#include "study/run_analysis.hpp"

namespace lash {

LinearModes linear_modes(const Model& model) {
  Model m = ideal_model(model);
  for (Driver& d : m.drivers) {  // hold every driven coordinate where it starts
    d.profile = DriverProfile::constant_speed;
    d.speed = 0.0;
    d.expression.clear();
  }
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

  // A = Bᵀ J B on the basis B = [(n, 0), (0, n)], J by central differences.
  const int n2 = 2 * out.dof;
  Eigen::MatrixXd A(n2, n2);
  const double h = 1e-6;
  for (int c = 0; c < n2; ++c) {
    Eigen::VectorXd b = Eigen::VectorXd::Zero(ny);
    if (c < out.dof)
      b.head(nq) = null.col(c);
    else
      b.segment(nq, nq) = null.col(c - out.dof);
    const Eigen::VectorXd yp = y + h * b, ym = y - h * b;
    if (!evaluate(m, ws, 0.0, yp.data(), f.data()) || !evaluate(m, ws, 0.0, ym.data(), fm.data()))
      throw std::runtime_error("the linearisation cannot be evaluated");
    Eigen::VectorXd df(2 * nq);
    for (int i = 0; i < 2 * nq; ++i) df[i] = (f[i] - fm[i]) / (2 * h);
    A.col(c).head(out.dof) = null.transpose() * df.head(nq);
    A.col(c).tail(out.dof) = null.transpose() * df.tail(nq);
  }
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
