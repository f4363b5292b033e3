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
/// least-squares solution. The factorisation is a sparse LDLᵀ without pivoting (FixedPatternLdlt:
/// Eigen's symbolic analysis, the numeric phase on the pattern it gives) in an elimination order
/// computed once per pattern: Eigen's approximate minimum degree (AMD) on
/// the graph of bodies coupled by constraint rows, each body's coordinates followed by the rows
/// anchored to it (a row is anchored to the earliest of its bodies whose coordinates it, with
/// the rows already anchored there, constrains independently). Then every leading block of the
/// ordered system is nonsingular and the fill follows the body graph: a crank shared by N
/// slider-cranks costs O(N), where the Schur complement W alone has a dense block of 2N + 3 rows.
#include <Eigen/Core>
#include <Eigen/Cholesky>
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

/// Which redundant rows are dropped at assembly (rows_to_keep_by_share): the last row in the model's
/// order whose share of Φ_q's left null space (its entry's size) is at least this fraction of
/// the largest share. With 0 that is the model's order; a row whose share is near 0 (a crank
/// along a world axis makes one row of its redundant joint carry none of the redundancy) would
/// leave the rows kept nearly dependent.
inline constexpr double kDropShare = 0.1;

/// A redundant mechanism whose rows kept are this close to dependent (the smallest singular
/// value of their Φ_q against the largest, at assembly and at every configuration probed
/// nearby: ConstraintSolver::rank_reference) is warned of at assembly: its joints nearly repeat
/// one another without quite agreeing (two pins 1e-7 m apart), so they hold it by a lever of
/// that size, with reactions of about 1/ratio times the loads and very small steps.
inline constexpr double kNearlyRedundant = 1e-6;

/// The regularisation of the augmented system: row a gets ε_a = kRegularisation · W_aa, its own
/// diagonal entry of W = Φ_q M⁻¹ Φ_qᵀ at assembly (about 100 units of round-off of that entry,
/// so that no pivot changes sign by round-off), i.e. εD with D = diag(W). It changes λ by at most
/// kRegularisation/σ_min(Ŵ) relative in the D-weighted norm, Ŵ = D^{-1/2} W D^{-1/2} (unit
/// diagonal): scaling each row by its own entry keeps bodies of very different mass (a 4.5 g
/// flexible pivot beside 1 kg links: cond(W) 1.5e9, cond(Ŵ) far less) from raising the error of
/// the heavy bodies' reactions. Below 1e-9 for any Ŵ whose condition number is below 1e5.
inline constexpr double kRegularisation = 1e-14;

/// Near a singular position (Φ_q losing rank: a parallelogram in line, a toggle) the pivot of
/// the row that becomes dependent goes to −εD. A row pivot d_a with |d_a| < kPivotFloor·r_a,
/// r_a = |d_a| at assembly (ConstraintSolver::pivot_reference), is set to −kPivotFloor·r_a (a
/// modified LDLᵀ): that row's equation is softened for the instant, with a compliance of
/// 1/(kPivotFloor·r_a), so that λ stays bounded and the factorisation never breaks down; its sign
/// can no longer be lost to round-off. No example comes within a factor 1e3 of
/// kNearSingular·r_a (tests/test_constraint_solver.cpp), so it changes nothing away from
/// singular positions.
inline constexpr double kPivotFloor = 1e-8;

/// A row pivot with |d_a| < kNearSingular·r_a (about 1e-3 rad from a parallelogram's in-line
/// position) marks the configuration as near-singular: the simulation then projects the state
/// back onto the constraints after each step (project_onto_constraints in core/dynamics.hpp),
/// which Baumgarte's terms alone cannot be trusted to do there.
inline constexpr double kNearSingular = 1e-6;

/// A row pivot at assembly below kReferenceShare of the same row's largest pivot at the
/// configurations drawn around it for Φ_q's pattern (JacobianPattern::drawn) marks an assembly
/// within about √kReferenceShare rad of a singular position, where the pivot is about s² of
/// its size elsewhere: it cannot be the row's reference (with a reference about 0 the floor is
/// about 0 and the projection never acts, and the singular positions on the way are passed
/// with λ nearly unbounded). Such a row's reference is that largest drawn pivot, or the largest
/// met during the run if larger (update_pivot_references). A driven unit parallelogram
/// assembled 1e-4 rad from in line took 141 526 steps (68 173 rejected) for 1 s, 1e-3 rad
/// 70 267, exactly in line 19 570 in its first 1e-5 s; one continued from its in-line position
/// 95 786 steps for 0.56 s. Bodies of very different mass make a pivot small at every
/// configuration alike (3e-8 of W_aa for the 4.5 g pivot of erkaya_compliant_beam.yaml), not
/// against the drawn ones. Rows chosen again during the run (reselect_redundant_rows) take the
/// larger of their pivot there and the drawn one, whatever the share: a choice is made where
/// the rows kept so far grew weak, often a few degrees from a singular position, where the new
/// rows' pivots are a few percent of their size elsewhere. A redundant double parallelogram
/// driven at 2000 rpm under BDF took its references there; its projection window and floor
/// then lay so close to the in-line position that the coupler's angle drifted 2.5 times further
/// at each in-line passage (1.8e-12 to 2.3e-9 rad) and the joints came apart within 0.25 s
/// (29–38 kJ booked as stabilization work); with the drawn references it runs 1 s at 2000 and
/// 3000 rpm, rtol 1e-7 and 1e-9, the stabilization work below 1e-3 of the kinetic energy.
inline constexpr double kReferenceShare = 1e-3;

/// L D Lᵀ of a sparse symmetric matrix given by its upper triangle in elimination order, for
/// many matrices of one pattern. The symbolic analysis is Eigen's SimplicialLDLT::analyzePattern
/// (elimination tree, column counts of L); from it the pattern of L is found once, and with it
/// the arithmetic of the left-looking algorithm as a flat list: for each entry of L (and each
/// pivot), where its value comes from in the matrix and the pairs (k, L(i,k)·D_k) it is
/// reduced by,
///
///     D_i    = A_ii − Σ_k L(i,k) U(i,k),      U(i,k) = L(i,k) D_k,
///     U(j,i) = A_ji − Σ_k L(j,k) U(i,k),      L(j,i) = U(j,i) / D_i   (j > i),
///
/// the sums over the columns k < i where both entries are in the pattern. A factorisation is then
/// that list run once, with no tree walk, scatter or gather (the 16 × 16 system of the Flores
/// example: 41 entries, 48 products).
///
/// Values of A that never change (M, most of Φ_q's entries: the ±1 of a revolute row's
/// positions, a driver's 1) can be named at the analysis. An entry of the list whose value and
/// products all come from such values, and whose pivot does, is the same at every factorisation:
/// it is computed by the first successful one only, and later ones run the rest of the list (on
/// the Flores example 23 of the 41 entries, with all 48 products: what is left out is M's
/// pivots and the entries of L in M's columns whose Φ_q entry is constant).
/// The list holds two indices per product, i.e. 8 bytes per multiply-add of the factorisation:
/// at most 405 products (3.2 KB) among the examples (erkaya_compliant_beam.yaml, 65 unknowns).
class FixedPatternLdlt {
 public:
  using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
  /// The pattern of `upper` (its values are not read). `fixed`, if not empty, holds per value
  /// of `upper` (its slot in valuePtr()) whether it is the same in every matrix factorised.
  void analyze(const SparseMatrix& upper, const std::vector<bool>& fixed = {});
  /// Factors `upper` (the analysed pattern). Stops and returns false at the first pivot d_k
  /// whose sign is not sign[k] (+1 or −1), before dividing by it. After one successful call,
  /// the part of the factorisation that depends only on fixed values is not computed again.
  /// With floors set (set_row_floors), a pivot of sign −1 above −near[k] raises near_singular(),
  /// and one above −floor[k] is set to −floor[k] (counted in clamped()).
  bool factorize(const SparseMatrix& upper, const std::vector<signed char>& sign);
  /// Per pivot: its floor and its near-singular threshold (0 for the pivots of sign +1).
  void set_row_floors(std::vector<double> floor, std::vector<double> near) {
    floor_ = std::move(floor);
    near_ = std::move(near);
  }
  /// One pivot's floor and near-singular threshold (set_row_floors first).
  void set_row_floor(int k, double floor, double near) { floor_[k] = floor, near_[k] = near; }
  long clamped() const { return clamped_; }  ///< pivots set to their floor, in all factorisations
  bool near_singular() const { return near_singular_; }  ///< since the last clear
  void clear_near_singular() { near_singular_ = false; }
  /// Whether the last factorisation computed a pivot below its near-singular threshold (a pivot
  /// that never varies is computed by the first one only: it equals its reference).
  bool weak_pivot() const { return weak_pivot_; }
  /// x ← A⁻¹x, in elimination order.
  void solve(Eigen::VectorXd& x) const;
  const Eigen::VectorXd& diagonal() const { return d_; }  ///< D of L D Lᵀ

 private:
  /// Per entry of L's strict lower triangle, column by column: its row and its column.
  std::vector<int> col_row_, col_of_;
  std::vector<double> l_, u_;  ///< L(j,i) and U(j,i) = L(j,i)·D_i, by slot
  /// The list, in order (column by column: its pivot, then its entries): per entry e, the slot
  /// of A's value in `upper` (−1: a fill-in, 0), what it computes (target_ ≥ 0: that slot of
  /// L; −1 − i: pivot i) and its products [pair_begin_[e], pair_begin_[e+1]) of
  /// l_[pair.l]·u_[pair.u].
  struct Pair {
    int l, u;
  };
  std::vector<int> source_, target_, pair_begin_;
  std::vector<Pair> pairs_;
  /// The entries (indices into the list, in order) that depend on a value not fixed.
  std::vector<int> varying_;
  bool factored_ = false;  ///< a factorisation succeeded: the fixed entries hold their values
  Eigen::VectorXd d_, d_inverse_;  ///< D and its inverse
  std::vector<double> floor_, near_;
  long clamped_ = 0;
  bool near_singular_ = false;
  bool weak_pivot_ = false;
};

/// Φ_q's pattern (ws.m × ws.nq): `nonzero` is true at the entries a row may write, `fixed` at
/// those of them whose value is the same at every configuration.
struct JacobianPattern {
  Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic> nonzero, fixed;
  /// Per row of Φ_q: kept (not redundant). Empty: independent_rows of the Φ_q given.
  std::vector<bool> keep;
  /// Φ_q at the configurations drawn around the assembled one (a row's pivot there is its
  /// typical size: the reference of a row assembled near a singular position, kReferenceShare).
  std::vector<Eigen::MatrixXd> drawn;
  /// The largest rank_ratio of Φ_q at the assembled configurations nearby where the rows were
  /// counted again (redundant mechanisms only; 0 if none): with the assembled one's, the
  /// reference of σ_(m−dropped)/σ_1 (kReselectRank), so that a mechanism assembled near a
  /// singular position does not take it there.
  double nearby_rank = 0.0;
  /// Φ_q at the nearby configuration where the redundant rows were chosen, for an assembly at a
  /// singular position of a redundant mechanism (empty: the assembled one). The warning names
  /// the joints the dropped rows are redundant with there: at the singular position more
  /// combinations span them.
  Eigen::MatrixXd counted;
};

/// The sparse solver of one workspace: pattern, elimination order and factorisation.
struct ConstraintSolver {
  using SparseMatrix = FixedPatternLdlt::SparseMatrix;

  std::vector<int> active;      ///< constraint rows kept (ascending); redundant ones dropped
  std::vector<int> pos;         ///< position of coordinate k (k < nq) and active row a (nq + a)
  SparseMatrix k;               ///< upper triangle of the augmented matrix, in elimination order
  std::vector<signed char> sign;  ///< per position: the pivot's sign, +1 (coordinate) or −1 (row)
  std::vector<int> slot_reg;    ///< per active row: its −ε entry in k.valuePtr()
  std::vector<int> phi_begin;   ///< per active row: its range in phi_col / phi_slot
  std::vector<int> phi_col, phi_slot;  ///< Φ_q's pattern: coordinate and slot in k.valuePtr()
  /// The entries of Φ_q's pattern whose value changes with the configuration: (row of Φ_q,
  /// coordinate, slot in k.valuePtr()). The others keep the value written at the analysis.
  struct Entry {
    int row, col, slot;
  };
  std::vector<Entry> phi_varying;
  std::vector<double> w_diag;   ///< per active row: W_aa at assembly (M⁻¹ by its diagonal)
  /// Per active row: its base regularisation ε_a = kRegularisation · W_aa.
  std::vector<double> regularisation;
  /// Per active row: what its pivot's floor and near-singular threshold are relative to (its
  /// pivot at assembly, in magnitude; kReferenceShare for a row assembled near a singular
  /// position).
  std::vector<double> pivot_reference;
  /// Active rows assembled near a singular position (kReferenceShare): their reference is their
  /// largest pivot at the configurations drawn for Φ_q's pattern or met since
  /// (update_pivot_references).
  std::vector<int> provisional;
  FixedPatternLdlt ldlt;
  Eigen::VectorXd x;            ///< right-hand side, then solution, in elimination order
  /// Redundant rows (dropped at assembly), ascending, and what reporting the smallest
  /// multipliers takes (smallest_multipliers): a basis N of Φ_q's left null space (m × dropped,
  /// and one more column per weak row near a singular position), orthonormalised in place near
  /// a singular position, NᵀN otherwise, and a work vector.
  std::vector<int> dropped;
  JacobianPattern pattern;  ///< as given at set-up (reselect_redundant_rows builds again from it)
  /// σ_(m−dropped)/σ_1 of Φ_q, the largest at assembly and the configurations nearby
  /// (JacobianPattern::nearby_rank; kReselectRank)
  double rank_reference = 0.0;
  /// Evaluations left before the choice is tried again, after one refused near a singular
  /// position (kReselectWait).
  int reselect_wait = 0;
  std::vector<int> weak;  ///< active rows near a singular position (smallest_multipliers)
  Eigen::MatrixXd null_basis, null_gram;
  Eigen::VectorXd null_work;
};


/// Rows kept in order (greedy, modified Gram–Schmidt with reorthogonalisation): row i is
/// redundant when its component outside the span of the rows kept before it is at most
/// kRedundancyTolerance of its norm.
std::vector<bool> independent_rows(const Eigen::MatrixXd& phi_q);

/// σ_kept/σ_1 of Φ_q (its singular values in decreasing order): how far the `kept` rows are from
/// losing rank; 0 if kept ≤ 0 or Φ_q is 0.
double rank_ratio(const Eigen::MatrixXd& phi_q, int kept);

/// The rows kept when `count` of Φ_q's rows are redundant: per redundancy (greedy, the left null
/// space's basis deflated by each choice) the last row in order whose share is at least
/// kDropShare of the largest; rows in `never` (drivers) are not dropped.
std::vector<bool> rows_to_keep_by_share(const Eigen::MatrixXd& phi_q, int count,
                                        const std::vector<int>& never);

/// Sets up ws's constraint solver from Φ_q (ws.m × ws.nq) at an assembled configuration and
/// the pattern of Φ_q (entries outside `nonzero` must stay 0 at every configuration and the
/// `fixed` ones keep their value at phi_q: the solver reads neither again): drops the rows
/// `pattern.keep` leaves out (if empty, independent_rows of phi_q: the model's order, joints
/// then drivers), warns about them in ws.warnings naming the joints they are redundant with, and
/// computes the elimination order and the factorisation's pattern. Throws std::runtime_error if
/// a driver's equation is redundant (its motion would be dropped). `chosen_again`: the rows
/// were chosen again during the run (reselect_redundant_rows), and each row's pivot reference
/// is at least its largest pivot at the drawn configurations (kReferenceShare).
void prepare_constraint_solver(const Model& model, Workspace& ws, const Eigen::MatrixXd& phi_q,
                               const JacobianPattern& pattern, bool chosen_again = false);

/// Solves the augmented system at the current ws.phi_q, ws.g (applied forces) and ws.rhs_m
/// (γ_B): fills ws.qdd and ws.lambda (0 on dropped rows). Returns false if a value is not
/// finite (a row pivot near 0 is floored, kPivotFloor; a coordinate pivot cannot vanish).
bool solve_constraints(Workspace& ws);

/// With redundant rows, after solve_constraints (its factorisation): replaces ws.lambda by the
/// smallest multipliers (Euclidean norm over all rows) with the same generalised constraint
/// force Φ_qᵀλ, so that the reactions reported do not depend on which rows were dropped (the
/// model's order, the world's orientation): a double parallelogram's three cranks carry equal
/// shares. Φ_qᵀλ, hence the motion and every power, is unchanged up to O(ε) (kRegularisation).
/// Near a singular position (a row pivot below kNearSingular of its reference) the same is done
/// along the nearly self-equilibrated set of multipliers found by inverse iteration on the
/// factorisation: λ's component there is amplified Baumgarte terms and round-off, not the
/// reaction (Φ_qᵀλ changes by that set's small Φ_qᵀ image). Nothing elsewhere, without
/// redundant rows.
void smallest_multipliers(Workspace& ws);

/// Which rows of a redundant set are dropped matters to the factorisation: the rows kept lose
/// rank where a dropped row's share of the redundancy vanishes (a double parallelogram whose
/// dropped row is coupler_2's y equation, where the cranks lie along the world's x axis),
/// though Φ_q does not. A kept row whose pivot falls below kReselectPivot of its reference
/// (its value when the rows were chosen) has the rows chosen again (reselect_redundant_rows),
/// long before the pivot floor would soften it (kNearSingular, kPivotFloor).
inline constexpr double kReselectPivot = 1e-2;
/// The rows are not chosen again where the ratio σ_(m−dropped)/σ_1 of Φ_q's singular values
/// (the smallest the redundancy leaves to the largest) is below this fraction of its value at
/// assembly: the mechanism itself is then near a singular position, where every choice is weak
/// and pivots taken as references would make the floor useless (kPivotFloor carries the
/// instant). The ratio does not change with the world's axes.
inline constexpr double kReselectRank = 0.1;
/// After a choice refused there, or one that comes out as the rows already dropped (the kept
/// rows are weak by the mechanism's own position), the next this many evaluations do not try
/// again (each try is an SVD of Φ_q: near a singular position every evaluation would make one);
/// nor after a choice made: with several redundant rows the choices near a singular position
/// are many and about as weak (a five-crank double parallelogram's x equations), and switching
/// between them at every evaluation changed the right-hand side at every evaluation (BDF, rtol
/// 1e-7, failed 12° before an in-line position with error test failures at h = 3e-14 s).
inline constexpr int kReselectWait = 64;

/// With redundant rows: whether a kept row's pivot in the last factorisation is below
/// kReselectPivot of its reference. False without redundant rows, and while a refused choice
/// waits (kReselectWait, counted down here).
bool kept_rows_weak(Workspace& ws);

/// Chooses the rows to drop again at ws.phi_q: those where the redundancy is largest (per
/// basis vector of Φ_q's left null space, by a column-pivoted QR of its transpose: the rows
/// with the largest shares, never a driver's) and sets the solver up for them, keeping
/// ws.warnings (the run's, from assembly). Returns false, the solver unchanged, if the choice
/// is the one in use.
bool reselect_redundant_rows(const Model& model, Workspace& ws);

/// The joint or driver constraint row `row` belongs to: its name (`element`) and how messages
/// name it (`what`: "joint 'a3'", "driver 'd'").
struct RowElement {
  std::string element, what;
};
RowElement constraint_row_element(const Model& model, const Workspace& ws, int row);

/// The names in `names` (as messages name elements) whose `share` is at least `least`, other
/// than `except`, each once, in order, joined with ", "; "the others" if none.
std::string other_names(const std::vector<std::string>& names, const Eigen::VectorXd& share,
                        double least, const std::string& except);

}  // namespace lash
