#include "core/dynamics.hpp"

#include <Eigen/LU>
#include <Eigen/QR>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/elements/clearance_revolute.hpp"
#include "core/elements/constraint_rows.hpp"
#include "core/elements/registry.hpp"

namespace lash {

namespace {

/// Constraint rows for `model` at (t, y); ws.kin must hold y's kinematics. Rows follow
/// ws.row_of_joint / ws.row_of_driver; with close_clearance the clearance joints' revolute rows
/// follow after them (initial assembly). phi_dot and gamma may be null.
void build_constraints(const Model& model, Workspace& ws, double t, const double* y,
                       bool close_clearance, Eigen::VectorXd& phi, Eigen::MatrixXd& phi_q,
                       Eigen::VectorXd* phi_dot, Eigen::VectorXd* gamma) {
  if (&phi_q == &ws.phi_q) {
    // The workspace's Φ_q: only the blocks of the bodies each row touches were ever written.
    for (int i = 0; i < ws.m; ++i)
      for (int b : ws.row_bodies[i])
        if (b >= 0) for_block(ws.blocks[b], [&](int k) { phi_q(i, k) = 0.0; });
  } else {
    phi_q.setZero();
  }
  ConstraintOut out{phi, phi_q, phi_dot, gamma};
  int extra_row = ws.m;
  for (size_t ji = 0; ji < model.joints.size(); ++ji) {
    const Joint& j = model.joints[ji];
    if (!j.is_constraint()) {
      if (close_clearance) {
        revolute_rows(ws, j.a, j.b, extra_row, out);
        extra_row += 2;
      }
      continue;
    }
    kind_of(j).constrain(model, ws, j, ws.row_of_joint[ji], out);
  }
  for (size_t di = 0; di < model.drivers.size(); ++di)
    driver_constrain(model, ws, static_cast<int>(di), t, y, ws.row_of_driver[di], out);
}

/// Solves W x = b for symmetric positive definite W given by its lower triangle within the
/// envelope `first` (W(i, j) = 0 for j < first[i]), factoring W in place (W = L Lᵀ, same
/// envelope). Returns false if W is not positive definite (redundant constraints).
bool cholesky_solve(Eigen::MatrixXd& w, const std::vector<int>& first, const Eigen::VectorXd& b,
                    Eigen::VectorXd& x) {
  const int n = static_cast<int>(w.rows());
  for (int i = 0; i < n; ++i) {
    for (int j = first[i]; j <= i; ++j) {
      double v = w(i, j);
      for (int k = std::max(first[i], first[j]); k < j; ++k) v -= w(i, k) * w(j, k);
      if (j < i) {
        w(i, j) = v / w(j, j);
      } else {
        if (!(v > 0.0)) return false;
        w(i, i) = std::sqrt(v);
      }
    }
  }
  for (int i = 0; i < n; ++i) {  // L z = b
    double v = b[i];
    for (int k = first[i]; k < i; ++k) v -= w(i, k) * x[k];
    x[i] = v / w(i, i);
  }
  for (int i = n - 1; i >= 0; --i) {  // Lᵀ x = z: column i of L, rows k > i within their envelopes
    x[i] /= w(i, i);
    for (int k = first[i]; k < i; ++k) x[k] -= w(i, k) * x[i];
  }
  return true;
}

/// The bodies' state as load expressions read it (`<body>.x` …), from ws.kin.
void load_body_state(Workspace& ws) {
  for (int b = 0; b < ws.nb; ++b) {
    const BodyKin& k = ws.kin[b];
    double* s = &ws.vars.body_state[6 * b];
    s[0] = k.r.x(), s[1] = k.r.y(), s[2] = k.phi;
    s[3] = k.v.x(), s[4] = k.v.y(), s[5] = k.omega;
  }
}

}  // namespace

int Model::clearance_joint_count() const {
  int n = 0;
  for (const auto& j : joints) n += j.clearance.has_value();
  return n;
}

/// Pose and velocity of a body from y into k (whose block is set).
inline void read_kin(BodyKin& k, int nq, const double* y) {
  const BodyBlock& bl = k.block;
  k.r = Vec2(y[bl.offset], y[bl.offset + 1]);
  k.v = Vec2(y[nq + bl.offset], y[nq + bl.offset + 1]);
  if (bl.rot >= 0) {
    k.phi = y[bl.rot];
    k.omega = y[nq + bl.rot];
    k.A = rotation(k.phi);
  }
}

BodyKin body_kin(const Workspace& ws, int b, const double* y) {
  BodyKin k;
  if (b == kGround) return k;
  k.block = ws.blocks[b];
  read_kin(k, ws.nq, y);
  return k;
}

std::vector<std::string> state_names(const Model& model, const Workspace& ws) {
  std::vector<std::string> n(ws.ny);
  for (int b = 0; b < ws.nb; ++b) {
    const BodyBlock& bl = ws.blocks[b];
    const std::string& name = model.bodies[b].name;
    const char* q[3] = {".x", ".y", ".phi"};
    const char* v[3] = {".vx", ".vy", ".omega"};
    for (int i = 0; i < bl.size; ++i) {
      n[bl.offset + i] = name + q[i];
      n[ws.nq + bl.offset + i] = name + v[i];
    }
  }
  for (int a = 0; a < ws.na; ++a) n[2 * ws.nq + a] = ws.aux_names[a];
  n[ws.i_dissipated] = "energy.dissipated";
  n[ws.i_input] = "energy.input";
  return n;
}

void update_kin(Workspace& ws, const double* y) {
  // In place: the blocks were set once by the Workspace; only pose and velocity change.
  for (BodyKin& k : ws.kin) read_kin(k, ws.nq, y);
}

Workspace::Workspace(const Model& model) {
  if (!model.finalized)
    throw std::invalid_argument("Workspace: the model has not been finalized (lash::finalize)");
  nb = static_cast<int>(model.bodies.size());
  // Coordinate blocks: one per body, sized by its kind.
  for (const Body& b : model.bodies) {
    BodyBlock bl;
    bl.offset = nq;
    bl.size = kind_of(b).coordinates;
    bl.rot = b.rotates() ? nq + 2 : -1;
    nq += bl.size;
    blocks.push_back(bl);
  }
  // Constraint rows: ideal joints, then drivers.
  for (size_t ji = 0; ji < model.joints.size(); ++ji) {
    const Joint& j = model.joints[ji];
    if (!j.is_constraint()) {
      row_of_joint.push_back(-1);
      clearance_joints.push_back(static_cast<int>(ji));
      continue;
    }
    row_of_joint.push_back(m);
    const int rows = kind_of(j).rows(model, j);
    for (int r = 0; r < rows; ++r) row_bodies.push_back({j.a.body, j.b.body});
    m += rows;
  }
  for (const Driver& d : model.drivers) {
    row_of_driver.push_back(m++);
    if (d.target == DriverTarget::body)
      row_bodies.push_back({d.body, -1});
    else
      row_bodies.push_back({model.joints[d.joint].a.body, model.joints[d.joint].b.body});
  }
  auto shares_body = [](const std::array<int, 2>& a, const std::array<int, 2>& b) {
    for (int x : a)
      if (x >= 0 && (x == b[0] || x == b[1])) return true;
    return false;
  };
  row_first.assign(m, 0);
  for (int i = 0; i < m; ++i) {
    int j = 0;
    while (j < i && !shares_body(row_bodies[i], row_bodies[j])) ++j;
    row_first[i] = j;
  }
  kin.assign(nb, BodyKin{});
  for (int b = 0; b < nb; ++b) kin[b].block = blocks[b];
  // Auxiliary states: the clearance joints', then the speed-profile drivers' positions.
  nc = static_cast<int>(clearance_joints.size());
  contact.assign(nc, ContactState{});
  clearance_out.assign(nc, ClearanceOutput{});
  aux_impact.assign(nc, -1);
  aux_bristle.assign(nc, -1);
  for (int k = 0; k < nc; ++k) clearance_layout(model, *this, k);
  for (const Driver& d : model.drivers) {
    aux_driver.push_back(d.profile == DriverProfile::speed ? na++ : -1);
    if (d.profile == DriverProfile::speed) aux_names.push_back(d.name + ".position");
  }
  // Absolute indices: y = [q, q̇, aux, E_dissipated, W_input].
  for (int& i : aux_impact) i += 2 * nq;
  for (int& i : aux_bristle)
    if (i >= 0) i += 2 * nq;
  for (int& i : aux_driver)
    if (i >= 0) i += 2 * nq;
  i_dissipated = 2 * nq + na;
  i_input = i_dissipated + 1;
  ny = i_input + 1;

  for (const auto& b : model.bodies) vars.body_names.push_back(b.name);
  vars.body_state.assign(6 * nb, 0.0);
  // Drivers need ḟ, f̈ of a position profile and f̈ of a speed profile (exact: expression.hpp).
  for (const auto& d : model.drivers) {
    if (d.profile == DriverProfile::constant_speed)
      driver_expr.emplace_back("0", vars);
    else
      driver_expr.emplace_back(d.expression, vars, d.profile == DriverProfile::position ? 2 : 1);
  }
  for (const auto& l : model.loads) {
    std::vector<Expression> ex;
    if (l.type == LoadType::force) {
      ex.emplace_back(l.fx, vars);
      ex.emplace_back(l.fy, vars);
    } else if (l.type == LoadType::torque) {
      ex.emplace_back(l.torque, vars);
    }
    for (const auto& e : ex) loads_use_state |= e.depends_on_state();
    load_expr.push_back(std::move(ex));
  }
  load_out.assign(model.loads.size(), LoadOutput{});

  minv.resize(nq);
  for (int b = 0; b < nb; ++b)
    kind_of(model.bodies[b]).mass_inverse(model.bodies[b], minv.data() + blocks[b].offset);
  g.resize(nq);
  qdd = Eigen::VectorXd::Zero(nq);
  phi.resize(m);
  phi_dot.resize(m);
  gamma.resize(m);
  rhs_m.resize(m);
  lambda = Eigen::VectorXd::Zero(m);
  rate_m.resize(m);
  phi_q = Eigen::MatrixXd::Zero(m, nq);
  w.resize(m, m);
}

void event_functions(const Model& model, const Workspace& ws, const double* y, double* g) {
  for (int k = 0; k < ws.nc; ++k) {
    double delta, delta_dot;
    clearance_gap(model, ws, k, y, delta, delta_dot);
    g[k] = ws.contact[k].in_contact ? -delta : delta;
  }
}

bool evaluate(const Model& model, Workspace& ws, double t, const double* y, double* ydot) {
  ++ws.rhs_evaluations;
  const int nq = ws.nq;
  update_kin(ws, y);
  ws.vars.time = t;
  if (ws.loads_use_state) load_body_state(ws);

  // Applied forces: gravity, then loads, then clearance contacts.
  ws.g.setZero();
  ws.kinetic = ws.potential = ws.dissipated_power = ws.input_power = 0.0;
  for (int b = 0; b < ws.nb; ++b) {
    const Body& body = model.bodies[b];
    const BodyKin& k = ws.kin[b];
    ws.g.segment<2>(k.block.offset) += body.mass * model.gravity;
    ws.potential -= body.mass * model.gravity.dot(k.r);
    ws.kinetic += kind_of(body).kinetic_energy(body, k);
  }
  for (size_t li = 0; li < model.loads.size(); ++li) {
    const Load& l = model.loads[li];
    kind_of(l).apply(model, ws, l, static_cast<int>(li));
  }
  for (int k = 0; k < ws.nc; ++k) clearance_forces(model, ws, k, y, ydot);
  for (size_t d = 0; d < model.drivers.size(); ++d)
    if (ws.aux_driver[d] >= 0) {
      double f, fd, fdd;
      driver_motion(model, ws, static_cast<int>(d), t, y, f, fd, fdd);
      ydot[ws.aux_driver[d]] = fd;
    }

  // Constraint forces from the Schur complement.
  ws.qdd = ws.minv.cwiseProduct(ws.g);
  if (ws.m > 0) {
    build_constraints(model, ws, t, y, false, ws.phi, ws.phi_q, &ws.phi_dot, &ws.gamma);
    const double a = model.solver.baumgarte_alpha, b = model.solver.baumgarte_beta;
    // rhs = γ − 2αΦ̇ − β²Φ − Φ_q M⁻¹ g, and W = Φ_q M⁻¹ Φ_qᵀ, from the row structure (each row
    // touches at most two coordinate blocks), then W λ = rhs by an in-place Cholesky
    // factorisation.
    const int m = ws.m;
    const Eigen::Map<const Eigen::VectorXd> qd(y + nq, nq);
    for (int i = 0; i < m; ++i) {
      double pq = 0.0, rate = 0.0;
      for (int bi : ws.row_bodies[i]) {
        if (bi < 0) continue;
        for_block(ws.blocks[bi], [&](int k) {
          pq += ws.phi_q(i, k) * ws.qdd[k];
          rate += ws.phi_q(i, k) * qd[k];
        });
      }
      ws.rhs_m[i] = ws.gamma[i] - 2.0 * a * ws.phi_dot[i] - b * b * ws.phi[i] - pq;
      ws.rate_m[i] = rate;
      for (int j = ws.row_first[i]; j <= i; ++j) {
        double sum = 0.0;
        for (int bi : ws.row_bodies[i]) {
          if (bi < 0 || (bi != ws.row_bodies[j][0] && bi != ws.row_bodies[j][1])) continue;
          for_block(ws.blocks[bi],
                    [&](int k) { sum += ws.phi_q(i, k) * ws.minv[k] * ws.phi_q(j, k); });
        }
        ws.w(i, j) = sum;
      }
    }
    if (!cholesky_solve(ws.w, ws.row_first, ws.rhs_m, ws.lambda)) return false;
    for (int i = 0; i < m; ++i)
      for (int bi : ws.row_bodies[i]) {
        if (bi < 0) continue;
        for_block(ws.blocks[bi], [&](int k) { ws.g[k] += ws.phi_q(i, k) * ws.lambda[i]; });
      }
    ws.qdd = ws.minv.cwiseProduct(ws.g);
    // Power of all constraint forces: the drivers' work (and Baumgarte's, ≈ 0).
    ws.input_power += ws.lambda.dot(ws.rate_m);
    ws.constraint_violation = ws.phi.cwiseAbs().maxCoeff();
  } else {
    ws.constraint_violation = 0.0;
  }

  for (int i = 0; i < nq; ++i) {
    ydot[i] = y[nq + i];
    ydot[nq + i] = ws.qdd[i];
  }
  ydot[ws.i_dissipated] = ws.dissipated_power;
  ydot[ws.i_input] = ws.input_power;
  return std::isfinite(ws.qdd.sum()) && std::isfinite(ws.dissipated_power);
}

double constraint_residual(const Model& model, Workspace& ws, double t, const double* y) {
  if (ws.m == 0) return 0.0;
  update_kin(ws, y);
  build_constraints(model, ws, t, y, false, ws.phi, ws.phi_q, nullptr, nullptr);
  return ws.phi.cwiseAbs().maxCoeff();
}

void project_state(const Model& model, Workspace& ws, double t, Eigen::VectorXd& y) {
  if (ws.m == 0) return;
  const int nq = ws.nq;
  Eigen::VectorXd phi(ws.m), phi_dot(ws.m);
  Eigen::MatrixXd phi_q(ws.m, nq);
  double residual = 0.0;
  for (int it = 0; it < 50; ++it) {
    update_kin(ws, y.data());
    build_constraints(model, ws, t, y.data(), false, phi, phi_q, nullptr, nullptr);
    residual = phi.cwiseAbs().maxCoeff();
    if (residual < 1e-13) break;
    Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(phi_q);
    y.head(nq) -= cod.solve(phi);
  }
  if (!(residual < 1e-10))
    throw std::runtime_error("state projection onto the constraints did not converge (residual " +
                             std::to_string(residual) + ")");
  update_kin(ws, y.data());
  build_constraints(model, ws, t, y.data(), false, phi, phi_q, &phi_dot, nullptr);
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(phi_q);
  y.segment(nq, nq) -= cod.solve(phi_dot);
}

std::string constraint_problem(const Model& model, Workspace& ws, double t,
                               const Eigen::VectorXd& y, bool check_residual) {
  if (ws.m == 0) return "";
  const int nq = ws.nq;
  Eigen::VectorXd p(ws.m), pd(ws.m);
  Eigen::MatrixXd pq(ws.m, nq);
  update_kin(ws, y.data());
  build_constraints(model, ws, t, y.data(), false, p, pq, &pd, nullptr);
  // The actual constraint set must be independent for the Schur complement to be SPD.
  Eigen::FullPivLU<Eigen::MatrixXd> lu(pq);
  if (lu.rank() < ws.m)
    return "the joints and drivers are redundant: " + std::to_string(ws.m) +
           " constraint equations but only " + std::to_string(lu.rank()) +
           " independent ones; remove a joint or a driver, or turn a revolute joint into a "
           "clearance joint";
  if (check_residual) {
    const double pos = p.cwiseAbs().maxCoeff(), vel = pd.cwiseAbs().maxCoeff();
    if (!(pos <= kStateTolerancePosition) || !(vel <= kStateToleranceVelocity)) {
      std::ostringstream s;
      s << "the state does not satisfy this model's joints and drivers at t = " << t
        << " s (largest residual " << pos << " in position, " << vel
        << " in velocity; at most " << kStateTolerancePosition << " and "
        << kStateToleranceVelocity
        << " are accepted): it was written by a model with other joints, markers or driver "
           "motion";
      return s.str();
    }
  }
  return "";
}

Eigen::VectorXd initial_state(const Model& model, Workspace& ws) {
  const int nq = ws.nq;
  const bool ideal = model.solver.initial_state == InitialStateRule::ideal;
  const int rows = ws.m + (ideal ? 2 * ws.nc : 0);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(ws.ny);
  for (int b = 0; b < ws.nb; ++b) {
    const Body& body = model.bodies[b];
    const BodyBlock& bl = ws.blocks[b];
    y.segment<2>(bl.offset) = body.r0;
    if (bl.rot >= 0) y[bl.rot] = body.phi0;
    if (!ideal) {
      y.segment<2>(nq + bl.offset) = body.v0;
      if (bl.rot >= 0) y[nq + bl.rot] = body.omega0;
    }
  }
  if (rows == 0) return y;
  Eigen::VectorXd phi(rows), phi_dot(rows);
  Eigen::MatrixXd phi_q(rows, nq);

  // Positions: Gauss–Newton with minimum-norm corrections.
  double residual = 0.0;
  for (int it = 0; it < 100; ++it) {
    update_kin(ws, y.data());
    build_constraints(model, ws, 0.0, y.data(), ideal, phi, phi_q, nullptr, nullptr);
    residual = phi.cwiseAbs().maxCoeff();
    if (residual < 1e-13) break;
    Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(phi_q);
    y.head(nq) -= cod.solve(phi);
  }
  if (!(residual < 1e-10))
    throw std::runtime_error("initial assembly failed: the joints and drivers cannot all be "
                             "satisfied from the given poses (largest residual " +
                             std::to_string(residual) +
                             "); check the markers and initial positions");

  // Velocities: Φ_q q̇ = −Φ_t, least-squares correction of the initial guess.
  update_kin(ws, y.data());
  build_constraints(model, ws, 0.0, y.data(), ideal, phi, phi_q, &phi_dot, nullptr);
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(phi_q);
  y.segment(nq, nq) -= cod.solve(phi_dot);

  if (const std::string why = constraint_problem(model, ws, 0.0, y, false); !why.empty())
    throw std::runtime_error(why);
  return y;
}

}  // namespace lash
