#pragma once
/// @file constraint_solver.hpp
/// The constraint solve of every right-hand side. With the applied generalised forces g, the
/// Baumgarte-stabilised constraint accelerations γ_B = γ − 2αΦ̇ − β²Φ and the active constraint
/// rows Φ_q (redundant rows dropped at assembly), it solves the augmented system
///
///     [ M    Φ_qᵀ ] [  q̈ ]   [ g  ]
///     [ Φ_q  −εD  ] [ −λ ] = [ γ_B ],
///
/// i.e. M q̈ = g + Φ_qᵀ λ with (W + εD) λ = γ_B − Φ_q M⁻¹ g, W = Φ_q M⁻¹ Φ_qᵀ, D = diag(W) at
/// assembly. The matrix is
/// quasi-definite for every ε > 0 (M positive definite), so it has an LDLᵀ factorisation in any
/// symmetric order, also where Φ_q loses rank (singular positions): there λ is the damped
/// least-squares solution. The factorisation is Eigen's SimplicialLDLT (sparse, no pivoting) in
/// an elimination order computed once per pattern: Eigen's approximate minimum degree (AMD) on
/// the graph of bodies coupled by constraint rows, each body's coordinates followed by the rows
/// anchored to it (a row is anchored to the earliest of its bodies whose coordinates it, with
/// the rows already anchored there, constrains independently). Then every leading block of the
/// ordered system is nonsingular and the fill follows the body graph: a crank shared by N
/// slider-cranks costs O(N), where the Schur complement W alone has a dense block of 2N + 3 rows.
#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <vector>

namespace lash {

struct Model;
struct Workspace;

/// Relative tolerance of the redundancy test at assembly: a constraint row is redundant when
/// the part of it (a row of Φ_q) not spanned by the rows kept before it is at most this
/// fraction of its norm.
inline constexpr double kRedundancyTolerance = 1e-8;

/// The regularisation of the augmented system: row a gets ε_a = kRegularisation · W_aa, its own
/// diagonal entry of W = Φ_q M⁻¹ Φ_qᵀ at assembly (about 100 units of round-off of that entry,
/// so that no pivot changes sign by round-off), i.e. εD with D = diag(W). It changes λ by at most
/// kRegularisation/σ_min(Ŵ) relative in the D-weighted norm, Ŵ = D^{-1/2} W D^{-1/2} (unit
/// diagonal): scaling each row by its own entry keeps bodies of very different mass (a 4.5 g
/// flexible pivot beside 1 kg links: cond(W) 1.5e9, cond(Ŵ) far less) from raising the error of
/// the heavy bodies' reactions. Below 1e-9 for any Ŵ whose condition number is below 1e5.
inline constexpr double kRegularisation = 1e-14;

/// A factorisation that breaks down (a pivot of the wrong sign: W singular to working
/// precision) is repeated with ε multiplied by this factor, at most kRegularisationSteps times.
inline constexpr double kRegularisationGrowth = 1e3;
inline constexpr int kRegularisationSteps = 3;

/// The sparse solver of one workspace: pattern, elimination order and factorisation.
struct ConstraintSolver {
  using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
  /// SimplicialLDLT factoring a matrix given in its elimination order (upper triangle) without
  /// the copy Eigen's factorize() makes: the right-hand side allocates nothing.
  class Ldlt : public Eigen::SimplicialLDLT<SparseMatrix, Eigen::Upper, Eigen::NaturalOrdering<int>> {
   public:
    void factorize_in_place(const SparseMatrix& a) { this->template factorize_preordered<true>(a); }
    /// D of L D Lᵀ, by reference (vectorD() returns a copy).
    const Eigen::VectorXd& diagonal() const { return this->m_diag; }
  };

  std::vector<int> active;      ///< constraint rows kept (ascending); redundant ones dropped
  std::vector<int> pos;         ///< position of coordinate k (k < nq) and active row a (nq + a)
  SparseMatrix k;               ///< upper triangle of the augmented matrix, in elimination order
  std::vector<int> slot_reg;    ///< per active row: its −ε entry in k.valuePtr()
  std::vector<int> phi_begin;   ///< per active row: its range in phi_col / phi_slot
  std::vector<int> phi_col, phi_slot;  ///< Φ_q entries: coordinate and slot in k.valuePtr()
  std::vector<double> w_diag;   ///< per active row: W_aa at assembly (M⁻¹ by its diagonal)
  /// Per active row: its base regularisation ε_a = kRegularisation · W_aa.
  std::vector<double> regularisation;
  Ldlt ldlt;
  Eigen::VectorXd b, x;         ///< right-hand side and solution, in elimination order
  long regularised = 0;         ///< solves that needed more than the base regularisation
};

/// Sets up ws's constraint solver from Φ_q (ws.m × ws.nq) at an assembled configuration:
/// detects redundant rows (kept rows in the order of the model: joints, then drivers), warns
/// about them in ws.warnings naming the joints they are redundant with, and computes the
/// elimination order and the factorisation's pattern. Throws std::runtime_error if a driver's
/// equation is redundant (its motion would be dropped).
void prepare_constraint_solver(const Model& model, Workspace& ws, const Eigen::MatrixXd& phi_q);

/// Solves the augmented system at the current ws.phi_q, ws.g (applied forces) and ws.rhs_m
/// (γ_B): fills ws.qdd and ws.lambda (0 on dropped rows). Returns false if no regularisation up
/// to kRegularisation·kRegularisationGrowth^kRegularisationSteps gives a factorisation.
bool solve_constraints(Workspace& ws);

}  // namespace lash
