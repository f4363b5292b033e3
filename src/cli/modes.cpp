// `lash modes MODEL`: the natural frequencies of each flexible link of a model, from its mesh,
// beside the Euler–Bernoulli closed forms for the same supports, so that a user can see that the
// mesh resolves the modes that matter before running; then those of the whole mechanism,
// linearised at its initial configuration (study/linear_modes.hpp).
#include "cli/modes.hpp"

#include <array>
#include <cmath>
#include <iomanip>

#include "study/linear_modes.hpp"

namespace lash::cli {
namespace {

// Roots β_k L of the Euler–Bernoulli frequency equations (ω_k = (β_k L)² √(EI/(ρA L⁴))):
// clamped–free cos βL cosh βL = −1, free–free cos βL cosh βL = 1 (elastic modes). Blevins,
// Formulas for Natural Frequency and Mode Shape (1979), Table 8-1.
constexpr std::array<double, 5> kClampedFree{1.87510407, 4.69409113, 7.85475744, 10.99554073,
                                             14.13716839};
constexpr std::array<double, 5> kFreeFree{4.73004074, 7.85320462, 10.99560784, 14.13716549,
                                          17.27875966};

void table(const beam::Mesh& m, beam::Support support, int count, std::ostream& out) {
  const beam::Section& s = m.section;
  const double bending = std::sqrt(s.youngs_modulus * s.inertia /
                                   (s.density * s.area * std::pow(m.length, 4)));
  const double axial = std::sqrt(s.youngs_modulus / s.density) / m.length;
  const bool clamped = support == beam::Support::clamped;
  out << (clamped ? "  end A clamped, end B free:\n" : "  both ends free (rigid-body modes left out):\n")
      << "    mode  kind      f mesh (Hz)    f closed form (Hz)   difference\n";
  int nb = 0, na = 0, shown = 0;
  const std::vector<beam::Mode> all = beam::modes(m, support);
  // A free beam's three rigid-body modes come first (beam.hpp), at round-off frequencies.
  for (size_t i = clamped ? 0 : 3; i < all.size() && shown < count; ++i) {
    const beam::Mode& md = all[i];
    const bool is_bending = md.transverse > 0.5;
    double exact = NAN;
    if (is_bending) {
      const auto& roots = clamped ? kClampedFree : kFreeFree;
      if (nb < static_cast<int>(roots.size())) exact = roots[nb] * roots[nb] * bending;
      ++nb;
    } else {
      ++na;  // axial: clamped–free (2k − 1)π/2 √(E/ρ)/L, free–free kπ √(E/ρ)/L
      exact = (clamped ? (2 * na - 1) * M_PI / 2 : na * M_PI) * axial;
    }
    out << "    " << std::setw(4) << ++shown << "  " << std::left << std::setw(8)
        << (is_bending ? "bending" : "axial") << std::right << std::setw(13) << std::setprecision(6)
        << md.omega / (2 * M_PI) << "  " << std::setw(19);
    if (std::isnan(exact))
      out << "-" << "\n";
    else
      out << exact / (2 * M_PI) << "  " << std::showpos << std::setw(10) << std::setprecision(2)
          << std::scientific << (md.omega - exact) / exact << std::noshowpos << std::defaultfloat
          << "\n";
  }
}

}  // namespace

int print_modes(const Model& model, int count, bool at_equilibrium, std::ostream& out) {
  int links = 0;
  for (const Body& b : model.bodies) {
    if (!b.flexible()) continue;
    ++links;
    const beam::Mesh& m = b.mesh;
    const beam::Section& s = m.section;
    out << "body '" << b.name << "': flexible link, " << m.length << " m, " << m.elements
        << " elements; EA = " << s.youngs_modulus * s.area << " N, EI = "
        << s.youngs_modulus * s.inertia << " N·m², ρA = " << s.density * s.area << " kg/m, mass "
        << b.mass << " kg\n";
    table(m, beam::Support::clamped, count, out);
    table(m, beam::Support::free, count, out);
    out << "  (a link pinned at both ends lies between these; in the mechanism its joints and the "
           "bodies they hold shift them)\n";
  }
  if (links == 0) out << "no flexible links in this model (give a body a 'flexible:' map)\n";
  out.flush();  // the mechanism's modes take a while on a fine mesh: the tables are out first
  const LinearModes lm = linear_modes(model, at_equilibrium);
  if (lm.equilibrium) {
    const Equilibrium& e = *lm.equilibrium;
    out << "the static equilibrium nearest the initial configuration (gravity and loads acting, "
           "drivers holding their coordinates): " << e.newton_steps << " Newton step"
        << (e.newton_steps == 1 ? "" : "s") << ", accelerations left " << std::setprecision(3)
        << e.residual;
    if (e.newton_steps > 0 && e.largest_move > 0)
      out << ", largest move " << e.largest_move << " m (" << e.largest_move_coordinate << ")";
    if (e.newton_steps > 0 && e.largest_turn > 1e-12)  // (a turn of 1e-80 rad said nothing)
      out << ", largest turn " << e.largest_turn << " rad (" << e.largest_turn_coordinate << ")";
    out << std::setprecision(6) << "\n";
  }
  out << "the mechanism, linearised at its "
      << (lm.equilibrium ? "static equilibrium" : "initial configuration")
      << " (clearance joints ideal, drivers holding their coordinates, at rest): " << lm.dof
      << " degree" << (lm.dof == 1 ? "" : "s") << " of freedom\n";
  if (!lm.modes.empty()) out << "    mode    f (Hz)        damping ratio\n";
  int shown = 0;
  for (const LinearMode& md : lm.modes) {
    if (shown >= count) break;
    out << "    " << std::setw(4) << ++shown << "  " << std::setw(12) << std::setprecision(6)
        << md.frequency << "  " << std::setw(12) << std::setprecision(3) << md.damping_ratio << "\n";
  }
  if (lm.modes.size() > static_cast<size_t>(count))
    out << "    (" << lm.modes.size() - count << " more; --count N shows more)\n";
  if (!lm.real_rates.empty()) {
    out << "  " << lm.real_rates.size() << " real eigenvalue" << (lm.real_rates.size() == 1 ? "" : "s")
        << " (1/s: a free or overdamped direction near 0, an unstable one > 0):";
    for (double r : lm.real_rates) out << " " << std::setprecision(4) << r;
    out << "\n";
  }
  return links;
}

}  // namespace lash::cli
