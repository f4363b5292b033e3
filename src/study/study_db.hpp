#pragma once
/// @file study_db.hpp
/// A study's results in SQLite (study.db in the study's folder; schema in docs/studies.md):
/// one row per finished run with its parameters, status, timing and verdict, its metrics, its
/// section points and kept series. Each run is written in one transaction (synchronous=FULL),
/// so a crash or kill -9 loses no finished run and leaves no half one.
#include <atomic>
#include <functional>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "study/sweep.hpp"

struct sqlite3;

namespace lash {

class StudyDb {
 public:
  /// Opens `path`, creating the schema for `spec` when the file is new. An existing database of
  /// another study (another study file or model text) is refused with std::invalid_argument.
  StudyDb(const std::string& path, const StudySpec& spec, int total_runs);
  StudyDb(const StudyDb&) = delete;
  StudyDb& operator=(const StudyDb&) = delete;
  ~StudyDb();

  /// Runs already recorded (any status but interrupted, which is never recorded).
  std::set<int> finished() const;
  /// Recorded runs that did not complete (failed or error), from this sweep and earlier ones.
  int failed() const;
  /// Records one run with its parameters, in one transaction. Throws IoError on failure.
  void add(const StudyRun& run, const RunRecord& record, const std::string& worker);
  /// A recorded run's status, message and (continuation studies) final state and driver speed.
  RunRecord recorded(int run) const;

  /// Writes runs.csv (one row per run: parameters, status, verdict, timing and every metric) and
  /// sections.csv (one row per section point) beside the database, each atomically.
  void export_csv(const std::string& folder) const;


 private:
  void exec(const std::string& sql) const;
  sqlite3* db_ = nullptr;
  std::string path_;
  std::vector<std::string> parameters_;
};

/// What a study database holds, for reports: every recorded run with its parameters (as text
/// and number) and metrics, and the section points of one channel.
struct StudyTable {
  std::string name;                       ///< the study's name
  std::vector<std::string> parameters;    ///< parameter names (column order)
  int total_runs = 0;
  struct Row {
    int run = 0;
    std::vector<std::string> values;
    std::vector<double> numbers;          ///< NaN for text values
    std::string status, message, verdict;
    double wall_seconds = 0.0;
    std::vector<std::pair<std::string, double>> metrics;
  };
  std::vector<Row> rows;                  ///< by run index
  std::vector<std::string> section_channels;
  /// points[channel] = (run, value) pairs, after the transient.
  std::vector<std::vector<std::pair<int, double>>> points;
};
/// Reads a study database (read-only). Throws IoError when it cannot be read.
StudyTable read_study(const std::string& db_path);

}  // namespace lash

namespace lash {

/// A study's output folder, locked for one sweep: its database opened (created, or with
/// `resume` reopened and checked to be this study's) and the runs still to do.
class StudyFolder {
 public:
  /// Throws std::invalid_argument when the folder holds a study and `resume` is false, holds
  /// another study, or is in use by another lash; IoError when it cannot be created or written.
  StudyFolder(const std::string& folder, const StudySpec& spec, bool resume);
  const std::vector<StudyRun>& runs() const { return runs_; }
  const std::vector<StudyRun>& todo() const { return todo_; }
  int already() const { return static_cast<int>(runs_.size() - todo_.size()); }
  StudyDb& db() { return *db_; }
  const std::string& folder() const { return folder_; }

 private:
  std::string folder_;
  std::shared_ptr<void> lock_;
  std::unique_ptr<StudyDb> db_;
  std::vector<StudyRun> runs_, todo_;
};

/// Runs `folder`'s remaining runs on `jobs` threads (0: every core), each finished run written to
/// the database by the calling thread and then passed to `on_record` (for a progress line).
/// `interrupt` (a signal number once set) stops the runs within one step; they are not
/// recorded. Returns "" or the database error that stopped the study (the runs recorded before
/// it stay; a failed CSV export is added to it). Writes runs.csv and sections.csv at the end.
std::string run_study_threads(StudyFolder& folder, const StudySpec& spec, int jobs,
                              const std::atomic<int>* interrupt,
                              const std::function<void(const RunRecord&)>& on_record);

}  // namespace lash
