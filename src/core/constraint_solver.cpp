#include "core/constraint_solver.hpp"

#include <Eigen/Cholesky>
#include <Eigen/OrderingMethods>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/dynamics.hpp"
#include "core/elements/registry.hpp"

namespace lash {

namespace {

/// Anchored rows restricted to a body's block are accepted when their smallest singular value,
/// each row scaled to unit length, is at least this: they then stay independent at every
/// configuration near the assembled one.
constexpr double kAnchorConditioning = 1e-3;

/// The element each constraint row belongs to: (is_driver, index), and its number of rows.
struct RowOwner {
  bool driver = false;
  int index = 0;
};

std::vector<RowOwner> row_owners(const Model& model, const Workspace& ws) {
  std::vector<RowOwner> owner(ws.m);
  for (size_t ji = 0; ji < model.joints.size(); ++ji) {
    const int r0 = ws.row_of_joint[ji];
    if (r0 < 0) continue;
    const int n = kind_of(model.joints[ji]).rows(model, model.joints[ji]);
    for (int r = 0; r < n; ++r) owner[r0 + r] = {false, static_cast<int>(ji)};
  }
  for (size_t d = 0; d < model.drivers.size(); ++d)
    owner[ws.row_of_driver[d]] = {true, static_cast<int>(d)};
  return owner;
}

std::string owner_name(const Model& model, const RowOwner& o) {
  return o.driver ? "driver '" + model.drivers[o.index].name + "'"
                  : "joint '" + model.joints[o.index].name + "'";
}


/// Whether `rows` (of phi_q) restricted to body block `bl` are independent, well conditioned.
bool independent_on_block(const Eigen::MatrixXd& phi_q, const std::vector<int>& rows,
                          const BodyBlock& bl) {
  if (static_cast<int>(rows.size()) > bl.size) return false;
  Eigen::MatrixXd a(rows.size(), bl.size);
  for (size_t r = 0; r < rows.size(); ++r) {
    a.row(r) = phi_q.row(rows[r]).segment(bl.offset, bl.size);
    const double n = a.row(r).norm();
    if (!(n > 0.0)) return false;
    a.row(r) /= n;
  }
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(a).singularValues();
  return sv[sv.size() - 1] >= kAnchorConditioning;
}

/// A basis of Φ_q's left null space (count × m, the combinations of rows that vanish): the last
/// `count` left singular vectors of `svd`, with the columns of the rows in `never` (drivers',
/// never dropped) zeroed.
Eigen::MatrixXd left_null_basis(const Eigen::JacobiSVD<Eigen::MatrixXd>& svd, int count,
                                const std::vector<int>& never) {
  Eigen::MatrixXd basis = svd.matrixU().rightCols(count).transpose();
  for (int r : never) basis.col(r).setZero();
  return basis;
}

}  // namespace

double rank_ratio(const Eigen::MatrixXd& phi_q, int kept) {
  if (kept <= 0) return 0.0;
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(phi_q).singularValues();
  return sv[0] > 0.0 ? sv[kept - 1] / sv[0] : 0.0;
}

std::vector<bool> independent_rows(const Eigen::MatrixXd& phi_q) {
  const int m = static_cast<int>(phi_q.rows());
  std::vector<bool> keep(m, false);
  std::vector<Eigen::VectorXd> basis;
  for (int i = 0; i < m; ++i) {
    Eigen::VectorXd v = phi_q.row(i).transpose();
    const double n0 = v.norm();
    if (!(n0 > 0.0)) continue;
    for (int pass = 0; pass < 2; ++pass)
      for (const auto& q : basis) v -= q.dot(v) * q;
    const double n = v.norm();
    if (n > kRedundancyTolerance * n0) {
      keep[i] = true;
      basis.push_back(v / n);
    }
  }
  return keep;
}

std::vector<bool> rows_to_keep_by_share(const Eigen::MatrixXd& phi_q, int count,
                                        const std::vector<int>& never) {
  const int m = static_cast<int>(phi_q.rows());
  std::vector<bool> keep(m, true);
  if (count <= 0) return keep;
  Eigen::MatrixXd basis =
      left_null_basis(Eigen::JacobiSVD<Eigen::MatrixXd>(phi_q, Eigen::ComputeFullU), count, never);
  for (int j = 0; j < count; ++j) {
    double top = 0.0;
    for (int r = 0; r < m; ++r) top = std::max(top, basis.col(r).norm());
    if (!(top > 0.0)) break;
    int pick = m - 1;
    while (!(basis.col(pick).norm() >= kDropShare * top)) --pick;
    keep[pick] = false;
    const Eigen::VectorXd q = basis.col(pick) / basis.col(pick).norm();
    basis -= q * (q.transpose() * basis);  // the redundancies left, without the row picked
  }
  return keep;
}

/// The solver's rows, order and pattern; with `late`, every row is anchored to the last of its
/// bodies in the order.
static void build_solver(const Model& model, Workspace& ws, const Eigen::MatrixXd& phi_q,
                         const JacobianPattern& pattern, bool late) {
  auto s = std::make_unique<ConstraintSolver>();
  const int nq = ws.nq, m = ws.m;
  const std::vector<RowOwner> owner = row_owners(model, ws);

  // Redundant rows: dropped, named in a warning (a driver's: refused).
  const std::vector<bool> keep =
      pattern.keep.empty() ? independent_rows(phi_q) : pattern.keep;
  for (int i = 0; i < m; ++i) (keep[i] ? s->active : s->dropped).push_back(i);
  s->null_basis.resize(m, s->dropped.size());
  s->null_work.resize(nq + m - s->dropped.size());
  s->weak.reserve(s->active.size());
  ws.warnings.clear();
  if (static_cast<int>(s->active.size()) < m) {
    // Which kept rows span each dropped one: the least-squares combination of the kept rows.
    const Eigen::MatrixXd& at = pattern.counted.size() > 0 ? pattern.counted : phi_q;
    Eigen::MatrixXd kept(nq, s->active.size());
    for (size_t a = 0; a < s->active.size(); ++a) kept.col(a) = at.row(s->active[a]).transpose();
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(kept);
    for (int i = 0; i < m;) {
      // All rows of one element together.
      int end = i;
      while (end < m && owner[end].driver == owner[i].driver && owner[end].index == owner[i].index)
        ++end;
      int dropped = 0;
      std::vector<bool> with(m, false);
      for (int r = i; r < end; ++r) {
        if (keep[r]) continue;
        ++dropped;
        const Eigen::VectorXd c = qr.solve(Eigen::VectorXd(at.row(r).transpose()));
        const double cmax = c.cwiseAbs().maxCoeff();
        for (size_t a = 0; a < s->active.size(); ++a)
          if (std::abs(c[a]) > 1e-9 * cmax) with[s->active[a]] = true;
      }
      if (dropped > 0) {
        std::string names;
        RowOwner last{true, -1};
        int count = 0;
        for (int r = 0; r < m; ++r) {
          // Not the element itself: its kept equations take part, but it is named already.
          if (r >= i && r < end) continue;
          if (!with[r] || (owner[r].driver == last.driver && owner[r].index == last.index)) continue;
          last = owner[r];
          names += (count++ ? ", " : "") + owner_name(model, owner[r]);
        }
        const std::string what = owner_name(model, owner[i]);
        if (owner[i].driver)
          throw std::runtime_error(what + ": its equation is redundant with " + names +
                                   ": the motion it prescribes is already fixed; remove the "
                                   "driver or one of those");
        const int total = end - i, others = total - dropped;
        const std::string which =
            others == 0 ? (total == 1 ? "its equation is" : "all " + std::to_string(total) + " of its equations are")
                        : std::to_string(dropped) + " of its " + std::to_string(total) +
                              (dropped == 1 ? " equations is" : " equations are");
        ws.warnings.push_back(what + ": " + which + " redundant with " + names +
                              "; the motion is computed without " + (dropped == 1 ? "it" : "them") +
                              ", and the reactions reported are the smallest that hold the "
                              "mechanism (least squares over all joint equations: redundant "
                              "reactions are not unique)");
      }
      i = end;
    }
  }
  const int ma = static_cast<int>(s->active.size());

  // The regularisation: each row's own diagonal entry of W (constraint_solver.hpp), with M⁻¹
  // taken by the inverse of its diagonal (exact but for flexible links).
  const Eigen::RowVectorXd diag_inverse = ws.mass_diag.cwiseInverse().transpose();
  for (int a = 0; a < ma; ++a) {
    double w = phi_q.row(s->active[a]).cwiseAbs2().dot(diag_inverse);
    if (!(w > 0.0)) w = 1.0;
    s->w_diag.push_back(w);
    s->regularisation.push_back(kRegularisation * w);
  }

  // Body order: approximate minimum degree on the graph of bodies coupled by a row.
  const int nb = ws.nb;
  std::vector<int> body_order(nb);
  {
    std::vector<Eigen::Triplet<double>> t;
    for (int b = 0; b < nb; ++b) t.emplace_back(b, b, 1.0);
    for (int a = 0; a < ma; ++a) {
      const auto& rb = ws.row_bodies[s->active[a]];
      if (rb[0] >= 0 && rb[1] >= 0 && rb[0] != rb[1]) {
        t.emplace_back(rb[0], rb[1], 1.0);
        t.emplace_back(rb[1], rb[0], 1.0);
      }
    }
    ConstraintSolver::SparseMatrix g(nb, nb);
    g.setFromTriplets(t.begin(), t.end());
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> p;
    Eigen::AMDOrdering<int>()(g, p);  // p.indices()[new position] = body
    for (int i = 0; i < nb; ++i) body_order[i] = p.indices()[i];
  }
  std::vector<int> body_rank(nb);
  for (int i = 0; i < nb; ++i) body_rank[body_order[i]] = i;

  // Anchor the rows of each element to a body. Rows touching one body go to it. An element
  // coupling two bodies goes to the earlier one when its rows, with the rows already there,
  // are independent on that body's coordinates (then eliminating it leaves only the later body
  // coupled: a crank shared by N rods stays a 3-coordinate separator), to the later one
  // otherwise (its whole row then lies in eliminated coordinates).
  std::vector<std::vector<int>> anchored(nb);       // active-row indices
  std::vector<std::vector<int>> anchored_rows(nb);  // the same as rows of phi_q
  {
    std::vector<std::pair<int, int>> groups;  // [first, end) in active-row indices
    for (int a = 0; a < ma;) {
      int e = a + 1;
      while (e < ma && owner[s->active[e]].driver == owner[s->active[a]].driver &&
             owner[s->active[e]].index == owner[s->active[a]].index)
        ++e;
      groups.emplace_back(a, e);
      a = e;
    }
    auto bodies_of = [&](int a) {
      std::vector<int> bodies;
      for (int b : ws.row_bodies[s->active[a]])
        if (b >= 0 && std::find(bodies.begin(), bodies.end(), b) == bodies.end())
          bodies.push_back(b);
      std::sort(bodies.begin(), bodies.end(),
                [&](int x, int y) { return body_rank[x] < body_rank[y]; });
      return bodies;
    };
    auto anchor = [&](const std::pair<int, int>& gr, int b) {
      for (int a = gr.first; a < gr.second; ++a) {
        anchored[b].push_back(a);
        anchored_rows[b].push_back(s->active[a]);
      }
    };
    for (int pass = 0; pass < 2; ++pass)  // one-body elements first: they have no choice
      for (const auto& gr : groups) {
        const std::vector<int> bodies = bodies_of(gr.first);
        if ((bodies.size() == 1) != (pass == 0)) continue;
        int chosen = bodies.back();
        if (bodies.size() == 2) {
          std::vector<int> rows = anchored_rows[bodies[0]];
          for (int a = gr.first; a < gr.second; ++a) rows.push_back(s->active[a]);
          if (!late && independent_on_block(phi_q, rows, ws.blocks[bodies[0]])) chosen = bodies[0];
        }
        anchor(gr, chosen);
      }
    for (auto& v : anchored) std::sort(v.begin(), v.end());
  }

  // Elimination order: per body, its coordinates, then its anchored rows.
  const int n = nq + ma;
  s->pos.assign(n, -1);
  int next = 0;
  for (int b : body_order) {
    const BodyBlock& bl = ws.blocks[b];
    for (int k = bl.offset; k < bl.offset + bl.size; ++k) s->pos[k] = next++;
    for (int a : anchored[b]) s->pos[nq + a] = next++;
  }

  // Each active row's entries: the coordinates of its bodies in Φ_q's pattern.
  std::vector<std::vector<int>> row_cols(ma);
  for (int a = 0; a < ma; ++a) {
    const auto& rb = ws.row_bodies[s->active[a]];
    for (int bi = 0; bi < 2; ++bi) {
      const int b = rb[bi];
      if (b < 0 || (bi == 1 && b == rb[0])) continue;
      const BodyBlock& bl = ws.blocks[b];
      for (int k = bl.offset; k < bl.offset + bl.size; ++k)
        if (pattern.nonzero(s->active[a], k)) row_cols[a].push_back(k);
    }
  }

  // Pattern of the upper triangle in that order: the diagonal, M's coupling (flexible links),
  // and Φ_q's.
  std::vector<Eigen::Triplet<double>> t;
  for (int v = 0; v < n; ++v) t.emplace_back(s->pos[v], s->pos[v], 1.0);
  for (const auto& e : ws.mass_coupling)
    t.emplace_back(std::min(s->pos[e.i], s->pos[e.j]), std::max(s->pos[e.i], s->pos[e.j]), 0.0);
  for (int a = 0; a < ma; ++a)
    for (int k : row_cols[a]) {
      const int i = s->pos[k], j = s->pos[nq + a];
      t.emplace_back(std::min(i, j), std::max(i, j), 0.0);
    }
  s->k.resize(n, n);
  s->k.setFromTriplets(t.begin(), t.end());
  s->k.makeCompressed();
  auto slot = [&](int u, int v) {
    const int i = std::min(s->pos[u], s->pos[v]), j = std::max(s->pos[u], s->pos[v]);
    return static_cast<int>(&s->k.coeffRef(i, j) - s->k.valuePtr());
  };
  s->k.coeffs().setZero();
  for (int k = 0; k < nq; ++k) s->k.valuePtr()[slot(k, k)] = ws.mass_diag[k];
  for (const auto& e : ws.mass_coupling) s->k.valuePtr()[slot(e.i, e.j)] = e.value;
  // Fixed values: M, the fill, Φ_q's fixed entries (written here once); not the −ε entries,
  // which grow when a factorisation is repeated.
  std::vector<bool> fixed(s->k.nonZeros(), true);
  for (int a = 0; a < ma; ++a) {
    const int row = s->active[a];
    s->slot_reg.push_back(slot(nq + a, nq + a));
    fixed[s->slot_reg.back()] = false;
    s->phi_begin.push_back(static_cast<int>(s->phi_col.size()));
    for (int k : row_cols[a]) {
      const int sl = slot(k, nq + a);
      s->phi_col.push_back(k);
      s->phi_slot.push_back(sl);
      s->k.valuePtr()[sl] = phi_q(row, k);
      if (!pattern.fixed(row, k)) {
        s->phi_varying.push_back({row, k, sl});
        fixed[sl] = false;
      }
    }
  }
  s->phi_begin.push_back(static_cast<int>(s->phi_col.size()));
  s->sign.assign(n, 1);
  for (int a = 0; a < ma; ++a) s->sign[s->pos[nq + a]] = -1;
  s->ldlt.analyze(s->k, fixed);
  s->x.resize(n);
  s->pattern = pattern;
  s->pattern.keep = keep;
  if (!s->dropped.empty()) s->rank_reference = std::max(rank_ratio(phi_q, ma), pattern.nearby_rank);
  ws.lambda.setZero();
  ws.solver = std::move(s);
}

void FixedPatternLdlt::analyze(const SparseMatrix& upper, const std::vector<bool>& fixed) {
  // Eigen's symbolic analysis: the elimination tree and the column counts of L.
  struct Analysis : Eigen::SimplicialLDLT<SparseMatrix, Eigen::Upper, Eigen::NaturalOrdering<int>> {
    const Eigen::VectorXi& parent() const { return m_parent; }
    const Eigen::VectorXi& counts() const { return m_nonZerosPerCol; }
  } analysis;
  analysis.analyzePattern(upper);
  const int n = static_cast<int>(upper.rows());
  std::vector<int> col_begin(n + 1, 0);  // column j of L: entries [col_begin[j], col_begin[j+1])
  for (int j = 0; j < n; ++j) col_begin[j + 1] = col_begin[j] + analysis.counts()[j];
  const int nnz = col_begin[n];
  col_row_.assign(nnz, 0);
  col_of_.assign(nnz, 0);
  // Row k's pattern: every entry (i, k), i < k, of the upper triangle and its tree path up to
  // k, ascending, with the slot of each L(k, i). Rows are visited in order, so column i's
  // entries are stored in row order.
  std::vector<std::vector<std::pair<int, int>>> row(n);  // (i, slot of L(k, i))
  std::vector<int> mark(n, -1), filled(n, 0), cols;
  for (int k = 0; k < n; ++k) {
    cols.clear();
    mark[k] = k;
    for (SparseMatrix::InnerIterator it(upper, k); it; ++it)
      for (int i = it.index(); i < k && mark[i] != k; i = analysis.parent()[i]) {
        mark[i] = k;
        cols.push_back(i);
      }
    std::sort(cols.begin(), cols.end());
    for (int i : cols) {
      const int slot = col_begin[i] + filled[i]++;
      if (slot >= col_begin[i + 1]) throw std::logic_error("FixedPatternLdlt: column count exceeded");
      col_row_[slot] = k;
      col_of_[slot] = i;
      row[k].emplace_back(i, slot);
    }
  }
  // Where each value of A is: the upper triangle's entry (i, j), i ≤ j, is in column j.
  auto source = [&](int i, int j) {
    for (SparseMatrix::InnerIterator it(upper, j); it; ++it)
      if (it.index() == i) return static_cast<int>(&it.value() - upper.valuePtr());
    return -1;
  };
  // The products of entry (j, i), j ≥ i: the k < i in both rows' patterns (merge, ascending).
  source_.clear();
  target_.clear();
  pair_begin_.assign(1, 0);
  pairs_.clear();
  auto add_entry = [&](int j, int i, int target) {
    source_.push_back(source(i, j));
    target_.push_back(target);
    auto a = row[j].begin(), b = row[i].begin();
    while (a != row[j].end() && b != row[i].end() && a->first < i) {
      if (a->first < b->first) {
        ++a;
      } else if (b->first < a->first) {
        ++b;
      } else {
        pairs_.push_back({a->second, b->second});
        ++a;
        ++b;
      }
    }
    pair_begin_.push_back(static_cast<int>(pairs_.size()));
  };
  for (int i = 0; i < n; ++i) {
    add_entry(i, i, -1 - i);
    for (int t = col_begin[i]; t < col_begin[i + 1]; ++t) add_entry(col_row_[t], i, t);
  }
  // The entries to compute again: those reading a value that is not fixed, directly or through
  // a product or (an entry of L) its pivot. U(j,i) is fixed when its value and products are;
  // L(j,i) when U(j,i) and D_i are.
  std::vector<bool> u_fixed(nnz), l_fixed(nnz), d_fixed(n);
  varying_.clear();
  for (int e = 0; e < static_cast<int>(target_.size()); ++e) {
    bool f = !fixed.empty() && (source_[e] < 0 || fixed[source_[e]]);
    for (int p = pair_begin_[e]; f && p < pair_begin_[e + 1]; ++p)
      f = l_fixed[pairs_[p].l] && u_fixed[pairs_[p].u];
    const int t = target_[e];
    if (t >= 0) {
      u_fixed[t] = f;
      l_fixed[t] = f = f && d_fixed[col_of_[t]];
    } else {
      d_fixed[-1 - t] = f;
    }
    if (!f) varying_.push_back(e);
  }
  factored_ = false;
  l_.assign(nnz, 0.0);
  u_.assign(nnz, 0.0);
  d_.setZero(n);
  d_inverse_.setZero(n);
}

bool FixedPatternLdlt::factorize(const SparseMatrix& upper, const std::vector<signed char>& sign) {
  const double* ax = upper.valuePtr();
  const int* source = source_.data();
  const int* target = target_.data();
  const int* pair_begin = pair_begin_.data();
  const int* col_of = col_of_.data();
  const Pair* pairs = pairs_.data();
  double* l = l_.data();
  double* u = u_.data();
  double* d_inverse = d_inverse_.data();
  weak_pivot_ = false;
  // Entry e of the list; false at a pivot of the wrong sign.
  auto compute = [&](int e) {
    double v = source[e] >= 0 ? ax[source[e]] : 0.0;
    for (int p = pair_begin[e]; p < pair_begin[e + 1]; ++p) v -= l[pairs[p].l] * u[pairs[p].u];
    const int t = target[e];
    if (t >= 0) {
      u[t] = v;
      l[t] = v * d_inverse[col_of[t]];  // the column's pivot came before it in the list
      return true;
    }
    const int i = -1 - t;
    if (sign[i] < 0 && !near_.empty() && v > -near_[i]) {  // NaN passes to the sign test
      near_singular_ = weak_pivot_ = true;
      if (v > -floor_[i]) {
        v = -floor_[i];
        ++clamped_;
      }
    }
    d_[i] = v;
    if (!(sign[i] * v > 0.0)) return false;
    d_inverse[i] = 1.0 / v;
    return true;
  };
  if (!factored_) {
    const int entries = static_cast<int>(source_.size());
    for (int e = 0; e < entries; ++e)
      if (!compute(e)) return false;
    return factored_ = true;
  }
  for (int e : varying_)
    if (!compute(e)) return false;
  return true;
}

void FixedPatternLdlt::solve(Eigen::VectorXd& x) const {
  // L z = x column by column (each x[j] is final when column j's entries come), z ← D⁻¹z, then
  // Lᵀ x = z backwards (each x[r] of column j's entries is final: its column came later).
  const int n = static_cast<int>(d_.size()), nnz = static_cast<int>(l_.size());
  double* v = x.data();
  for (int p = 0; p < nnz; ++p) v[col_row_[p]] -= l_[p] * v[col_of_[p]];
  for (int j = 0; j < n; ++j) v[j] *= d_inverse_[j];
  for (int p = nnz - 1; p >= 0; --p) v[col_of_[p]] -= l_[p] * v[col_row_[p]];
}

void prepare_constraint_solver(const Model& model, Workspace& ws, const Eigen::MatrixXd& phi_q,
                               const JacobianPattern& pattern, bool chosen_again) {
  build_solver(model, ws, phi_q, pattern, false);
  if (!chosen_again && !ws.solver->dropped.empty() &&
      ws.solver->rank_reference < kNearlyRedundant) {
    // Named: the kept row with the largest share of the weakest direction (the last left
    // singular vector of the rows kept), with the others holding at least kDropShare of it.
    const ConstraintSolver& s = *ws.solver;
    Eigen::MatrixXd kept(s.active.size(), ws.nq);
    for (size_t a = 0; a < s.active.size(); ++a) kept.row(a) = phi_q.row(s.active[a]);
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(kept, Eigen::ComputeFullU);
    const Eigen::VectorXd weakest = svd.matrixU().col(kept.rows() - 1).cwiseAbs();
    Eigen::Index top = 0;
    weakest.maxCoeff(&top);
    const std::vector<RowOwner> owner = row_owners(model, ws);
    std::vector<std::string> names;
    for (int r : s.active) names.push_back(owner_name(model, owner[r]));
    const std::string what = names[top];
    char ratio[32];
    std::snprintf(ratio, sizeof ratio, "%.2g", s.rank_reference);
    ws.warnings.push_back(
        what + ": its equations kept are nearly redundant with " +
        other_names(names, weakest, kDropShare * weakest[top], what) +
        " (the smallest singular value of the rows kept is " + ratio +
        " of the largest, at assembly and nearby): the joints nearly repeat one another without "
        "quite agreeing, so they hold the mechanism by a lever of about that size, with "
        "reactions of about 1/" + ratio + " times the loads and very small steps; if they are "
        "meant to repeat one another, make their markers agree to 1e-10 m");
  }
  // Safety net: a row pivot near 0 at assembly means an anchoring to an earlier body left a
  // leading block nearly singular; then every row goes after all of its bodies (safe whenever
  // the rows are independent, at the price of more fill).
  const int nq = ws.nq, ma = static_cast<int>(ws.solver->active.size());
  if (ma == 0) return;
  auto factor_at = [&](const Eigen::MatrixXd& jacobian) {
    ConstraintSolver& s = *ws.solver;
    double* v = s.k.valuePtr();
    for (int a = 0; a < ma; ++a) {
      for (int e = s.phi_begin[a]; e < s.phi_begin[a + 1]; ++e)
        v[s.phi_slot[e]] = jacobian(s.active[a], s.phi_col[e]);
      v[s.slot_reg[a]] = -s.regularisation[a];
    }
    return s.ldlt.factorize(s.k, s.sign);
  };
  auto factor_at_assembly = [&] { return factor_at(phi_q); };
  bool ok = factor_at_assembly();
  for (int a = 0; a < ma && ok; ++a)
    ok = -ws.solver->ldlt.diagonal()[ws.solver->pos[nq + a]] > 1e-10 * ws.solver->w_diag[a];
  if (!ok) {
    const std::vector<std::string> warnings = ws.warnings;
    build_solver(model, ws, phi_q, pattern, true);
    ws.warnings = warnings;
    factor_at_assembly();
  }
  // The floors (kPivotFloor, kNearSingular), once the order is settled, relative to each row's
  // pivot at assembly. Not to W_aa: a pivot is the mass-weighted part of the row outside the
  // span of the rows before it, which bodies of very different mass make a small part of W_aa
  // far from any singular position (3e-8 W_aa for the 4.5 g pivot of
  // erkaya_compliant_beam.yaml; about the mass ratio for 1e-8 kg cranks on a 1 kg coupler, whose
  // rows the floor then softened for good).
  ConstraintSolver& s = *ws.solver;
  s.pivot_reference.clear();
  s.provisional.clear();
  std::vector<double> floor(nq + ma, 0.0), near(nq + ma, 0.0);
  for (int a = 0; a < ma; ++a) s.pivot_reference.push_back(-s.ldlt.diagonal()[s.pos[nq + a]]);
  // Each row's largest pivot at the drawn configurations (Φ_q's values only; M and the pattern
  // are the same there): a row far below it at assembly was assembled near a singular position;
  // rows chosen again during the run take the larger of the two (kReferenceShare).
  if (!pattern.drawn.empty()) {
    std::vector<double> drawn_pivot(ma, 0.0);
    for (const Eigen::MatrixXd& drawn : pattern.drawn)
      if (factor_at(drawn))
        for (int a = 0; a < ma; ++a)
          drawn_pivot[a] = std::max(drawn_pivot[a], -s.ldlt.diagonal()[s.pos[nq + a]]);
    for (int a = 0; a < ma; ++a)
      if (s.pivot_reference[a] < (chosen_again ? 1.0 : kReferenceShare) * drawn_pivot[a]) {
        s.provisional.push_back(a);
        s.pivot_reference[a] = drawn_pivot[a];
      }
    factor_at_assembly();
  }
  for (int a = 0; a < ma; ++a) {
    const int p = s.pos[nq + a];
    floor[p] = kPivotFloor * s.pivot_reference[a];
    near[p] = kNearSingular * s.pivot_reference[a];
  }
  s.ldlt.set_row_floors(std::move(floor), std::move(near));
}

/// The references of the rows assembled near a singular position (kReferenceShare): the
/// largest pivot so far, and the floors with them.
static void update_pivot_references(int nq, ConstraintSolver& s) {
  const Eigen::VectorXd& d = s.ldlt.diagonal();
  for (int a : s.provisional) {
    const int p = s.pos[nq + a];
    if (-d[p] > s.pivot_reference[a]) {
      s.pivot_reference[a] = -d[p];
      s.ldlt.set_row_floor(p, kPivotFloor * -d[p], kNearSingular * -d[p]);
    }
  }
}

bool solve_constraints(Workspace& ws) {
  ConstraintSolver& s = *ws.solver;
  const int nq = ws.nq, ma = static_cast<int>(s.active.size());
  double* v = s.k.valuePtr();
  for (const ConstraintSolver::Entry& e : s.phi_varying) v[e.slot] = ws.phi_q(e.row, e.col);
  for (int a = 0; a < ma; ++a) s.x[s.pos[nq + a]] = ws.rhs_m[s.active[a]];
  for (int k = 0; k < nq; ++k) s.x[s.pos[k]] = ws.g[k];
  // The −ε entries keep the values written at assembly (prepare_constraint_solver).
  const bool ok = s.ldlt.factorize(s.k, s.sign);
  if (!ok) return false;
  if (!s.provisional.empty()) update_pivot_references(nq, s);
  s.ldlt.solve(s.x);
  for (int k = 0; k < nq; ++k) ws.qdd[k] = s.x[s.pos[k]];
  for (int a = 0; a < ma; ++a) ws.lambda[s.active[a]] = -s.x[s.pos[nq + a]];
  for (int r : s.dropped) ws.lambda[r] = 0.0;  // smallest_multipliers may have set them
  return true;
}

void smallest_multipliers(Workspace& ws) {
  ConstraintSolver& s = *ws.solver;
  const int nq = ws.nq, ma = static_cast<int>(s.active.size());
  // Rows near a singular position: a pivot below kNearSingular of its reference.
  const Eigen::VectorXd& d = s.ldlt.diagonal();
  s.weak.clear();
  if (s.dropped.empty() && !s.ldlt.weak_pivot()) return;  // the factorisation found none
  for (int a = 0; a < ma; ++a)
    if (-d[s.pos[nq + a]] < kNearSingular * s.pivot_reference[a]) s.weak.push_back(a);
  if (s.dropped.empty() && s.weak.empty()) return;
  // Redundant rows. The multipliers of a redundant set are not unique: any self-equilibrated
  // set (a vector of Φ_q's left null space) can be added. Those of the kept rows alone (0 on the
  // dropped ones) depend on which rows were dropped, i.e. on the model's order and the world's
  // orientation. Reported instead: the smallest multipliers with the same generalised constraint
  // force Φ_qᵀλ, λ less its projection on the left null space, spanned by N: per dropped row r,
  // e_r − Σ_a c_a e_(kept a), where Φ_rᵀ = Σ_a c_a Φ_aᵀ; c from the factorisation at hand (the
  // augmented system with right-hand side [Φ_rᵀ; 0] has the solution [O(ε); c]).
  // Near a singular position Φ_q has a nearly self-equilibrated set as well, along which the
  // solve amplifies Baumgarte's terms and round-off by 1/pivot (a parallelogram's pivots, about
  // 23.6 N through its in-line position, peaked at 220 N within 1e-3 rad of it): per weak row a,
  // the multipliers of the solution with right-hand side e_a (inverse iteration: 1/d_a times
  // that set, up to O(1)), with the drivers' entries left out and scaled to unit length, are
  // one more column of N.
  const int nd = static_cast<int>(s.dropped.size()), nw = static_cast<int>(s.weak.size());
  if (s.null_basis.cols() != nd + nw) s.null_basis.resize(ws.m, nd + nw);  // near singular only
  for (int j = 0; j < nd; ++j) {
    const int r = s.dropped[j];
    s.null_work.setZero();
    for (int k = 0; k < nq; ++k) s.null_work[s.pos[k]] = ws.phi_q(r, k);
    s.ldlt.solve(s.null_work);
    s.null_basis.col(j).setZero();
    s.null_basis(r, j) = 1.0;
    for (int a = 0; a < ma; ++a) s.null_basis(s.active[a], j) = -s.null_work[s.pos[nq + a]];
  }
  for (int j = 0; j < nw; ++j) {
    s.null_work.setZero();
    s.null_work[s.pos[nq + s.weak[j]]] = 1.0;
    s.ldlt.solve(s.null_work);
    auto col = s.null_basis.col(nd + j);
    col.setZero();
    for (int a = 0; a < ma; ++a) col[s.active[a]] = s.null_work[s.pos[nq + a]];
    // Without the drivers' entries: the driver's multiplier is the power the motion needs
    // (τω), which the self-stress carries none of in the limit; the estimate's share of it
    // took half a driven parallelogram's torque at its in-line position (14.7 of 29.43 N·m).
    for (const int r : ws.row_of_driver) col[r] = 0.0;
    const double norm = col.norm();
    if (!(norm > 0.0) || !std::isfinite(norm)) return;  // λ as solved
    col /= norm;
  }
  // λ less its projection on the span of N. With redundant rows only, N = [e_r − Σ c_a e_a] has
  // an identity block (each column's own dropped row), so NᵀN = I + CCᵀ has no eigenvalue below
  // 1: the normal equations NᵀN z = Nᵀλ are well conditioned and solved by Cholesky (NᵀN formed
  // as one rank update: a linkage with 100 parallel cranks spent 64 % of its run in the
  // orthogonalisation below, O(m·nd²) column by column).
  if (nw == 0) {
    s.null_gram.setZero(nd, nd);
    s.null_gram.selfadjointView<Eigen::Lower>().rankUpdate(s.null_basis.transpose());
    const Eigen::LLT<Eigen::MatrixXd> llt(s.null_gram);
    if (llt.info() == Eigen::Success) {
      const Eigen::VectorXd z = llt.solve(s.null_basis.transpose() * ws.lambda);
      ws.lambda.noalias() -= s.null_basis * z;
      return;
    }
  }
  // Near a singular position, through an orthonormal basis (modified Gram–Schmidt, twice): the
  // two kinds of columns can be nearly parallel there, and (NᵀN)⁻¹ then amplifies round-off
  // (a double parallelogram in line reported 3.3e4 N). A column within 1e-8 of the span of
  // those before it adds nothing.
  int kept = 0;
  for (int j = 0; j < nd + nw; ++j) {
    auto col = s.null_basis.col(j);
    const double before = col.norm();
    for (int pass = 0; pass < 2; ++pass)
      for (int i = 0; i < kept; ++i) col -= s.null_basis.col(i).dot(col) * s.null_basis.col(i);
    const double after = col.norm();
    if (!(after > 1e-8 * before)) continue;
    s.null_basis.col(kept++) = col / after;
  }
  for (int i = 0; i < kept; ++i) ws.lambda -= s.null_basis.col(i).dot(ws.lambda) * s.null_basis.col(i);
}

bool kept_rows_weak(Workspace& ws) {
  ConstraintSolver& s = *ws.solver;
  if (s.dropped.empty()) return false;
  if (s.reselect_wait > 0) {
    --s.reselect_wait;
    return false;
  }
  const int nq = ws.nq, ma = static_cast<int>(s.active.size());
  const Eigen::VectorXd& d = s.ldlt.diagonal();
  for (int a = 0; a < ma; ++a)
    if (-d[s.pos[nq + a]] < kReselectPivot * s.pivot_reference[a]) return true;
  return false;
}

bool reselect_redundant_rows(const Model& model, Workspace& ws) {
  const ConstraintSolver& s = *ws.solver;
  const int m = ws.m, nd = static_cast<int>(s.dropped.size());
  ++ws.row_choices;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(ws.phi_q, Eigen::ComputeFullU);
  // Near a singular position of the mechanism itself (Φ_q losing rank beyond its redundancy)
  // every choice is weak, and pivots taken there as references would make the floor useless:
  // the choice stays, and the floor carries the instant (kPivotFloor).
  const Eigen::VectorXd& sv = svd.singularValues();
  const double rank_ratio = m - nd > 0 ? sv[m - nd - 1] / sv[0] : 0.0;
  if (!(rank_ratio > kReselectRank * s.rank_reference)) {
    ws.solver->reselect_wait = kReselectWait;
    return false;
  }
  // The rows dropped: those of the largest shares in the redundancies (column pivoting).
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(left_null_basis(svd, nd, ws.row_of_driver));
  std::vector<bool> keep(m, true);
  for (int j = 0; j < nd; ++j) keep[qr.colsPermutation().indices()[j]] = false;
  if (keep == s.pattern.keep) {  // already the best: weak by the mechanism's own position
    ws.solver->reselect_wait = kReselectWait;
    return false;
  }
  JacobianPattern pattern = s.pattern;
  pattern.keep = std::move(keep);
  pattern.counted.resize(0, 0);  // the warning is the assembly's (kept below)
  const std::vector<std::string> warnings = ws.warnings;
  const double rank_reference = s.rank_reference;
  prepare_constraint_solver(model, ws, ws.phi_q, pattern, true);
  ws.solver->rank_reference = rank_reference;  // the assembly's, not this instant's
  ws.solver->reselect_wait = kReselectWait;
  ws.warnings = warnings;
  return true;
}

std::string other_names(const std::vector<std::string>& names, const Eigen::VectorXd& share,
                        double least, const std::string& except) {
  std::vector<std::string> seen;
  std::string list;
  for (size_t r = 0; r < names.size(); ++r) {
    if (!(share[static_cast<Eigen::Index>(r)] >= least) || names[r] == except ||
        std::find(seen.begin(), seen.end(), names[r]) != seen.end())
      continue;
    list += (seen.empty() ? "" : ", ") + names[r];
    seen.push_back(names[r]);
  }
  return seen.empty() ? "the others" : list;
}

RowElement constraint_row_element(const Model& model, const Workspace& ws, int row) {
  const RowOwner o = row_owners(model, ws).at(static_cast<size_t>(row));
  return {o.driver ? model.drivers[o.index].name : model.joints[o.index].name,
          owner_name(model, o)};
}

}  // namespace lash
