// Flexible link: a planar Euler–Bernoulli beam in the absolute nodal coordinate formulation
// (core/beam.hpp; docs/architecture.md, "Flexible links"). Coordinates: [rx, ry, r'x, r'y] per
// node from end A to end B; mass block: the constant, banded ∫ρA SᵀS dx; its own forces: the
// elastic and Kelvin–Voigt damping forces of each element and gravity ∫ρA Sᵀg dx. Its pose
// channels (x, y, phi, …) are those of the chord from A to B.
#include <cmath>

#include "core/elements/registry.hpp"

namespace lash::flexible_link {
namespace {

constexpr int kN = beam::kNodeCoordinates;

int coordinates(const Body& b) { return b.mesh.coordinates(); }

void mass(const Body& b, Eigen::Ref<Eigen::MatrixXd> m) {
  const beam::Mat8 me = beam::element_mass(b.mesh.section, b.mesh.element_length());
  for (int e = 0; e < b.mesh.elements; ++e) m.block<8, 8>(kN * e, kN * e) += me;
}

void initial(const Body& b, double* q, double* qd) {
  const double len = b.mesh.length;
  const Vec2 t(std::cos(b.phi0), std::sin(b.phi0));
  const Eigen::VectorXd q0 = beam::straight_coordinates(b.mesh, b.r0 - 0.5 * len * t, b.phi0);
  for (int i = 0; i < q0.size(); ++i) q[i] = q0[i];
  if (!qd) return;
  // Rigid motion: ṙ = v0 + ω perp(r − r0), ṙ' = ω perp(r').
  for (int n = 0; n < b.mesh.nodes(); ++n) {
    const Vec2 r(q[kN * n], q[kN * n + 1]);
    const Vec2 v = b.v0 + b.omega0 * perp(Vec2(r - b.r0));
    const Vec2 sd = b.omega0 * perp(t);
    qd[kN * n] = v.x(), qd[kN * n + 1] = v.y(), qd[kN * n + 2] = sd.x(), qd[kN * n + 3] = sd.y();
  }
}

void forces(const Model& model, const Body& b, const BodyKin& k, Workspace& ws) {
  const beam::Mesh& m = b.mesh;
  const double l = m.element_length();
  const beam::Vec8 qg = beam::element_gravity(m.section, l, model.gravity);
  double energy = 0.0, dissipation = 0.0;
  for (int e = 0; e < m.elements; ++e) {
    const Eigen::Map<const beam::Vec8> q(k.q + kN * e), qd(k.qd + kN * e);
    beam::Vec8 f = qg;
    ws.potential -= qg.dot(q);
    beam::element_forces(m.section, l, q, qd, b.structural_damping, f, energy, dissipation);
    ws.g.segment<8>(k.block.offset + kN * e) += f;
  }
  ws.potential += energy;
  ws.dissipated_power += dissipation;
}

void channels(const Body& b, const BodyKin& k, const double* qdd, ChannelSink& s) {
  const beam::Mesh& m = b.mesh;
  const int last = kN * m.elements;
  s.add("x", "m", "x of the middle of the chord from end A to end B", k.r.x());
  s.add("y", "m", "y of the middle of the chord", k.r.y());
  s.add("phi", "rad", "angle of the chord A→B, in (−π, π]", k.phi);
  s.add("vx", "m/s", "x velocity of the middle of the chord", k.v.x());
  s.add("vy", "m/s", "y velocity of the middle of the chord", k.v.y());
  s.add("omega", "rad/s", "angular velocity of the chord", k.omega);
  s.add("ax", "m/s²", "x acceleration of the middle of the chord", 0.5 * (qdd[0] + qdd[last]));
  s.add("ay", "m/s²", "y acceleration of the middle of the chord",
        0.5 * (qdd[1] + qdd[last + 1]));
  // Deformation and stresses (not computed while only the channels' names are collected).
  Eigen::VectorXd q;
  beam::Resultants mid, top;
  double w_mid = 0.0, w_max = 0.0, at = 0.0, energy = 0.0;
  if (!s.describing()) {
    q = Eigen::Map<const Eigen::VectorXd>(k.q, m.coordinates());
    w_mid = beam::chord_deflection(m, q, 0.5 * m.length);
    for (int n = 1; n < m.nodes() - 1; ++n) {
      const double w = beam::chord_deflection(m, q, n * m.element_length());
      if (std::abs(w) > std::abs(w_max)) w_max = w;
    }
    if (std::abs(w_mid) > std::abs(w_max)) w_max = w_mid;
    mid = beam::resultants(m, q, 0.5 * m.length);
    top = beam::largest_stress(m, q, &at);
    energy = beam::strain_energy(m, q);
  }
  s.add("deflection", "m", "deflection at mid-length from the chord (+ to its left)", w_mid);
  s.add("deflection_max", "m", "largest deflection from the chord, at mid-length or a node (signed)",
        w_max);
  s.add("N", "N", "axial force at mid-length (> 0: tension)", mid.axial_force);
  s.add("M", "N·m", "bending moment at mid-length", mid.bending_moment);
  s.add("stress_max", "Pa", "largest normal stress |N/A| + |M|c/I along the link", top.stress);
  s.add("stress_max_at", "m", "where it acts, from end A", at);
  s.add("strain_energy", "J", "elastic energy", energy);
}

}  // namespace

const BodyKind kKind{"flexible", coordinates, mass, initial, forces, channels};

}  // namespace lash::flexible_link
