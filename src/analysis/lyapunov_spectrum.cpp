#include "analysis/lyapunov_spectrum.hpp"

#include <Eigen/QR>
#include <cmath>
#include <stdexcept>

namespace lash {

namespace {

/// Weighted norm ‖v‖_w.
double weighted_norm(const Eigen::VectorXd& v, const Eigen::VectorXd& w) {
  return v.cwiseProduct(w).norm();
}

/// Weighted QR by modified Gram–Schmidt with one reorthogonalisation pass: on return
/// diag(w) V has orthonormal columns and V_in = V R. False if a column collapses: what is
/// left of it is at most `collapse` of its length (0: exactly nothing) or not finite.
bool weighted_qr(Eigen::MatrixXd& V, const Eigen::VectorXd& w, Eigen::MatrixXd& R,
                 double collapse) {
  const int p = static_cast<int>(V.cols());
  R = Eigen::MatrixXd::Zero(p, p);
  for (int k = 0; k < p; ++k) {
    const double before = weighted_norm(V.col(k), w);
    for (int pass = 0; pass < 2; ++pass)
      for (int j = 0; j < k; ++j) {
        const double c = V.col(j).cwiseProduct(w).dot(V.col(k).cwiseProduct(w));
        V.col(k) -= c * V.col(j);
        R(j, k) += c;
      }
    const double r = weighted_norm(V.col(k), w);
    if (!(r > collapse * before) || !std::isfinite(r)) return false;
    V.col(k) /= r;
    R(k, k) = r;
  }
  return true;
}

}  // namespace

bool forward_difference_jv(const FlowRhs& f, double t, const Eigen::VectorXd& y,
                           const Eigen::VectorXd& f0, const Eigen::MatrixXd& V,
                           const Eigen::VectorXd& weights, double step, Eigen::MatrixXd& JV) {
  JV.resize(f0.size(), V.cols());
  Eigen::VectorXd yp(y.size()), fp(f0.size());
  for (int k = 0; k < V.cols(); ++k) {
    const double len = weighted_norm(V.col(k), weights);
    if (!(len > 0.0)) {
      JV.col(k).setZero();
      continue;
    }
    const double sigma = step / len;
    yp = y + sigma * V.col(k);
    if (!f(t, yp, fp)) return false;
    JV.col(k) = (fp - f0) / sigma;
  }
  return true;
}

bool tangent_rk4_step(const TangentMap& jv, double t0, double t1, Eigen::MatrixXd& V) {
  const double h = t1 - t0, tm = t0 + 0.5 * h;
  Eigen::MatrixXd k1, k2, k3, k4, tmp;
  if (!jv(t0, V, k1)) return false;
  tmp = V + 0.5 * h * k1;
  if (!jv(tm, tmp, k2)) return false;
  tmp = V + 0.5 * h * k2;
  if (!jv(tm, tmp, k3)) return false;
  tmp = V + h * k3;
  if (!jv(t1, tmp, k4)) return false;
  V += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  return true;
}

Eigen::MatrixXd saltation_matrix(const Eigen::MatrixXd& D, const Eigen::VectorXd& f_minus,
                                 const Eigen::VectorXd& f_plus, const Eigen::VectorXd& grad_h,
                                 double h_t) {
  const long n = D.rows();
  if (D.cols() != n || f_minus.size() != n || f_plus.size() != n || grad_h.size() != n)
    throw std::invalid_argument("saltation_matrix: sizes disagree");
  const double rate = grad_h.dot(f_minus) + h_t;  // dh/dt along the trajectory at the crossing
  if (!(std::abs(rate) > 0.0) || !std::isfinite(rate))
    throw std::invalid_argument("saltation_matrix: tangential crossing (dh/dt = 0)");
  return D + (f_plus - D * f_minus) * grad_h.transpose() / rate;
}

TangentSpectrum::TangentSpectrum(Eigen::MatrixXd V0, Eigen::VectorXd weights, double t0)
    : V_(std::move(V0)), w_(std::move(weights)), t0_(t0), t_(t0) {
  if (V_.cols() < 1 || V_.rows() != w_.size())
    throw std::invalid_argument("TangentSpectrum: expected n × p vectors (p ≥ 1) and n weights");
  // Initial columns left with round-off only (1e-12 of their length) depended on the others.
  Eigen::MatrixXd R;
  if (!weighted_qr(V_, w_, R, 1e-12))
    throw std::invalid_argument("TangentSpectrum: the initial vectors are dependent");
  log_sum_ = Eigen::VectorXd::Zero(V_.cols());
}

bool TangentSpectrum::renormalise(double t, bool record) {
  Eigen::MatrixXd V = V_, R;
  if (!weighted_qr(V, w_, R, 0.0)) return false;
  for (int k = 0; k < V.cols(); ++k) log_sum_[k] += std::log(R(k, k));
  V_ = std::move(V);
  t_ = t;
  if (!record) return true;
  ++count_;
  history_time.push_back(t);
  history.push_back(exponents());
  return true;
}

Eigen::VectorXd TangentSpectrum::exponents() const {
  if (!(t_ > t0_)) return Eigen::VectorXd::Zero(V_.cols());
  return log_sum_ / (t_ - t0_);
}

}  // namespace lash
