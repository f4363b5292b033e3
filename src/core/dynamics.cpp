#include "core/dynamics.hpp"

#include <Eigen/LU>
#include <Eigen/QR>
#include <cmath>
#include <stdexcept>

namespace lash {

namespace {

using Kin = BodyKin;

Kin body_kin(int b, int nq, const double* y) {
  Kin k;
  if (b == kGround) return k;
  k.r = Vec2(y[3 * b], y[3 * b + 1]);
  k.phi = y[3 * b + 2];
  k.v = Vec2(y[nq + 3 * b], y[nq + 3 * b + 1]);
  k.omega = y[nq + 3 * b + 2];
  k.A = rotation(k.phi);
  return k;
}

/// Fills ws.kin from y (one sine and cosine per body per evaluation).
void update_kin(Workspace& ws, const double* y) {
  for (int b = 0; b < ws.nb; ++b) ws.kin[b] = body_kin(b, ws.nq, y);
}

/// The cached kinematics of body b (the ground for kGround).
inline const Kin& kin_of(const Workspace& ws, int b) {
  static const Kin ground;
  return b == kGround ? ground : ws.kin[b];
}

/// A point of a body: world offset from the centre of mass, position and velocity.
struct PointKin {
  Vec2 s, r, v;
};
PointKin point_kin(const Kin& k, const Vec2& s_body) {
  PointKin p;
  p.s = k.A * s_body;
  p.r = k.r + p.s;
  p.v = k.v + k.omega * perp(p.s);
  return p;
}

/// Writes Φ_q entries of a body (skipped for the ground).
inline void put(Eigen::MatrixXd& phi_q, int row, int body, double dx, double dy, double dphi) {
  if (body == kGround) return;
  phi_q(row, 3 * body) += dx;
  phi_q(row, 3 * body + 1) += dy;
  phi_q(row, 3 * body + 2) += dphi;
}

/// Generalized force of a world force F applied at world offset s from body's centre of mass.
inline void apply(Eigen::VectorXd& g, int body, const Vec2& s, const Vec2& f) {
  if (body == kGround) return;
  g[3 * body] += f.x();
  g[3 * body + 1] += f.y();
  g[3 * body + 2] += cross(s, f);
}

/// Constraint rows for `model` at (t, y); ws.kin must hold y's kinematics. Rows follow ws.row_of_joint / ws.row_of_driver; with
/// close_clearance the clearance joints' revolute rows follow after them (initial assembly).
/// phi_dot and gamma may be null.
void build_constraints(const Model& model, Workspace& ws, double t, const double* y,
                       bool close_clearance, Eigen::VectorXd& phi, Eigen::MatrixXd& phi_q,
                       Eigen::VectorXd* phi_dot, Eigen::VectorXd* gamma) {
  if (&phi_q == &ws.phi_q) {
    // The workspace's Φ_q: only the blocks of the bodies each row touches were ever written.
    for (int i = 0; i < ws.m; ++i)
      for (int b : ws.row_bodies[i])
        if (b >= 0) phi_q.block<1, 3>(i, 3 * b).setZero();
  } else {
    phi_q.setZero();
  }
  int extra_row = ws.m;

  // Revolute rows: Φ = r_a − r_b (journal point minus bearing point).
  auto revolute = [&](const Joint& j, int row) {
    const Kin &ka = kin_of(ws, j.a.body), &kb = kin_of(ws, j.b.body);
    const PointKin pa = point_kin(ka, j.a.s), pb = point_kin(kb, j.b.s);
    phi.segment<2>(row) = pa.r - pb.r;
    const Vec2 ps_a = perp(pa.s), ps_b = perp(pb.s);
    put(phi_q, row, j.a.body, 1, 0, ps_a.x());
    put(phi_q, row + 1, j.a.body, 0, 1, ps_a.y());
    put(phi_q, row, j.b.body, -1, 0, -ps_b.x());
    put(phi_q, row + 1, j.b.body, 0, -1, -ps_b.y());
    if (phi_dot) phi_dot->segment<2>(row) = pa.v - pb.v;
    if (gamma)
      gamma->segment<2>(row) = pa.s * ka.omega * ka.omega - pb.s * kb.omega * kb.omega;
  };
  // Relative-angle row: Φ = φ_b − φ_a − angle0 − f.
  auto angle = [&](int body_a, int body_b, double angle0, double f, double fd, double fdd,
                   int row) {
    const Kin &ka = kin_of(ws, body_a), &kb = kin_of(ws, body_b);
    phi[row] = kb.phi - ka.phi - angle0 - f;
    put(phi_q, row, body_a, 0, 0, -1);
    put(phi_q, row, body_b, 0, 0, 1);
    if (phi_dot) (*phi_dot)[row] = kb.omega - ka.omega - fd;
    if (gamma) (*gamma)[row] = fdd;
  };
  // Dot row: Φ = (A_a v')·(r_Pb − r_Pa) − f, v' fixed in body a.
  auto dot_row = [&](const Joint& j, const Vec2& v_body, double f, double fd, double fdd,
                     int row) {
    const Kin &ka = kin_of(ws, j.a.body), &kb = kin_of(ws, j.b.body);
    const PointKin pa = point_kin(ka, j.a.s), pb = point_kin(kb, j.b.s);
    const Vec2 v = ka.A * v_body, pv = perp(v);
    const Vec2 d = pb.r - pa.r, dd = pb.v - pa.v;
    phi[row] = v.dot(d) - f;
    put(phi_q, row, j.a.body, -v.x(), -v.y(), pv.dot(pb.r - ka.r));
    put(phi_q, row, j.b.body, v.x(), v.y(), v.dot(perp(pb.s)));
    if (phi_dot) (*phi_dot)[row] = ka.omega * pv.dot(d) + v.dot(dd) - fd;
    if (gamma) {
      const double quad = -v.dot(d) * ka.omega * ka.omega + 2.0 * ka.omega * pv.dot(dd) +
                          v.dot(pa.s * ka.omega * ka.omega - pb.s * kb.omega * kb.omega);
      (*gamma)[row] = fdd - quad;
    }
  };

  for (size_t ji = 0; ji < model.joints.size(); ++ji) {
    const Joint& j = model.joints[ji];
    if (!j.is_constraint()) {
      if (close_clearance) {
        revolute(j, extra_row);
        extra_row += 2;
      }
      continue;
    }
    const int row = ws.row_of_joint[ji];
    switch (j.type) {
      case JointType::revolute: revolute(j, row); break;
      case JointType::fixed:
        revolute(j, row);
        angle(j.a.body, j.b.body, j.angle0, 0, 0, 0, row + 2);
        break;
      case JointType::translational:
        angle(j.a.body, j.b.body, j.angle0, 0, 0, 0, row);
        dot_row(j, perp(j.axis), 0, 0, 0, row + 1);
        break;
    }
  }
  for (size_t di = 0; di < model.drivers.size(); ++di) {
    const Driver& d = model.drivers[di];
    const Joint& j = model.joints[d.joint];
    double f, fd, fdd;
    driver_motion(model, ws, static_cast<int>(di), t, f, fd, fdd);
    const int row = ws.row_of_driver[di];
    if (j.type == JointType::revolute)  // θ = φ_a − φ_b: the angle row with a and b swapped
      angle(j.b.body, j.a.body, 0.0, f, fd, fdd, row);
    else
      dot_row(j, j.axis, f, fd, fdd, row);
  }
}

bool shares_body(const std::array<int, 2>& a, const std::array<int, 2>& b) {
  for (int x : a)
    if (x >= 0 && (x == b[0] || x == b[1])) return true;
  return false;
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

void load_body_state(Workspace& ws, const double* y) {
  for (int b = 0; b < ws.nb; ++b)
    for (int f = 0; f < 3; ++f) {
      ws.vars.body_state[6 * b + f] = y[3 * b + f];
      ws.vars.body_state[6 * b + 3 + f] = y[ws.nq + 3 * b + f];
    }
}

}  // namespace

int Model::clearance_joint_count() const {
  int n = 0;
  for (const auto& j : joints) n += j.clearance.has_value();
  return n;
}

Workspace::Workspace(const Model& model) {
  nb = static_cast<int>(model.bodies.size());
  nq = 3 * nb;
  ny = 2 * nq + 2;
  for (size_t ji = 0; ji < model.joints.size(); ++ji) {
    const Joint& j = model.joints[ji];
    if (!j.is_constraint()) {
      row_of_joint.push_back(-1);
      clearance_joints.push_back(static_cast<int>(ji));
      continue;
    }
    row_of_joint.push_back(m);
    m += j.type == JointType::fixed ? 3 : 2;
  }
  for (size_t di = 0; di < model.drivers.size(); ++di) row_of_driver.push_back(m++);
  row_bodies.assign(m, {-1, -1});
  for (size_t ji = 0; ji < model.joints.size(); ++ji) {
    const Joint& j = model.joints[ji];
    if (row_of_joint[ji] < 0) continue;
    const int rows = j.type == JointType::fixed ? 3 : 2;
    for (int r = 0; r < rows; ++r) row_bodies[row_of_joint[ji] + r] = {j.a.body, j.b.body};
  }
  for (size_t di = 0; di < model.drivers.size(); ++di) {
    const Joint& j = model.joints[model.drivers[di].joint];
    row_bodies[row_of_driver[di]] = {j.a.body, j.b.body};
  }
  row_first.assign(m, 0);
  for (int i = 0; i < m; ++i) {
    int j = 0;
    while (j < i && !shares_body(row_bodies[i], row_bodies[j])) ++j;
    row_first[i] = j;
  }
  kin.assign(nb, BodyKin{});
  nc = static_cast<int>(clearance_joints.size());
  contact.assign(nc, ContactState{});
  clearance_out.assign(nc, ClearanceOutput{});

  for (const auto& b : model.bodies) vars.body_names.push_back(b.name);
  vars.body_state.assign(6 * nb, 0.0);
  for (const auto& d : model.drivers) {
    if (d.profile == DriverProfile::expression)
      driver_expr.emplace_back(d.expression, vars);
    else
      driver_expr.emplace_back("0", vars);
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

  minv.resize(nq);
  for (int b = 0; b < nb; ++b) {
    minv[3 * b] = minv[3 * b + 1] = 1.0 / model.bodies[b].mass;
    minv[3 * b + 2] = 1.0 / model.bodies[b].inertia;
  }
  g.resize(nq);
  qdd.resize(nq);
  phi.resize(m);
  phi_dot.resize(m);
  gamma.resize(m);
  rhs_m.resize(m);
  lambda.resize(m);
  rate_m.resize(m);
  phi_q = Eigen::MatrixXd::Zero(m, nq);
  w.resize(m, m);
}

void driver_motion(const Model& model, Workspace& ws, int d, double t, double& f, double& fd,
                   double& fdd) {
  const Driver& drv = model.drivers[d];
  if (drv.profile == DriverProfile::constant_speed) {
    f = drv.initial + drv.speed * t;
    fd = drv.speed;
    fdd = 0.0;
    return;
  }
  ws.driver_expr[d].eval_derivatives(t, f, fd, fdd);
  f += drv.initial;
}

void clearance_gap(const Model& model, const Workspace& ws, int k, const double* y, double& delta,
                   double& delta_dot) {
  const Joint& j = model.joints[ws.clearance_joints[k]];
  const PointKin pj = point_kin(body_kin(j.a.body, ws.nq, y), j.a.s);
  const PointKin pb = point_kin(body_kin(j.b.body, ws.nq, y), j.b.s);
  const Vec2 e = pj.r - pb.r;
  const double e_len = e.norm();
  delta = e_len - j.clearance->clearance;
  delta_dot = e_len > 0.0 ? (pj.v - pb.v).dot(e) / e_len : 0.0;
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
  if (ws.loads_use_state) load_body_state(ws, y);

  // Applied forces: gravity, then loads, then clearance contacts.
  ws.g.setZero();
  ws.kinetic = ws.potential = ws.dissipated_power = ws.input_power = 0.0;
  for (int b = 0; b < ws.nb; ++b) {
    const Body& body = model.bodies[b];
    const Vec2 r(y[3 * b], y[3 * b + 1]), v(y[nq + 3 * b], y[nq + 3 * b + 1]);
    const double omega = y[nq + 3 * b + 2];
    ws.g.segment<2>(3 * b) += body.mass * model.gravity;
    ws.potential -= body.mass * model.gravity.dot(r);
    ws.kinetic += 0.5 * (body.mass * v.squaredNorm() + body.inertia * omega * omega);
  }

  for (size_t li = 0; li < model.loads.size(); ++li) {
    const Load& l = model.loads[li];
    switch (l.type) {
      case LoadType::force: {
        const PointKin p = point_kin(kin_of(ws, l.a.body), l.a.s);
        const Vec2 f(ws.load_expr[li][0].eval(), ws.load_expr[li][1].eval());
        apply(ws.g, l.a.body, p.s, f);
        ws.input_power += f.dot(p.v);
        break;
      }
      case LoadType::torque: {
        const double tau = ws.load_expr[li][0].eval();
        if (l.body_a != kGround) {
          ws.g[3 * l.body_a + 2] += tau;
          ws.input_power += tau * y[nq + 3 * l.body_a + 2];
        }
        break;
      }
      case LoadType::spring_damper: {
        const PointKin pa = point_kin(kin_of(ws, l.a.body), l.a.s);
        const PointKin pb = point_kin(kin_of(ws, l.b.body), l.b.s);
        const Vec2 d = pb.r - pa.r;
        const double len = d.norm();
        const Vec2 u = len > 0.0 ? Vec2(d / len) : Vec2::UnitX();
        const double len_dot = u.dot(pb.v - pa.v);
        const double tension = l.stiffness * (len - l.free_length) + l.damping * len_dot;
        apply(ws.g, l.a.body, pa.s, tension * u);
        apply(ws.g, l.b.body, pb.s, -tension * u);
        ws.potential += 0.5 * l.stiffness * (len - l.free_length) * (len - l.free_length);
        ws.dissipated_power += l.damping * len_dot * len_dot;
        break;
      }
      case LoadType::torsional_spring_damper: {
        const Kin &ka = kin_of(ws, l.body_a), &kb = kin_of(ws, l.body_b);
        const double theta = kb.phi - ka.phi - l.angle0, theta_dot = kb.omega - ka.omega;
        const double torque = l.stiffness * theta + l.damping * theta_dot;
        if (l.body_a != kGround) ws.g[3 * l.body_a + 2] += torque;
        if (l.body_b != kGround) ws.g[3 * l.body_b + 2] -= torque;
        ws.potential += 0.5 * l.stiffness * theta * theta;
        ws.dissipated_power += l.damping * theta_dot * theta_dot;
        break;
      }
    }
  }

  // Clearance joints: journal a inside bearing b.
  for (int k = 0; k < ws.nc; ++k) {
    const Joint& j = model.joints[ws.clearance_joints[k]];
    const Clearance& cl = *j.clearance;
    const Kin &kj = kin_of(ws, j.a.body), &kb = kin_of(ws, j.b.body);
    const PointKin pj = point_kin(kj, j.a.s), pb = point_kin(kb, j.b.s);
    ClearanceOutput& out = ws.clearance_out[k];
    out.e = pj.r - pb.r;
    out.e_len = out.e.norm();
    out.delta = out.e_len - cl.clearance;
    const Vec2 n = out.e_len > 0.0 ? Vec2(out.e / out.e_len) : Vec2::UnitX();
    const Vec2 tng = perp(n);
    const Vec2 e_dot = pj.v - pb.v;
    out.delta_dot = out.e_len > 0.0 ? e_dot.dot(n) : 0.0;
    out.v_t = e_dot.dot(tng) + cl.journal_radius * kj.omega - cl.bearing_radius * kb.omega;
    out.f_n = out.f_t = out.potential = out.dissipation = 0.0;
    if (out.delta <= 0.0) continue;
    // δ̇⁻ is the value located at onset; a stage that overshoots an unlocated onset uses δ̇.
    const double v_impact =
        std::max(ws.contact[k].in_contact ? ws.contact[k].impact_velocity : out.delta_dot,
                 cl.min_impact_velocity);
    out.f_n = normal_force(cl.normal_law, out.delta, out.delta_dot, v_impact, cl.contact);
    out.f_t = friction_force(cl.friction_law, out.v_t, out.f_n, cl.friction);
    out.potential = contact_potential(out.delta, cl.contact);
    const double elastic = hertz(out.delta, cl.contact);
    out.dissipation = (out.f_n - elastic) * out.delta_dot - out.f_t * out.v_t;
    // Normal force through the centres; friction at each body's contact point.
    apply(ws.g, j.a.body, pj.s, -out.f_n * n);
    apply(ws.g, j.b.body, pb.s, out.f_n * n);
    apply(ws.g, j.a.body, pj.s + cl.journal_radius * n, out.f_t * tng);
    apply(ws.g, j.b.body, pb.s + cl.bearing_radius * n, -out.f_t * tng);
    ws.potential += out.potential;
    ws.dissipated_power += out.dissipation;
  }

  // Constraint forces from the Schur complement.
  ws.qdd = ws.minv.cwiseProduct(ws.g);
  if (ws.m > 0) {
    build_constraints(model, ws, t, y, false, ws.phi, ws.phi_q, &ws.phi_dot, &ws.gamma);
    const double a = model.solver.baumgarte_alpha, b = model.solver.baumgarte_beta;
    // rhs = γ − 2αΦ̇ − β²Φ − Φ_q M⁻¹ g, and W = Φ_q M⁻¹ Φ_qᵀ, from the row structure (each row
    // touches at most two bodies), then W λ = rhs by an in-place Cholesky factorisation.
    const int m = ws.m;
    const Eigen::Map<const Eigen::VectorXd> qd(y + nq, nq);
    for (int i = 0; i < m; ++i) {
      double pq = 0.0, rate = 0.0;
      for (int bi : ws.row_bodies[i]) {
        if (bi < 0) continue;
        for (int k = 3 * bi; k < 3 * bi + 3; ++k) {
          pq += ws.phi_q(i, k) * ws.qdd[k];
          rate += ws.phi_q(i, k) * qd[k];
        }
      }
      ws.rhs_m[i] = ws.gamma[i] - 2.0 * a * ws.phi_dot[i] - b * b * ws.phi[i] - pq;
      ws.rate_m[i] = rate;
      for (int j = ws.row_first[i]; j <= i; ++j) {
        double sum = 0.0;
        for (int bi : ws.row_bodies[i]) {
          if (bi < 0 || (bi != ws.row_bodies[j][0] && bi != ws.row_bodies[j][1])) continue;
          for (int k = 3 * bi; k < 3 * bi + 3; ++k)
            sum += ws.phi_q(i, k) * ws.minv[k] * ws.phi_q(j, k);
        }
        ws.w(i, j) = sum;
      }
    }
    if (!cholesky_solve(ws.w, ws.row_first, ws.rhs_m, ws.lambda)) return false;
    for (int i = 0; i < m; ++i)
      for (int bi : ws.row_bodies[i]) {
        if (bi < 0) continue;
        for (int k = 3 * bi; k < 3 * bi + 3; ++k) ws.g[k] += ws.phi_q(i, k) * ws.lambda[i];
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
  ydot[2 * nq] = ws.dissipated_power;
  ydot[2 * nq + 1] = ws.input_power;
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

Eigen::VectorXd initial_state(const Model& model, Workspace& ws) {
  const int nq = ws.nq;
  const bool ideal = model.solver.initial_state == InitialStateRule::ideal;
  const int rows = ws.m + (ideal ? 2 * ws.nc : 0);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(ws.ny);
  for (int b = 0; b < ws.nb; ++b) {
    const Body& body = model.bodies[b];
    y.segment<2>(3 * b) = body.r0;
    y[3 * b + 2] = body.phi0;
    if (!ideal) {
      y.segment<2>(nq + 3 * b) = body.v0;
      y[nq + 3 * b + 2] = body.omega0;
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

  // The actual constraint set must be independent for the Schur complement to be SPD.
  if (ws.m > 0) {
    Eigen::VectorXd p(ws.m);
    Eigen::MatrixXd pq(ws.m, nq);
    update_kin(ws, y.data());
    build_constraints(model, ws, 0.0, y.data(), false, p, pq, nullptr, nullptr);
    Eigen::FullPivLU<Eigen::MatrixXd> lu(pq);
    if (lu.rank() < ws.m)
      throw std::runtime_error("the joints and drivers are redundant: " + std::to_string(ws.m) +
                               " constraint equations but only " + std::to_string(lu.rank()) +
                               " independent ones; remove a joint or a driver, or turn a "
                               "revolute joint into a clearance joint");
  }
  return y;
}

}  // namespace lash
