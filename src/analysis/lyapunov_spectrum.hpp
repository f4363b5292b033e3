#pragma once
/// @file lyapunov_spectrum.hpp
/// Model-free pieces of the variational Lyapunov spectrum (Benettin, Galgani, Giorgilli &
/// Strelcyn 1980, "Lyapunov characteristic exponents for smooth dynamical systems and for
/// Hamiltonian systems; a method for computing all of them", Meccanica 15): p tangent vectors
/// V (n × p) integrated by the variational equation V' = J(t) V along a reference trajectory,
/// mapped through discontinuities by saltation matrices (Müller 1995, "Calculation of Lyapunov
/// exponents for dynamic systems with discontinuities", Chaos, Solitons & Fractals 5(9)), and
/// renormalised by QR: λ_i = Σ ln |R_ii| / (t − t0).
#include <Eigen/Core>
#include <functional>
#include <vector>

namespace lash {

/// Right-hand side f(t, y) → ydot; false if it cannot be evaluated.
using FlowRhs = std::function<bool(double t, const Eigen::VectorXd& y, Eigen::VectorXd& ydot)>;

/// Jacobian–vector products at the reference state of time t: JV = J(t) V, column by column.
/// False if the right-hand side cannot be evaluated.
using TangentMap = std::function<bool(double t, const Eigen::MatrixXd& V, Eigen::MatrixXd& JV)>;

/// J(t, y) V by forward differences, JV_k = (f(y + σ_k v_k) − f(y)) / σ_k with
/// σ_k = step / ‖v_k‖_w (weighted norm, as TangentSpectrum; a zero column gives 0). `f0` is
/// f(t, y). Error O(σ‖f''‖) from truncation plus O(ε_machine |f| / σ) from round-off, so `step`
/// is about √ε_machine times the state's scale. False if an evaluation fails.
bool forward_difference_jv(const FlowRhs& f, double t, const Eigen::VectorXd& y,
                           const Eigen::VectorXd& f0, const Eigen::MatrixXd& V,
                           const Eigen::VectorXd& weights, double step, Eigen::MatrixXd& JV);

/// One classical Runge–Kutta step of the linear variational equation V' = J(t) V from t0 to t1
/// (J evaluated at t0, (t0 + t1)/2 and t1; order 4). False if `jv` fails.
bool tangent_rk4_step(const TangentMap& jv, double t0, double t1, Eigen::MatrixXd& V);

/// The saltation matrix of a transversal crossing of h(t, y) = 0 followed by the jump map
/// y⁺ = g(y⁻) (Müller 1995; without a jump, D = I, it is S = I + (f⁺ − f⁻)∇hᵀ/(∇hᵀf⁻ + ∂h/∂t)):
///   S = D + (f⁺ − D f⁻) ∇hᵀ / (∇hᵀ f⁻ + ∂h/∂t),   D = ∂g/∂y at the crossing.
/// f⁻, f⁺: the vector field before and after (at y⁻ and y⁺). Throws std::invalid_argument when
/// the crossing is tangential (|∇hᵀ f⁻ + ∂h/∂t| = 0): a grazing contact has no saltation matrix.
Eigen::MatrixXd saltation_matrix(const Eigen::MatrixXd& D, const Eigen::VectorXd& f_minus,
                                 const Eigen::VectorXd& f_plus, const Eigen::VectorXd& grad_h,
                                 double h_t = 0.0);

/// Tangent vectors with QR (Gram–Schmidt) renormalisation in the weighted norm
/// ‖v‖_w² = Σ (w_i v_i)². Entries with weight 0 are carried along (transformed with the others)
/// but not measured: states slaved to the measured ones, such as an impact velocity that is
/// reset at every contact onset.
class TangentSpectrum {
 public:
  /// `V0` (n × p, p ≥ 1) spans the directions followed; it is orthonormalised (in the weighted
  /// norm) at once without counting. Throws std::invalid_argument if its columns are dependent
  /// in that norm or the sizes disagree.
  TangentSpectrum(Eigen::MatrixXd V0, Eigen::VectorXd weights, double t0);

  Eigen::MatrixXd& vectors() { return V_; }
  const Eigen::MatrixXd& vectors() const { return V_; }
  const Eigen::VectorXd& weights() const { return w_; }
  int size() const { return static_cast<int>(V_.cols()); }

  /// QR of diag(w) V = Q R, V ← V R⁻¹, ln|R_ii| accumulated, and (with `record`) the running
  /// estimates recorded at time t and counted. Unrecorded renormalisations keep the vectors
  /// apart after a strongly stretching map (a near-grazing contact's saltation matrix is nearly
  /// of rank one). Returns false (and changes nothing) if a column has collapsed (|R_ii| = 0 or
  /// not finite).
  bool renormalise(double t, bool record = true);

  /// Running estimates Σ ln|R_ii| / (t − t0), 1/time, in the order of the columns (descending
  /// once the vectors have aligned); zeros before the first renormalisation.
  Eigen::VectorXd exponents() const;
  int renormalisations() const { return count_; }
  double start() const { return t0_; }
  double last_time() const { return t_; }

  /// (time, estimates) after every renormalisation: the convergence history.
  std::vector<double> history_time;
  std::vector<Eigen::VectorXd> history;

 private:
  Eigen::MatrixXd V_;
  Eigen::VectorXd w_, log_sum_;
  double t0_ = 0.0, t_ = 0.0;
  int count_ = 0;
};

}  // namespace lash
