#pragma once
/// @file run_folder.hpp
/// A run folder written by `lash run`, read back for `lash report` and `lash analyze`: its
/// summary.json (status, integrator statistics, the model it ran), the time series
/// (timeseries.csv; a run with `--format hdf5` is not read yet), events.csv and
/// final_state.json, each checked against the others before anything is analysed. A damaged or
/// inconsistent folder is refused with a message naming the file (and line and column where
/// there is one); docs/analysis.md lists the checks.
#include <stdexcept>
#include <string>

#include "study/run_analysis.hpp"

namespace lash {

/// A run folder that cannot be read as the run left it: a file missing, cut, edited or not of
/// this run. The message names the file. `lash` exits with 2 (bad input).
class RunFolderError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Reads and checks the run in `dir` against `model` (loaded from its model_resolved.yaml):
/// summary.json must be valid JSON, record exactly the text of model_resolved.yaml and a run
/// that completed or stopped on a numerical failure; the time series must have the header and
/// the number of rows the summary lists, each row whole and numeric with increasing times;
/// events.csv as many well-formed rows of the model's clearance joints as the summary counts
/// events; final_state.json must read back into the model's layout. The header, the row count
/// and every event are checked here; each row as RecordedRun::next_row reads it. Throws
/// RunFolderError naming the file, IoError when a file cannot be read. A run written as HDF5
/// (timeseries.h5) is checked up to its time series, which is not read yet: `next_row` is then
/// empty and the caller runs the model again.
RecordedRun read_run_folder(const std::string& dir, const Model& model);

}  // namespace lash
