// floor_flores: the hand-written floor (bench/floor_slider_crank.hpp) as a whole program that
// writes its CSV, the process `bench_whole` times against `lash run`. Built from
// floor_slider_crank.cpp and the engine's DOPRI5 (src/core/dopri5.cpp) only, so it loads no
// library besides the C and C++ run-time: the smallest process that solves this mechanism.
//
//   floor_flores OUT.csv a ω θ0 L m_r I_r m_s gx gy c R_J K cₑ v_min rtol atol end_time dt
//
// The 18 parameters are FloorParams in declaration order (SI); bench_whole reads them from the
// Lash model (floor_params_from_model), so the two always solve the same problem. The CSV has
// 12 columns besides time, each the same quantity as the Lash channel of the same name, with
// the same formatting (%.9g via lash::format_g9, the CSV writer's), in large buffered blocks.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "bench/floor_slider_crank.hpp"
#include "io/number_format.hpp"

namespace {

using lash::bench::FloorContact;
using lash::bench::FloorParams;

/// The CSV header: Lash's names for the same quantities.
constexpr const char* kHeader =
    "time,rod.phi,rod.omega,rod.alpha,slider.x,slider.vx,slider.ax,rod_slider.ex,rod_slider.ey,"
    "rod_slider.e,rod_slider.delta,rod_slider.delta_dot,rod_slider.Fn\n";

class CsvWriter : public lash::bench::FloorObserver {
 public:
  CsvWriter(const FloorParams& p, std::FILE* f) : p_(p), f_(f) { buf_.reserve(kBlock + 512); }
  void output(double t, const double* y) override {}
  void output(double t, const double* y, const FloorContact& c) override {
    double dy[4];
    lash::bench::floor_rhs(p_, c, t, y, dy);
    const double a = p_.crank_length, L = p_.rod_length;
    const double th = p_.crank_angle0 + p_.crank_speed * t;
    const double ex = a * std::cos(th) + L * std::cos(y[0]) - y[1];
    const double ey = a * std::sin(th) + L * std::sin(y[0]);
    double delta, delta_dot;
    lash::bench::floor_gap(p_, t, y, delta, delta_dot);
    // F_N as floor_rhs computes it (the contact force's magnitude, 0 in free flight).
    double fn = 0.0;
    if (delta > 0.0) {
      const double k = 3.0 * (1.0 - p_.restitution * p_.restitution) / 4.0;
      const double v = std::max(c.in_contact ? c.impact_velocity : delta_dot,
                                p_.min_impact_velocity);
      fn = std::max(0.0, p_.stiffness * delta * std::sqrt(delta) * (1.0 + k * delta_dot / v));
    }
    const double row[] = {t,  y[0], y[2], dy[2], y[1], y[3], dy[3], ex, ey,
                          std::sqrt(ex * ex + ey * ey), delta, delta_dot, fn};
    for (size_t i = 0; i < sizeof row / sizeof row[0]; ++i) {
      if (i) buf_.push_back(',');
      char s[lash::kG9MaxChars];
      buf_.insert(buf_.end(), s, lash::format_g9(row[i], s));
    }
    buf_.push_back('\n');
    if (buf_.size() >= kBlock) flush();
  }
  bool flush() {
    const bool ok = std::fwrite(buf_.data(), 1, buf_.size(), f_) == buf_.size();
    buf_.clear();
    return ok;
  }

 private:
  static constexpr size_t kBlock = 1 << 16;
  const FloorParams& p_;
  std::FILE* f_;
  std::vector<char> buf_;
};

}  // namespace

int main(int argc, char** argv) {
  constexpr int kParams = 18;
  if (argc != 2 + kParams) {
    std::fprintf(stderr, "usage: floor_flores OUT.csv <%d FloorParams values, SI>\n", kParams);
    return 2;
  }
  FloorParams p;
  double* fields[kParams] = {&p.crank_length, &p.crank_speed, &p.crank_angle0, &p.rod_length,
                             &p.rod_mass, &p.rod_inertia, &p.slider_mass, &p.gx, &p.gy,
                             &p.clearance, &p.journal_radius, &p.stiffness, &p.restitution,
                             &p.min_impact_velocity, &p.rtol, &p.atol, &p.end_time,
                             &p.output_interval};
  for (int i = 0; i < kParams; ++i) *fields[i] = std::strtod(argv[2 + i], nullptr);
  std::FILE* f = std::fopen(argv[1], "w");
  if (!f) {
    std::perror(argv[1]);
    return 3;
  }
  std::fputs(kHeader, f);
  CsvWriter w(p, f);
  const auto r = lash::bench::simulate_floor(p, w);
  const bool written = w.flush() && std::fclose(f) == 0;
  if (!r.ok) std::fprintf(stderr, "floor_flores: %s\n", r.message.c_str());
  if (!written) std::fprintf(stderr, "floor_flores: %s: write failed\n", argv[1]);
  return !r.ok ? 1 : written ? 0 : 3;
}
