#include "core/dynamics.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <limits>
#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>
#include <stdexcept>

#include "core/elements/clearance_revolute.hpp"
#include "core/elements/constraint_rows.hpp"
#include "core/elements/registry.hpp"

namespace lash {

/// A constraint residual (m or rad) for a message: three significant digits, exponent form for
/// small ones ("1e-09", where %f printed "0.000000").
static std::string residual_text(double r) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", r);
  return b;
}

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

/// Configurations drawn around the assembled one for Φ_q's pattern (jacobian_pattern).
constexpr int kPatternProbes = 3;

/// Where Φ_q can be nonzero: the entries nonzero at y (assembled) or at kPatternProbes
/// configurations drawn around it, each coordinate moved by up to 1 + |q_k| (a fixed seed, so
/// every run of a model gets the same pattern). Every entry is a smooth function of the
/// configuration (sines and cosines of the angles, polynomials of the positions and modal
/// amplitudes), so one that is not identically 0 is 0 at a drawn configuration only by a
/// coincidence of probability 0; a coincidental 0 at assembly (a marker on a body's axis at
/// angle 0) is caught by the draws. The solver then leaves out what is 0 at every configuration:
/// a revolute row's coordinate across it, a driver's or an angle row's positions, a marker at a
/// body's centre of mass (on the Flores example L has 25 entries instead of 38, and a
/// factorisation 48 products instead of 84). `fixed`: the entries with the same value at y and
/// at every drawn configuration, i.e. constant (the ±1 of a revolute row's positions, a
/// driver's 1, a guide's direction on the ground); a smooth entry that is not constant takes
/// four equal values only by the same coincidence. The solver writes them once. Leaves ws.kin
/// at y.
JacobianPattern jacobian_pattern(const Model& model, Workspace& ws, double t, const double* y,
                                 const Eigen::MatrixXd& phi_q) {
  JacobianPattern pattern{phi_q.array() != 0.0,
                          Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic>::Ones(ws.m, ws.nq), {}, {}};
  Eigen::VectorXd probe = Eigen::Map<const Eigen::VectorXd>(y, ws.ny);
  Eigen::VectorXd phi(ws.m);
  Eigen::MatrixXd pq(ws.m, ws.nq);
  std::mt19937 draw(20261126u);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int p = 0; p < kPatternProbes; ++p) {
    for (int k = 0; k < ws.nq; ++k) probe[k] = y[k] + unit(draw) * (1.0 + std::abs(y[k]));
    update_kin(ws, probe.data());
    build_constraints(model, ws, t, probe.data(), false, phi, pq, nullptr, nullptr);
    pattern.nonzero = pattern.nonzero || (pq.array() != 0.0);
    pattern.fixed = pattern.fixed && (pq.array() == phi_q.array());
    pattern.drawn.push_back(pq);
  }
  // Redundant rows. At a singular position (a parallelogram's links in line, a four-bar's
  // change point) Φ_q loses rank at that configuration only, so the rows are counted again at
  // assembled configurations nearby, reached by moves of 1e-3 and 3e-2 along the null space of
  // the joints' rows (the mechanism's motions with the drivers let go, the singular direction
  // among them: a driven mechanism reaches a nearby configuration a moment later), one random
  // and one per driver along its coordinate, and Newton's method back onto the joints. With as
  // many redundant rows nearby as at assembly, the mechanism is redundant there: the rows
  // dropped are chosen by their share of the redundancy (rows_to_keep_by_share: the model's
  // order unless that leaves the rows kept nearly dependent, a crank along a world axis).
  // With fewer, the assembly is at a singular position: the fewest found nearby are the
  // mechanism's redundancy, chosen at the probe furthest from a singular position with that
  // count (a probe may land near the singular position again), and the rank the singular
  // position loses besides is carried by the regularised factorisation through the instant
  // (constraint_solver.hpp). A redundant driver is left dropped (build_solver refuses it).
  pattern.keep = independent_rows(phi_q);
  const int redundant = static_cast<int>(std::count(pattern.keep.begin(), pattern.keep.end(), false));
  bool driver_dropped = false;
  for (int r : ws.row_of_driver) driver_dropped = driver_dropped || !pattern.keep[r];
  if (redundant > 0) {
    auto joints_only = [&](Eigen::MatrixXd& a, Eigen::VectorXd* v) {
      for (int r : ws.row_of_driver) {
        a.row(r).setZero();
        if (v) (*v)[r] = 0.0;
      }
    };
    Eigen::MatrixXd joint_rows = phi_q;
    joints_only(joint_rows, nullptr);
    // The joints' null space at the redundancy test's tolerance: a state continued from a run
    // holds its joints to the drift (1e-12), so the rows of a redundant set are dependent to that
    // only, and LU's default threshold (round-off) found no null space to probe along.
    Eigen::FullPivLU<Eigen::MatrixXd> lu(joint_rows);
    lu.setThreshold(kRedundancyTolerance);
    const Eigen::MatrixXd null = lu.kernel();
    std::vector<Eigen::MatrixXd> nearby;        // Φ_q at the probes
    int redundant_nearby = redundant;
    std::vector<int> counts;                    // redundant rows at each probe
    bool driver_kept_nearby = false;            // at some probe every driver's row is independent
    // Besides a random move, per driver the move in that null space along which its coordinate
    // changes most (the way the drivers take the mechanism: at a singular assembly a random
    // move has a part along the flex, which is no motion).
    Eigen::MatrixXd along_drivers(ws.nq, 0);
    if (null.cols() > 0) {
      const Eigen::MatrixXd basis =
          Eigen::HouseholderQR<Eigen::MatrixXd>(null).householderQ() *
          Eigen::MatrixXd::Identity(ws.nq, null.cols());
      for (int r : ws.row_of_driver) {
        const Eigen::VectorXd d = basis * (basis.transpose() * phi_q.row(r).transpose());
        if (d.norm() > 0.0) {
          along_drivers.conservativeResize(Eigen::NoChange, along_drivers.cols() + 1);
          along_drivers.rightCols(1) = d;
        }
      }
    }
    const int probes = null.cols() > 0 && null.norm() > 0.0 ? 2 * (1 + along_drivers.cols()) : 0;
    for (int p = 0; p < probes; ++p) {
      const double move = p < probes / 2 ? 1e-3 : 3e-2;
      const int which = p % (probes / 2);
      Eigen::VectorXd d;
      if (which == 0) {
        Eigen::VectorXd r(null.cols());
        for (int k = 0; k < r.size(); ++k) r[k] = unit(draw);
        d = null * r;
      } else {
        d = along_drivers.col(which - 1);
      }
      if (!(d.norm() > 0.0)) continue;
      const Eigen::VectorXd u = d / d.norm();
      probe = Eigen::Map<const Eigen::VectorXd>(y, ws.ny);
      probe.head(ws.nq) += move * u;
      // Newton's steps orthogonal to the move (its length along u is kept): unconstrained
      // minimum-norm steps from a move with a part along a singular position's flex (a motion
      // to first order only) went back to that position (a double parallelogram assembled in
      // line: σ ratio 1.5e-7 at the probes), and the rows were chosen there.
      const Eigen::MatrixXd across = Eigen::MatrixXd::Identity(ws.nq, ws.nq) - u * u.transpose();
      double residual = 1.0;
      for (int it = 0; it < 50 && !(residual < 1e-12); ++it) {
        update_kin(ws, probe.data());
        build_constraints(model, ws, t, probe.data(), false, phi, pq, nullptr, nullptr);
        Eigen::MatrixXd a = pq;
        joints_only(a, &phi);
        residual = phi.cwiseAbs().maxCoeff();
        if (!(residual < 1e-12))
          probe.head(ws.nq) -=
              across * Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(a * across).solve(phi);
      }
      if (!(residual < 1e-12)) continue;  // pq is Φ_q at the converged probe (no step after)
      nearby.push_back(pq);
      const std::vector<bool> near = independent_rows(pq);
      const int count = static_cast<int>(std::count(near.begin(), near.end(), false));
      counts.push_back(count);
      redundant_nearby = std::min(redundant_nearby, count);
      bool drivers_kept = true;
      for (int r : ws.row_of_driver) drivers_kept = drivers_kept && near[r];
      driver_kept_nearby = driver_kept_nearby || drivers_kept;
    }
    if (probes > 0 && nearby.empty() && !driver_dropped) {
      // No move along the joints' first-order motions comes back onto the joints: they are no
      // motions (a rod tangent to the guide its end slides on: free to first order, held to
      // second). The mechanism is locked at a singular position, where holding it takes
      // unbounded reactions; counting a row redundant there dropped a joint that holds it (the
      // bob slid off with the rod stretched, and the run failed blaming the stabilization).
      std::string dependent;
      for (int r = 0; r < ws.m; ++r)
        if (!pattern.keep[r]) {
          const std::string what = constraint_row_element(model, ws, r).what;
          if (dependent.find(what) == std::string::npos)
            dependent += (dependent.empty() ? "" : ", ") + what;
        }
      throw std::runtime_error(
          dependent + ": its equations are dependent on the other joints' at the starting "
          "configuration, and no configuration nearby satisfies the joints: the mechanism is "
          "locked at a singular position (a link tangent to the guide it slides on, a toggle "
          "with nothing to move), where holding it would take unbounded reactions; start it off "
          "that position");
    }
    if (driver_dropped && !driver_kept_nearby) {
      // A driver redundant nearby as well: its motion is fixed by the joints (build_solver
      // refuses it). Redundant only at assembly, it is a singular position (a state continued
      // 2e-7 rad from a double parallelogram's in-line position: the joints' rows, one nearly
      // dependent, were all kept in order and the driver's counted redundant).
    } else if (redundant_nearby == redundant) {
      pattern.keep = rows_to_keep_by_share(phi_q, redundant, ws.row_of_driver);
    } else if (redundant_nearby > 0) {
      // Chosen at the probe furthest from a singular position among those with the fewest.
      int fewest = -1;
      double best = -1.0;
      for (size_t p = 0; p < nearby.size(); ++p) {
        if (counts[p] != redundant_nearby) continue;
        const double ratio = rank_ratio(nearby[p], ws.m - redundant_nearby);
        if (!(ratio <= best)) best = ratio, fewest = static_cast<int>(p);
      }
      pattern.counted = nearby[fewest];
      pattern.keep = rows_to_keep_by_share(pattern.counted, redundant_nearby, ws.row_of_driver);
    } else {
      pattern.keep.assign(ws.m, true);  // a singular position of a mechanism not redundant
    }
    const int kept = static_cast<int>(std::count(pattern.keep.begin(), pattern.keep.end(), true));
    for (const Eigen::MatrixXd& near : nearby)
      pattern.nearby_rank = std::max(pattern.nearby_rank, rank_ratio(near, kept));
  }
  update_kin(ws, y);
  return pattern;
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

/// Size of body b's rigid motion: 3 (x, y, φ) for a rigid body or a flexible link, 2 for a point
/// mass.
int rigid_size(const Model& model, int b) { return model.bodies[b].type == BodyType::point_mass ? 2 : 3; }


/// The bodies' rigid motions q̇ = T u, u = per body (v_x, v_y[, ω]): the identity for rigid
/// bodies and point masses; for a flexible link the motion of its current shape as a rigid body
/// about the middle c of its chord, ṙ_i = v + ω perp(r_i − c), ṙ'_i = ω perp(r'_i).
Eigen::MatrixXd rigid_motion_basis(const Model& model, const Workspace& ws, const double* y) {
  int nu = 0;
  for (int b = 0; b < ws.nb; ++b) nu += rigid_size(model, b);
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(ws.nq, nu);
  int u = 0;
  for (int b = 0; b < ws.nb; ++b) {
    const BodyBlock& bl = ws.blocks[b];
    if (!model.bodies[b].flexible()) {
      t.block(bl.offset, u, bl.size, bl.size).setIdentity();
      u += bl.size;
      continue;
    }
    const Vec2 c = body_kin(ws, b, y).r;
    for (int i = 0; i < bl.size; i += beam::kNodeCoordinates) {
      const Vec2 r(y[bl.offset + i], y[bl.offset + i + 1]), s(y[bl.offset + i + 2], y[bl.offset + i + 3]);
      t.block<2, 2>(bl.offset + i, u).setIdentity();
      t.block<2, 1>(bl.offset + i, u + 2) = perp(Vec2(r - c));
      t.block<2, 1>(bl.offset + i + 2, u + 2) = perp(s);
    }
    u += 3;
  }
  return t;
}

/// Moves every body rigidly by du (the coordinates of rigid_motion_basis): a flexible link
/// turns by an exact rotation about the middle of its chord, so its strain does not change.
void move_rigidly(const Model& model, const Workspace& ws, Eigen::VectorXd& y, const Eigen::VectorXd& du) {
  int u = 0;
  for (int b = 0; b < ws.nb; ++b) {
    const BodyBlock& bl = ws.blocks[b];
    if (!model.bodies[b].flexible()) {
      y.segment(bl.offset, bl.size) += du.segment(u, bl.size);
      u += bl.size;
      continue;
    }
    const Vec2 c = body_kin(ws, b, y.data()).r, d = du.segment<2>(u);
    const Eigen::Matrix2d rot = rotation(du[u + 2]);
    for (int i = 0; i < bl.size; i += beam::kNodeCoordinates) {
      const Vec2 r = y.segment<2>(bl.offset + i);
      y.segment<2>(bl.offset + i) = c + d + rot * (r - c);
      y.segment<2>(bl.offset + i + 2) = rot * Vec2(y.segment<2>(bl.offset + i + 2));
    }
    u += 3;
  }
}

}  // namespace

int Model::clearance_joint_count() const {
  int n = 0;
  for (const auto& j : joints) n += j.clearance.has_value();
  return n;
}

/// Pose and velocity of a body from y into k (whose block, and mesh for a flexible link, are set).
/// A flexible link's coordinates are read through k.q, k.qd: into `store` (the workspace's copy,
/// so that what the elements read stays valid after y is gone), or into y itself when null.
inline void read_kin(BodyKin& k, int nq, const double* y, double* store = nullptr) {
  const BodyBlock& bl = k.block;
  if (k.mesh) {
    // A flexible link: the chord from end A (node 0) to end B (the last node).
    if (store) {
      std::copy(y + bl.offset, y + bl.offset + bl.size, store + bl.offset);
      std::copy(y + nq + bl.offset, y + nq + bl.offset + bl.size, store + nq + bl.offset);
      y = store;
    }
    k.q = y + bl.offset;
    k.qd = y + nq + bl.offset;
    const int b = bl.size - beam::kNodeCoordinates;
    const Vec2 ra(k.q[0], k.q[1]), rb(k.q[b], k.q[b + 1]);
    const Vec2 va(k.qd[0], k.qd[1]), vb(k.qd[b], k.qd[b + 1]);
    const Vec2 d = rb - ra;
    k.r = 0.5 * (ra + rb);
    k.v = 0.5 * (va + vb);
    k.phi = std::atan2(d.y(), d.x());
    k.omega = cross(d, Vec2(vb - va)) / d.squaredNorm();
    k.A = rotation(k.phi);
    return;
  }
  k.r = Vec2(y[bl.offset], y[bl.offset + 1]);
  k.v = Vec2(y[nq + bl.offset], y[nq + bl.offset + 1]);
  if (bl.rot >= 0) {
    // k.A is rotation(k.phi) at every moment (a new BodyKin: 0 and I), so an unchanged angle
    // (a slider's on its guide) keeps its matrix without another sincos.
    const double phi = y[bl.rot];
    if (phi != k.phi) k.A = rotation(phi), k.phi = phi;
    k.omega = y[nq + bl.rot];
  }
}

BodyKin body_kin(const Workspace& ws, int b, const double* y) {
  BodyKin k;
  if (b == kGround) return k;
  k.block = ws.blocks[b];
  k.mesh = ws.kin[b].mesh;
  read_kin(k, ws.nq, y);
  return k;
}

Eigen::MatrixXd mass_matrix(const Workspace& ws) {
  Eigen::MatrixXd m = ws.mass_diag.asDiagonal();
  for (const auto& e : ws.mass_coupling) m(e.i, e.j) = m(e.j, e.i) = e.value;
  return m;
}

Eigen::SparseMatrix<double> sparse_mass_matrix(const Workspace& ws) {
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(ws.mass_diag.size() + 2 * ws.mass_coupling.size());
  for (int i = 0; i < ws.mass_diag.size(); ++i) entries.emplace_back(i, i, ws.mass_diag[i]);
  for (const auto& e : ws.mass_coupling) {
    entries.emplace_back(e.i, e.j, e.value);
    entries.emplace_back(e.j, e.i, e.value);
  }
  Eigen::SparseMatrix<double> m(ws.mass_diag.size(), ws.mass_diag.size());
  m.setFromTriplets(entries.begin(), entries.end(), [](double, double b) { return b; });
  return m;
}

std::vector<std::string> state_names(const Model& model, const Workspace& ws) {
  std::vector<std::string> n(ws.ny);
  for (int b = 0; b < ws.nb; ++b) {
    const BodyBlock& bl = ws.blocks[b];
    const std::string& name = model.bodies[b].name;
    if (model.bodies[b].flexible()) {
      const char* q[4] = {".x", ".y", ".sx", ".sy"};  // position and slope r' of each node
      const char* v[4] = {".vx", ".vy", ".vsx", ".vsy"};
      for (int i = 0; i < bl.size; ++i) {
        const std::string node = name + ".n" + std::to_string(i / beam::kNodeCoordinates);
        n[bl.offset + i] = node + q[i % 4];
        n[ws.nq + bl.offset + i] = node + v[i % 4];
      }
      continue;
    }
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
  n[ws.i_stabilization] = "energy.stabilization";
  return n;
}

void update_kin(Workspace& ws, const double* y) {
  // In place: the blocks were set once by the Workspace; only pose and velocity change.
  for (BodyKin& k : ws.kin) read_kin(k, ws.nq, y, ws.flexible_state.data());
}

double run_violation_limit(const Model& model) {
  Vec2 lo = Vec2::Constant(INFINITY), hi = Vec2::Constant(-INFINITY);
  auto add = [&](const Vec2& p) { lo = lo.cwiseMin(p), hi = hi.cwiseMax(p); };
  auto point = [&](const PointRef& p) {
    if (p.body == kGround) return p.s;
    const Body& b = model.bodies[p.body];
    return Vec2(b.r0 + rotation(b.phi0) * p.s);
  };
  for (const Body& b : model.bodies) add(b.r0);
  for (const Joint& j : model.joints) add(point(j.a)), add(point(j.b));
  const double size = (hi - lo).norm();
  return std::isfinite(size) && size > 0.0 ? std::min(kRunViolationLimit, kRunViolationShare * size)
                                           : kRunViolationLimit;
}

Workspace::Workspace(const Model& model) {
  if (!model.finalized)
    throw std::invalid_argument("Workspace: the model has not been finalized (lash::finalize)");
  violation_limit = run_violation_limit(model);
  nb = static_cast<int>(model.bodies.size());
  // Coordinate blocks: one per body, sized by its kind.
  for (const Body& b : model.bodies) {
    BodyBlock bl;
    bl.offset = nq;
    bl.size = kind_of(b).coordinates(b);
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
  kin.assign(nb, BodyKin{});
  meshes.resize(nb);
  // Until the first evaluation the kinematics are those of the initial poses at rest (channel
  // descriptions read them).
  flexible_state = Eigen::VectorXd::Zero(2 * nq);
  for (int b = 0; b < nb; ++b) {
    kin[b].block = blocks[b];
    meshes[b] = model.bodies[b].mesh;
    const Body& body = model.bodies[b];
    kind_of(body).initial(body, flexible_state.data() + blocks[b].offset, nullptr);
    if (body.flexible()) kin[b].mesh = &meshes[b];
  }
  {
    const Eigen::VectorXd y0 = flexible_state;
    for (BodyKin& k : kin) read_kin(k, nq, y0.data(), flexible_state.data());
  }
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
  i_stabilization = i_input + 1;
  ny = i_stabilization + 1;

  for (const auto& b : model.bodies) vars.body_names.push_back(b.name);
  vars.body_state.assign(6 * nb, 0.0);
  // Drivers need ḟ, f̈ of a position profile and f̈ of a speed profile (exact: expression.hpp).
  for (const auto& d : model.drivers) {
    if (d.profile == DriverProfile::constant_speed)
      driver_expr.emplace_back();  // no expression (a parser costs ~1.6 M instructions to build)
    else
      driver_expr.emplace_back(std::in_place, d.expression, vars,
                               d.profile == DriverProfile::position ? 2 : 1);
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

  mass_diag.resize(nq);
  for (int b = 0; b < nb; ++b) {
    const BodyBlock& bl = blocks[b];
    Eigen::MatrixXd mb = Eigen::MatrixXd::Zero(bl.size, bl.size);
    kind_of(model.bodies[b]).mass(model.bodies[b], mb);
    for (int i = 0; i < bl.size; ++i) {
      mass_diag[bl.offset + i] = mb(i, i);
      for (int j = i + 1; j < bl.size; ++j)
        if (mb(i, j) != 0.0) mass_coupling.push_back({bl.offset + i, bl.offset + j, mb(i, j)});
    }
  }
  g.resize(nq);
  qdd = Eigen::VectorXd::Zero(nq);
  phi.resize(m);
  phi_dot.resize(m);
  gamma.resize(m);
  rhs_m.resize(m);
  lambda = Eigen::VectorXd::Zero(m);
  phi_q = Eigen::MatrixXd::Zero(m, nq);
}

void event_functions(const Model& model, const Workspace& ws, const double* y, double* g,
                     double* through) {
  for (int k = 0; k < ws.nc; ++k) {
    double delta, delta_dot;
    clearance_gap(model, ws, k, y, delta, delta_dot);
    g[k] = ws.contact[k].in_contact ? -delta : delta;
    if (through) through[k] = delta - model.joints[ws.clearance_joints[k]].clearance->journal_radius;
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
    kind_of(body).forces(model, body, ws.kin[b], ws);
  }
  // Kinetic energy ½ q̇ᵀ M q̇ from the constant mass matrix (every kind's block).
  const Eigen::Map<const Eigen::VectorXd> q_dot(y + nq, nq);
  ws.kinetic = 0.5 * q_dot.cwiseAbs2().dot(ws.mass_diag);
  for (const auto& e : ws.mass_coupling) ws.kinetic += e.value * q_dot[e.i] * q_dot[e.j];
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

  // Constraint forces: the sparse augmented system (core/constraint_solver.hpp).
  ws.stabilization_power = 0.0;
  if (ws.m > 0) {
    build_constraints(model, ws, t, y, false, ws.phi, ws.phi_q, &ws.phi_dot, &ws.gamma);
    if (!ws.solver)
      prepare_constraint_solver(model, ws, ws.phi_q, jacobian_pattern(model, ws, t, y, ws.phi_q));
    const double a = model.solver.baumgarte_alpha, b = model.solver.baumgarte_beta;
    // γ_B = γ − 2αΦ̇ − β²Φ.
    ws.rhs_m = ws.gamma - (2.0 * a) * ws.phi_dot - (b * b) * ws.phi;
    if (!solve_constraints(ws)) return false;
    // Redundant rows: the ones dropped are chosen again where the kept ones grow weak.
    if (kept_rows_weak(ws) && reselect_redundant_rows(model, ws) && !solve_constraints(ws))
      return false;
    // Power of the constraint forces λ·Φ_q q̇ = λ·(Φ̇ − Φ_t), split into the drivers' input
    // −λΦ_t (Φ_t = 0 for every other row) and the work on the drift, λ·Φ̇: Baumgarte's, which
    // would be 0 on the exact constraint manifold. A driver's Φ_q q̇ from its row's blocks.
    for (int r : ws.row_of_driver) {
      double rate = 0.0;
      for (int bi : ws.row_bodies[r])
        if (bi >= 0)
          for_block(ws.blocks[bi], [&](int k) { rate += ws.phi_q(r, k) * y[nq + k]; });
      ws.input_power += ws.lambda[r] * (rate - ws.phi_dot[r]);
    }
    ws.stabilization_power = ws.lambda.dot(ws.phi_dot);
    // After the powers: those of the solve itself. Left to report_multipliers while integrating.
    ws.multipliers_reported = !ws.integrating;
    if (!ws.integrating) smallest_multipliers(ws);
    ws.constraint_violation = ws.phi.cwiseAbs().maxCoeff();
  } else {
    // No constraints: M q̈ = g, block by block (a flexible link's block through its Cholesky
    // factor, computed once).
    if (ws.mass_coupling.empty()) {
      ws.qdd = ws.g.cwiseQuotient(ws.mass_diag);
    } else {
      if (!ws.mass_factor) ws.mass_factor = std::make_unique<Eigen::LLT<Eigen::MatrixXd>>(mass_matrix(ws));
      ws.qdd = ws.mass_factor->solve(ws.g);
    }
    ws.constraint_violation = 0.0;
  }

  for (int i = 0; i < nq; ++i) {
    ydot[i] = y[nq + i];
    ydot[nq + i] = ws.qdd[i];
  }
  ydot[ws.i_dissipated] = ws.dissipated_power;
  ydot[ws.i_input] = ws.input_power;
  ydot[ws.i_stabilization] = ws.stabilization_power;
  return std::isfinite(ws.qdd.sum()) && std::isfinite(ws.dissipated_power) &&
         std::isfinite(ws.stabilization_power);
}

void report_multipliers(Workspace& ws) {
  if (ws.multipliers_reported || ws.m == 0 || !ws.solver) return;
  smallest_multipliers(ws);
  ws.multipliers_reported = true;
}

double constraint_residual(const Model& model, Workspace& ws, double t, const double* y) {
  if (ws.m == 0) return 0.0;
  update_kin(ws, y);
  build_constraints(model, ws, t, y, false, ws.phi, ws.phi_q, nullptr, nullptr);
  return ws.phi.cwiseAbs().maxCoeff();
}

bool project_onto_constraints(const Model& model, Workspace& ws, double t, Eigen::VectorXd& y) {
  if (ws.m == 0 || !ws.solver || !ws.solver->ldlt.near_singular()) return false;
  const int nq = ws.nq;
  Eigen::VectorXd y0 = y, ydot(ws.ny);
  if (!evaluate(model, ws, t, y.data(), ydot.data())) return false;
  const double energy0 = ws.kinetic + ws.potential;
  // Each correction solves [M Φ_qᵀ; Φ_q −εD] [Δ; −μ] = [0; −r]: Δ = M⁻¹Φ_qᵀμ with Φ_q Δ = −r.
  auto correct = [&](const Eigen::VectorXd& r, int offset) {
    ws.g.setZero();
    ws.rhs_m = -r;
    if (!solve_constraints(ws)) return false;
    y.segment(offset, nq) += ws.qdd;
    return true;
  };
  for (int it = 0; it < 4; ++it) {
    update_kin(ws, y.data());
    build_constraints(model, ws, t, y.data(), false, ws.phi, ws.phi_q, nullptr, nullptr);
    if (!(ws.phi.cwiseAbs().maxCoeff() > 1e-15)) break;
    if (!correct(ws.phi, 0)) return y = y0, false;
  }
  update_kin(ws, y.data());
  build_constraints(model, ws, t, y.data(), false, ws.phi, ws.phi_q, &ws.phi_dot, nullptr);
  if (!correct(ws.phi_dot, nq)) return y = y0, false;
  if (!evaluate(model, ws, t, y.data(), ydot.data()) || !y.allFinite()) {
    y = y0;
    evaluate(model, ws, t, y.data(), ydot.data());
    return false;
  }
  // energy.balance = kinetic + potential + dissipated − input − stabilization stays as it was.
  y[ws.i_stabilization] += ws.kinetic + ws.potential - energy0;
  ws.solver->ldlt.clear_near_singular();
  return true;
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
                             residual_text(residual) + ")");
  update_kin(ws, y.data());
  build_constraints(model, ws, t, y.data(), false, phi, phi_q, &phi_dot, nullptr);
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(phi_q);
  y.segment(nq, nq) -= cod.solve(phi_dot);
}

std::vector<int> drivers_out_of_reach(const Model& model, Workspace& ws, double t,
                                      const Eigen::VectorXd& y) {
  std::vector<int> found;
  if (ws.m == 0 || model.drivers.empty()) return found;
  const int nq = ws.nq;
  Eigen::VectorXd phi(ws.m), part, yy, trial, step;
  Eigen::MatrixXd phi_q(ws.m, nq), part_q;
  std::vector<bool> out(ws.m, false);
  std::vector<int> rows;
  // The rows not left out at a configuration: their residual's largest entry and 2-norm.
  auto residual_at = [&](const Eigen::VectorXd& at, bool with_jacobian, double& norm) {
    update_kin(ws, at.data());
    build_constraints(model, ws, t, at.data(), false, phi, phi_q, nullptr, nullptr);
    for (size_t i = 0; i < rows.size(); ++i) {
      part[static_cast<Eigen::Index>(i)] = phi[rows[i]];
      if (with_jacobian) part_q.row(static_cast<Eigen::Index>(i)) = phi_q.row(rows[i]);
    }
    norm = part.norm();
    return part.cwiseAbs().maxCoeff();
  };
  // Gauss–Newton with halving steps on the rows not left out, from y's positions: do they close
  // (to the 1e-10 that assembly accepts)? Least squares where they cannot, stopped when a step
  // no longer lowers the residual's norm.
  auto close = [&]() {
    rows.clear();
    for (int r = 0; r < ws.m; ++r)
      if (!out[r]) rows.push_back(r);
    if (rows.empty()) return true;
    part.resize(static_cast<Eigen::Index>(rows.size()));
    part_q.resize(part.size(), nq);
    yy = y;
    double norm = 0.0;
    for (int it = 0; it < 60; ++it) {
      if (residual_at(yy, true, norm) < 1e-10) return true;
      step = Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(part_q).solve(part);
      bool lower = false;
      for (double a = 1.0; a > 1e-3 && !lower; a *= 0.5) {
        trial = yy;
        trial.head(nq) -= a * step;
        double trial_norm = 0.0;
        residual_at(trial, false, trial_norm);
        lower = trial_norm < (1.0 - 1e-4 * a) * norm;
      }
      if (!lower) return false;
      yy = trial;
    }
    return false;
  };
  const bool all_close = close();
  for (const int r : ws.row_of_driver) out[r] = true;
  if (!all_close && close()) {
    // Each driver alone: the joints and the other drivers close without it. Where no single
    // one is at fault (only together), none is named.
    for (size_t d = 0; d < model.drivers.size(); ++d) {
      for (size_t k = 0; k < model.drivers.size(); ++k) out[ws.row_of_driver[k]] = k == d;
      if (close()) found.push_back(static_cast<int>(d));
    }
  }
  update_kin(ws, y.data());
  return found;
}

std::string constraint_problem(const Model& model, Workspace& ws, double t,
                               const Eigen::VectorXd& y, bool check_residual) {
  if (ws.m == 0) return "";
  const int nq = ws.nq;
  Eigen::VectorXd p(ws.m), pd(ws.m);
  Eigen::MatrixXd pq(ws.m, nq);
  update_kin(ws, y.data());
  build_constraints(model, ws, t, y.data(), false, p, pq, &pd, nullptr);
  // Redundant joint equations are dropped (named in ws.warnings); a redundant driver throws.
  try {
    prepare_constraint_solver(model, ws, pq, jacobian_pattern(model, ws, t, y.data(), pq));
  } catch (const std::runtime_error& e) {
    return e.what();
  }
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

namespace {

/// Why assembly failed, at the configuration closest to closing (phi, phi_q there), said at the
/// element at fault so that the message is placed at its line. Where Φ_q is short of rank
/// (kRedundancyTolerance) and most of the residual lies in its left null space, the equations
/// are redundant but disagree: no motion can reduce that part (three parallel cranks one of
/// which is 1e-9 m longer: 1.2e-10 m is left, beyond the 1e-10 m assembly accepts; two
/// drivers of one motion whose values differ). The element is then the redundant row's (the
/// last in the model's order with at least kDropShare of the largest share of the null space,
/// as the redundancy warning picks it), and the message names those it disagrees with; else it
/// is the element whose equation is worst off.
std::string assembly_failure(const Model& model, const Workspace& ws, const Eigen::VectorXd& phi,
                             const Eigen::MatrixXd& phi_q) {
  auto owner = [&](Eigen::Index row) {
    return row < ws.m ? constraint_row_element(model, ws, static_cast<int>(row)).what
                      : "joint '" + model.joints[ws.clearance_joints[(row - ws.m) / 2]].name + "'";
  };
  const Eigen::Index rows = phi.size();
  Eigen::Index worst = 0;
  const double residual = phi.cwiseAbs().maxCoeff(&worst);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(phi_q, Eigen::ComputeFullU);
  const Eigen::VectorXd& sv = svd.singularValues();
  Eigen::Index rank = 0;
  while (rank < sv.size() && sv[rank] > kRedundancyTolerance * sv[0]) ++rank;
  if (rank < rows) {
    const Eigen::MatrixXd left = svd.matrixU().rightCols(rows - rank);
    const double disagreement = (left.transpose() * phi).norm();
    if (disagreement >= 0.5 * phi.norm()) {
      const Eigen::VectorXd share = left.rowwise().norm();
      const double most = share.maxCoeff();
      Eigen::Index pick = 0;
      for (Eigen::Index r = 0; r < rows; ++r)
        if (share[r] >= kDropShare * most) pick = r;
      std::vector<std::string> names;
      for (Eigen::Index r = 0; r < rows; ++r) names.push_back(owner(r));
      const std::string& who = names[pick];
      const std::string list = other_names(names, share, 1e-8 * most, who);
      if (std::find(ws.row_of_driver.begin(), ws.row_of_driver.end(), pick) !=
          ws.row_of_driver.end())
        return who + ": initial assembly failed: its equation is redundant with " + list +
               " and disagrees with them by " + residual_text(disagreement) +
               " (m or rad): the motion it prescribes is already fixed; remove the driver or "
               "one of those";
      return who + ": initial assembly failed: its equations are redundant with " + list +
             " and disagree with them by " + residual_text(disagreement) +
             " (m or rad; a redundant joint must agree with the others to 1e-10): its markers "
             "close the loop only approximately (a link slightly longer than the one parallel "
             "to it, a pivot slightly off); make them agree, or remove the joint";
    }
  }
  return owner(worst) + ": initial assembly failed: the joints and drivers cannot all be "
                        "satisfied from the given poses (largest residual " +
         residual_text(residual) + ", in this one's equations); check the markers and initial "
                                   "positions";
}

/// At a singular position (Φ_q short of rank beyond any redundancy: a parallelogram in line)
/// the velocity constraints Φ_q q̇ = −Φ_t leave a direction free that no driver fixes, and the
/// least-kinetic-energy velocities need not lie on any branch of the motion through it: the
/// acceleration equations Φ_q q̈ = γ(q̇) then have no solution (uᵀγ ≠ 0 for a vector u of Φ_q's
/// left null space), and the run starts with a blow that Baumgarte's terms deliver (a
/// parallelogram assembled in line and driven at 2000 rpm: 1.3e4 J of stabilization work under
/// DOPRI5; under BDF the coupler spun). The velocities are moved along the free directions
/// (orthonormal in the kinetic-energy metric, coordinates a) to a root of F(a) = Uᵀγ(q̇ + Wa),
/// quadratic in a: Newton's method with minimum-norm steps from a = 0 and from ±s along each
/// free direction (s the velocities' own size), the root of least kinetic energy kept. Nothing
/// changes where Uᵀγ is already about 0 (away from singular positions, at rest), or when no
/// root is found (the run's stabilization warning then says what happened). phi, phi_q and
/// phi_dot are the caller's buffers (their rows: the joints', drivers' and with close_clearance
/// the clearance joints' closures); ws.kin is left at a trial state.
/// A Cholesky factor of the mass matrix, M = L Lᵀ in the coordinates' own order (matrixL/U).
using MassFactor = Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower,
                                        Eigen::NaturalOrdering<int>>;

void velocities_on_a_branch(const Model& model, Workspace& ws, bool close_clearance,
                            Eigen::VectorXd& y, Eigen::VectorXd& phi, Eigen::MatrixXd& phi_q,
                            Eigen::VectorXd& phi_dot) {
  const int nq = ws.nq, rows = static_cast<int>(phi.size());
  Eigen::VectorXd gamma(rows);
  update_kin(ws, y.data());
  build_constraints(model, ws, 0.0, y.data(), close_clearance, phi, phi_q, &phi_dot, &gamma);
  const double scale = gamma.norm();
  if (!(scale > 0.0)) return;
  // M = L Lᵀ (sparse: M is block diagonal by bodies), Φ_q L⁻ᵀ = (L⁻¹ Φ_qᵀ)ᵀ. Its rank from the
  // singular values alone first: the common full rank returns before the full SVD, whose
  // nq × nq V made assembly cost nq³ (1.6 s beside 800 free bodies).
  const Eigen::SparseMatrix<double> m = sparse_mass_matrix(ws);
  const MassFactor chol(m);
  const Eigen::MatrixXd scaled =
      chol.matrixL().solve(Eigen::MatrixXd(phi_q.transpose())).transpose();
  auto rank_of = [&](const Eigen::VectorXd& sv) {
    int r = 0;
    while (r < sv.size() && sv[r] > 1e-8 * sv[0]) ++r;
    return r;
  };
  if (const int r = rank_of(Eigen::JacobiSVD<Eigen::MatrixXd>(scaled).singularValues());
      r == 0 || r == rows || r == nq)
    return;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(scaled, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const int rank = rank_of(svd.singularValues());
  if (rank == 0 || rank == rows || rank == nq) return;
  const Eigen::MatrixXd left = svd.matrixU().rightCols(rows - rank);
  const Eigen::MatrixXd free =
      chol.matrixU().solve(Eigen::MatrixXd(svd.matrixV().rightCols(nq - rank)));
  const Eigen::VectorXd v0 = y.segment(nq, nq);
  auto residual = [&](const Eigen::VectorXd& a) {
    y.segment(nq, nq) = v0 + free * a;
    update_kin(ws, y.data());
    build_constraints(model, ws, 0.0, y.data(), close_clearance, phi, phi_q, &phi_dot, &gamma);
    return Eigen::VectorXd(left.transpose() * gamma);
  };
  const double tolerance = 1e-10 * scale;
  const Eigen::VectorXd f0 = residual(Eigen::VectorXd::Zero(nq - rank));
  if (f0.norm() <= 1e3 * tolerance) return;  // y as given
  // The starts' size: the velocities' own, or from rest (F(a) = F(0) + Q(a), Q quadratic, no
  // linear term to move Newton off a = 0) the size at which Q balances F(0), Q(±e_i) measured
  // along each free direction (a slider-crank driven at its slider from rest at dead centre:
  // the crank started at rest, and a push of 3.4e8 N started it).
  double s = std::sqrt(v0.dot(m * v0));  // |Lᵀ v0|
  if (!(s > 0.0)) {
    double q = 0.0;
    for (int i = 0; i < nq - rank; ++i) {
      const Eigen::VectorXd e = Eigen::VectorXd::Unit(nq - rank, i);
      q = std::max(q, 0.5 * (residual(e) + residual(-e) - 2.0 * f0).norm());
    }
    s = q > 0.0 ? std::sqrt(f0.norm() / q) : 0.0;
  }
  s = std::max(s, 1e-300);
  std::vector<Eigen::VectorXd> starts{Eigen::VectorXd::Zero(nq - rank)};
  for (int i = 0; i < nq - rank; ++i)
    for (double sign : {1.0, -1.0}) starts.push_back(sign * s * Eigen::VectorXd::Unit(nq - rank, i));
  Eigen::VectorXd best;
  for (Eigen::VectorXd a : starts) {
    Eigen::MatrixXd jacobian(left.cols(), nq - rank);
    Eigen::VectorXd f = residual(a);
    for (int it = 0; it < 40 && f.norm() > tolerance; ++it) {
      // F is quadratic in a: central differences give its derivative to round-off.
      for (int i = 0; i < nq - rank; ++i) {
        const Eigen::VectorXd e = 1e-3 * s * Eigen::VectorXd::Unit(nq - rank, i);
        jacobian.col(i) = (residual(a + e) - residual(a - e)) / (2e-3 * s);
      }
      a -= Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(jacobian).solve(f);
      f = residual(a);
    }
    if (f.norm() <= tolerance && (best.size() == 0 || a.norm() < best.norm())) best = a;
  }
  y.segment(nq, nq) = best.size() > 0 ? Eigen::VectorXd(v0 + free * best) : v0;
}

}  // namespace

Eigen::VectorXd initial_state(const Model& model, Workspace& ws) {
  const int nq = ws.nq;
  const bool ideal = model.solver.initial_state == InitialStateRule::ideal;
  const int rows = ws.m + (ideal ? 2 * ws.nc : 0);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(ws.ny);
  for (int b = 0; b < ws.nb; ++b) {
    const Body& body = model.bodies[b];
    const BodyBlock& bl = ws.blocks[b];
    kind_of(body).initial(body, y.data() + bl.offset, ideal ? nullptr : y.data() + nq + bl.offset);
  }
  if (rows == 0) return y;
  Eigen::VectorXd phi(rows), phi_dot(rows);
  Eigen::MatrixXd phi_q(rows, nq);

  // Positions: Gauss–Newton with minimum-norm corrections, each body moved as a rigid body (a
  // flexible link keeps its shape: assembly does not strain it). Where rigid motions cannot
  // close the joints (a link clamped at both ends to bodies posed for a bent link), the rest is
  // closed by corrections of every coordinate, which bend the link.
  const bool flexible = std::any_of(model.bodies.begin(), model.bodies.end(),
                                    [](const Body& b) { return b.flexible(); });
  double residual = 0.0, best = std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_y = y;
  for (int it = 0; it < 130; ++it) {
    update_kin(ws, y.data());
    build_constraints(model, ws, 0.0, y.data(), ideal, phi, phi_q, nullptr, nullptr);
    residual = phi.cwiseAbs().maxCoeff();
    if (residual < best) best = residual, best_y = y;
    if (residual < 1e-13) break;
    if (flexible && it < 30) {
      Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(
          phi_q * rigid_motion_basis(model, ws, y.data()));
      move_rigidly(model, ws, y, -cod.solve(phi));
    } else {
      Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(phi_q);
      y.head(nq) -= cod.solve(phi);
    }
  }
  if (!(residual < 1e-10)) {
    // Said at the closest configuration found, and at the element whose equation is worst off.
    update_kin(ws, best_y.data());
    build_constraints(model, ws, 0.0, best_y.data(), ideal, phi, phi_q, nullptr, nullptr);
    throw std::runtime_error(assembly_failure(model, ws, phi, phi_q));
  }

  // Velocities: Φ_q q̇ = −Φ_t by the correction of the initial guess with the least kinetic
  // energy, Δ = L⁻ᵀ (Φ_q L⁻ᵀ)⁺ Φ̇ with M = L Lᵀ (Gauss's principle): from rest (`ideal`) that is the
  // motion a drive started impulsively gives — a body no driver moves stays at rest, and a driver
  // between two otherwise free bodies splits its motion so that their momentum is conserved.
  // Unlike a Euclidean minimum norm it does not depend on the units of the coordinates.
  // With flexible links and rule `ideal` (the motion of the mechanism with ideal joints and
  // undeformed links) the correction is a rigid motion of each body if one satisfies the
  // constraints, q̇ = T u (a link starts without strain rates, which would ring through the run:
  // a free beam's least-kinetic-energy nodal velocities rang a steel rod at 2.7 GPa), with M and
  // Φ_q those of u: TᵀMT, Φ_q T. Under rule `given`, or where no rigid motion satisfies the
  // constraints, the correction is in every coordinate, again with the least kinetic energy: the
  // given velocities change least, and a light link takes the deformation rate (a rigid motion
  // would have stopped a rod held by a clamped flexural pivot, and started it with a blow).
  // Returns the largest velocity residual after the correction relative to the one before.
  // `t` null: every coordinate (T = I), with M's Cholesky factor sparse (M is block diagonal
  // by bodies): dense products and a dense factorisation of M cost nq³, 2.7 s of assembly for a
  // slider-crank beside 400 free bodies.
  auto correct_velocities = [&](const Eigen::MatrixXd* t) {
    update_kin(ws, y.data());
    build_constraints(model, ws, 0.0, y.data(), ideal, phi, phi_q, &phi_dot, nullptr);
    const double before = phi_dot.size() == 0 ? 0.0 : phi_dot.cwiseAbs().maxCoeff();
    if (t) {
      const Eigen::LLT<Eigen::MatrixXd> chol(t->transpose() * mass_matrix(ws) * *t);
      const Eigen::MatrixXd scaled =
          chol.matrixU().solve<Eigen::OnTheRight>(Eigen::MatrixXd(phi_q * *t));
      Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(scaled);
      y.segment(nq, nq) -= *t * chol.matrixU().solve(cod.solve(phi_dot));
    } else {
      // M = L Lᵀ in natural order: Φ_q L⁻ᵀ = (L⁻¹ Φ_qᵀ)ᵀ, and Δ = L⁻ᵀ (Φ_q L⁻ᵀ)⁺ Φ̇.
      const MassFactor chol(sparse_mass_matrix(ws));
      const Eigen::MatrixXd scaled =
          chol.matrixL().solve(Eigen::MatrixXd(phi_q.transpose())).transpose();
      Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(scaled);
      y.segment(nq, nq) -= chol.matrixU().solve(Eigen::VectorXd(cod.solve(phi_dot)));
    }
    update_kin(ws, y.data());
    build_constraints(model, ws, 0.0, y.data(), ideal, phi, phi_q, &phi_dot, nullptr);
    const double after = phi_dot.size() == 0 ? 0.0 : phi_dot.cwiseAbs().maxCoeff();
    return after / std::max(before, 1e-300);
  };
  const Eigen::VectorXd guess = y;
  if (!flexible || !ideal) {
    correct_velocities(nullptr);
  } else if (const Eigen::MatrixXd rigid = rigid_motion_basis(model, ws, y.data());
             !(correct_velocities(&rigid) < 1e-9)) {
    y = guess;
    correct_velocities(nullptr);
  }
  if (!flexible) velocities_on_a_branch(model, ws, ideal, y, phi, phi_q, phi_dot);

  if (const std::string why = constraint_problem(model, ws, 0.0, y, false); !why.empty())
    throw std::runtime_error(why);
  // Bodies that assembly turned or moved far from their given poses: said (after the solver's
  // warnings, which it sets anew). A loop that closes only approximately (a redundant joint's
  // pivot 1e-11 m off) is closed exactly only at isolated positions, and Newton's method goes
  // there: a double parallelogram posed at −30° started at −90°, silently. A pose given in the
  // wrong unit or for another configuration (the slider of a slider-crank given 0.34 m off its
  // guide's reach) was moved there without a word.
  Eigen::VectorXd given = Eigen::VectorXd::Zero(ws.ny);
  // The mechanism's size: the diagonal of the box around the given positions and markers (the
  // ground's origin and the ground points of joints among them), at least kAssemblyMoveFloor (a
  // body alone at the origin moved 1e-6 m by its driver was "more than 10 % of 0 m").
  Vec2 lo = Vec2::Zero(), hi = Vec2::Zero();
  auto extend = [&](const Vec2& p) { lo = lo.cwiseMin(p), hi = hi.cwiseMax(p); };
  for (int b = 0; b < ws.nb; ++b) {
    const Body& body = model.bodies[b];
    if (body.flexible()) continue;
    const int o = ws.blocks[b].offset;
    kind_of(body).initial(body, given.data() + o, nullptr);
    const Vec2 at(given[o], given[o + 1]);
    const double phi = body.type == BodyType::rigid ? given[o + 2] : 0.0;
    extend(at);
    for (const Marker& m : body.markers) extend(at + rotation(phi) * m.s_P_B);
  }
  for (const Joint& j : model.joints)
    for (const PointRef* p : {&j.a, &j.b})
      if (p->body == kGround) extend(p->s);
  const double size = std::max((hi - lo).norm(), kAssemblyMoveFloor);
  std::vector<std::pair<double, int>> turned, moved;  // (amount, body) beyond the warnings'
  for (int b = 0; b < ws.nb; ++b) {
    const Body& body = model.bodies[b];
    if (body.flexible()) continue;
    const int o = ws.blocks[b].offset;
    if (body.type == BodyType::rigid && std::abs(y[o + 2] - given[o + 2]) > kAssemblyTurnWarning)
      turned.push_back({std::abs(y[o + 2] - given[o + 2]), b});
    if (const double d = (y.segment<2>(o) - given.segment<2>(o)).norm(); d > kAssemblyMoveWarning * size)
      moved.push_back({d, b});
  }
  // "body 'a': assembly <verb> it A<unit> from its given <what> (and body 'b' B, ...<unit>)":
  // the body changed most first (model order on ties).
  auto bodies = [&](std::vector<std::pair<double, int>> list, const char* verb, double scale,
                    const char* unit, const char* what) {
    std::stable_sort(list.begin(), list.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    std::ostringstream s;
    s.precision(3);
    s << "body '" << model.bodies[list[0].second].name << "': assembly " << verb << " it "
      << list[0].first * scale << unit << " from its given " << what;
    for (size_t i = 1; i < list.size(); ++i)
      s << (i == 1 ? " (and body '" : ", body '") << model.bodies[list[i].second].name << "' "
        << list[i].first * scale << (i + 1 == list.size() ? std::string(unit) + ")" : "");
    return s.str();
  };
  if (!turned.empty())
    ws.warnings.push_back(bodies(turned, "turned", 180.0 / M_PI, " degrees", "angle") +
                          " to satisfy every joint and driver; check the markers, the poses and "
                          "any driver's initial value (a redundant joint whose markers close the "
                          "loop only approximately is satisfied only at isolated positions)");
  if (!moved.empty()) {
    std::ostringstream s;
    s.precision(3);
    s << bodies(moved, "moved", 1.0, " m", "position") << ", more than "
      << 100 * kAssemblyMoveWarning << " % of the mechanism's size (" << size
      << " m across its given positions and markers), to satisfy every joint and driver; check "
      << "the poses and their units";
    ws.warnings.push_back(s.str());
  }
  // A journal placed through its bearing's wall by its own radius or more (a pose given for
  // another clearance or geometry, initial_state: given): the contact's normal points the wrong
  // way there, and the run failed at once saying "journal driven through its bearing ... the
  // contact is too soft", as if the load were to blame. Refused as a continued state is.
  for (int c = 0; c < ws.nc; ++c) {
    const Joint& j = model.joints[ws.clearance_joints[c]];
    double delta = 0.0, delta_dot = 0.0;
    clearance_gap(model, ws, c, y.data(), delta, delta_dot);
    if (delta >= j.clearance->journal_radius) {
      std::ostringstream s;
      s.precision(6);
      s << "joint '" << j.name << "': at the start the journal lies " << delta
        << " m into its bearing's wall, as deep as its own radius " << j.clearance->journal_radius
        << " m or deeper (clearance " << j.clearance->clearance
        << " m); check the poses of the bodies it joins";
      throw std::runtime_error(s.str());
    }
  }
  return y;
}

}  // namespace lash
