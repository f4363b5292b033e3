#pragma once
/// @file report.hpp
/// Runs a model with the analyses of a study and gathers what the report and the figures need
/// (docs/report-data.md): decimated channels, the ideal twin, journal orbits, contact modes,
/// stroboscopic Poincaré sections, spectra, phase portraits, the largest Lyapunov exponent and
/// a periodic / quasi-periodic / chaotic verdict.
#include <nlohmann/json.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "core/simulate.hpp"
#include "io/model_loader.hpp"

namespace lash {

class ResultsWriter;

struct ReportOptions {
  bool ideal_twin = true;           ///< run the model with every clearance joint ideal
  bool lyapunov = true;             ///< estimate the largest Lyapunov exponent
  double lyapunov_d0 = 0.0;         ///< separation, m (0: 2e-4 × the smallest clearance, ≤ 1e-7)
  std::string poincare_driver;      ///< driver whose period sets the sections ("" = first rotary)
  /// Event-based sections instead of stroboscopic ones: "<body>.<x|y|phi|vx|vy|omega>=V[,down]".
  std::vector<std::string> section_planes;
  int discard_periods = 1;          ///< transient periods skipped by sections, spectra, Lyapunov
  std::vector<std::string> fft_channels;   ///< default: translational bodies' ax, each Fn
  std::vector<std::pair<std::string, std::string>> phase;  ///< default: each joint's (ex, ey)
  double continuous_contact_time = 0.0;    ///< 0: 10% of the period, or 1 ms without one
  size_t display_points = 800;      ///< buckets for decimated series (2 points each)
  size_t frames = 400;              ///< animation frames
  double stats_t0 = -1e300, stats_t1 = 1e300;  ///< statistics window (s)
  /// Statistics only where the crank angle (deg, of the period driver) lies in [a0, a1],
  /// wrapping through 360 when a0 > a1; NaN: everywhere.
  double stats_angle0 = std::nan(""), stats_angle1 = std::nan("");
};

struct ReportRun {
  RunResult result;                 ///< the main run
  nlohmann::json data;              ///< report_data.json
};

/// Runs `loaded` with the analyses; when `writer` is given the main run also streams the usual
/// result files through it. Throws std::runtime_error if no initial state exists.
ReportRun run_with_analysis(const LoadedModel& loaded, const ReportOptions& options,
                            ResultsWriter* writer, Observer* progress = nullptr);

/// Writes report_data.json, report.html (self-contained) and, when Debian's matplotlib is
/// present, figures/*.png|svg into `folder`. Returns lines describing what was written or why a
/// part was skipped.
std::vector<std::string> write_report(const nlohmann::json& data, const std::string& folder);

}  // namespace lash
