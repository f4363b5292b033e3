#pragma once
/// @file sweep.hpp
/// `lash sweep STUDY -o DIR`: every run of a study file on all local cores (threads), or on the
/// processes of an MPI job (rank 0 hands out runs and writes the database, the others run them),
/// results in DIR/study.db with runs.csv and sections.csv beside it; `--resume` runs only what
/// the database does not hold yet. `lash report DIR` of such a folder: study_report.html.
///
/// Only the program `lash-mpi` (built beside `lash` when Open MPI is found) links MPI, whose
/// libraries cost every start of a program about 7 ms (bench/README.md, "Whole process"): `lash`
/// started by an MPI launcher with more than one process executes `lash-mpi` with the same
/// arguments, so `mpirun -n N lash sweep ...` works with either name.
#include <CLI/CLI.hpp>
#include <atomic>
#include <functional>
#include <string>

namespace lash::cli {

class SweepCommand {
 public:
  /// `argv`: the program's arguments, for handing the command to `lash-mpi` under mpirun.
  SweepCommand(CLI::App& app, char** argv);
  SweepCommand(const SweepCommand&) = delete;
  SweepCommand& operator=(const SweepCommand&) = delete;
  bool parsed() const { return sub_->parsed(); }
  /// Runs the study. `interrupt` holds a signal number once one arrived (handlers installed by
  /// `install_handlers`, called once the study is checked). Returns the exit code.
  int run(std::atomic<int>& interrupt, const std::function<void()>& install_handlers) const;

 private:
  CLI::App* sub_;
  char** argv_;
  std::string study_;
  std::string out_;
  int jobs_ = 0;
  bool resume_ = false;
  bool quiet_ = false;
};

/// Writes `folder`/study_report.html from `folder`/study.db: the bifurcation diagram of each kept
/// section channel over the first numeric parameter, metric-versus-parameter plots, the failed
/// runs with their errors. Returns the path written.
std::string write_study_report(const std::string& folder);

/// True if `path` holds a YAML map with a `study` or a `model` key, as a study file (`study:`
/// may be left out) and never a model file (false for anything else, a model, a file
/// that does not parse or is not a regular file of at most kMaxModelFileBytes: the model loader
/// then reports it).
bool is_study_file(const std::string& path);

/// `lash check` of a study file: every problem as `lash sweep` finds them before it runs (exit
/// 2), or a line with its runs and models (exit 0).
int check_study(const std::string& path);

}  // namespace lash::cli
