#pragma once
/// @file tune_absorber.hpp
/// `lash tune-absorber`: Den Hartog's tuned-mass absorber (analysis/absorber.hpp) from the command
/// line. Needs no model file.
#include <CLI/CLI.hpp>
#include <iosfwd>
#include <string>

namespace lash::cli {

/// The `tune-absorber` subcommand and its option values. Construct it before `app.parse()` and
/// keep it alive until run() returns (CLI11 writes the values into it); it cannot be copied.
class TuneAbsorberCommand {
 public:
  /// Adds the subcommand to `app`.
  explicit TuneAbsorberCommand(CLI::App& app);
  TuneAbsorberCommand(const TuneAbsorberCommand&) = delete;
  TuneAbsorberCommand& operator=(const TuneAbsorberCommand&) = delete;

  /// True when the command line chose `tune-absorber`.
  bool parsed() const { return sub_->parsed(); }

  /// Prints the design (text, or JSON with --json) to `out`. Returns the exit code: 0, or 2 with
  /// a message naming the offending option on `err` for bad input.
  int run(std::ostream& out, std::ostream& err) const;

 private:
  CLI::App* sub_;
  double frequency_hz_ = 0.0;
  double mass_ratio_ = 0.0;
  double primary_mass_ = 0.0, absorber_mass_ = 0.0;
  CLI::Option* primary_mass_option_ = nullptr;
  CLI::Option* absorber_mass_option_ = nullptr;
  std::string attach_ = "link.P";
  bool json_ = false;
};

}  // namespace lash::cli
