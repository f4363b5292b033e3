#pragma once
/// @file report.hpp
/// The report of a run with its analyses (study/run_analysis.hpp): report_data.json
/// (docs/report-data.md), the self-contained report.html and the figures drawn by
/// tools/lash_figures.py. Nothing here runs a simulation.
#include <atomic>
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "core/model.hpp"
#include "study/run_analysis.hpp"

namespace lash {

/// The report_data.json document of `analysis`, a run of `model` (docs/report-data.md): the
/// model, the run's status and integrator statistics, the channels' units and descriptions,
/// and every analysis; series, frames, orbits, spectra and the Lyapunov history rounded to six
/// significant digits (section times in full: at six digits k·T was off by up to 1.8e-7 s).
nlohmann::json report_data(const Model& model, const RunAnalysis& analysis);

/// Writes report_data.json, report.html (self-contained) and, when Debian's matplotlib is
/// present, figures/*.png|svg into `folder` (an earlier report's figures/ is replaced; a figures/
/// folder lash did not write is left alone: std::invalid_argument). Returns lines describing
/// what was written or why a part was skipped; throws IoError when a file cannot be written.
/// `interrupt` (a signal's number once one arrived) stops the figures' program early.
std::vector<std::string> write_report(const nlohmann::json& data, const std::string& folder,
                                      const std::atomic<int>* interrupt = nullptr);

/// Removes what write_report wrote into `folder` (report_data.json, report.html, figures.log and
/// a figures/ folder carrying lash's mark): a report cut short by a signal is not left beside the
/// results it would misdescribe.
void remove_report(const std::string& folder);

}  // namespace lash
