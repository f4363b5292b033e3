// `lash sweep` (sweep.hpp): local threads or MPI ranks over a study's runs, one database.
#include "cli/sweep.hpp"

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <random>
#include <set>
#include <thread>
#include <iostream>

#include "io/diagnostics.hpp"
#include "io/files.hpp"
#include "study/study_db.hpp"
#include "study/sweep.hpp"
#include <yaml-cpp/yaml.h>

#ifdef LASH_MPI
#include <mpi.h>
#endif

namespace lash::cli {
namespace {

constexpr int kExitOk = 0, kExitFailed = 1, kExitBadInput = 2, kExitIo = 3, kExitInterrupted = 130;

std::string duration_text(double s) {
  // Rounded to the unit shown last before it is split (3 h 59.6 min is 4 h 0 min, not 3 h 60 min).
  if (s < 90) return fmt::format("{:.0f} s", s);
  if (s < 5400) {
    const long seconds = std::lround(s);
    return fmt::format("{} min {} s", seconds / 60, seconds % 60);
  }
  const long minutes = std::lround(s / 60);
  return fmt::format("{} h {} min", minutes / 60, minutes % 60);
}

/// The progress line: done / failed / remaining and an estimated finish.
class Progress {
 public:
  /// `already` runs recorded before this session, `already_failed` of them not completed.
  Progress(int total, int already, int already_failed, bool show)
      : total_(total), done_(already), failed_(already_failed), show_(show),
        tty_(isatty(STDERR_FILENO)) {}
  void add(const RunRecord& r) {
    ++done_;
    ++this_session_;
    if (r.status != "completed") ++failed_;
    if (done_ < total_) print(false);  // the last line is print(true)'s
  }
  void print(bool last) {
    if (!show_) return;
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    // Without a terminal: a line per 10 % or per 30 s, not one per run.
    if (!tty_ && !last && done_ < total_ && done_ < next_mark_ &&
        now - last_ < std::chrono::seconds(30))
      return;
    last_ = now;
    next_mark_ = done_ + std::max(1, (total_ + 9) / 10);
    const int left = total_ - done_;
    std::string eta = "";
    if (this_session_ > 0 && left > 0)
      eta = ", about " + duration_text(elapsed / this_session_ * left) + " left";
    fmt::print(stderr, "{}sweep: {}/{} done ({} failed), {} to go{}{}", tty_ ? "\r" : "", done_,
               total_, failed_, left, eta, tty_ && !last ? "    " : "\n");
  }

 private:
  int total_, done_, failed_, this_session_ = 0, next_mark_ = 0;
  bool show_, tty_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_{};
};

/// Prints a model error of the study (every diagnostic) and returns exit 2.
int study_error(const ModelError& e) {
  for (const auto& d : e.diagnostics()) std::cerr << d.str() << "\n";
  std::cerr << e.diagnostics().size() << " problem" << (e.diagnostics().size() == 1 ? "" : "s")
            << " found; nothing was run.\n";
  return kExitBadInput;
}

}  // namespace

bool is_study_file(const std::string& path) {
  try {
    // Read as the model loader reads: a FIFO or a device is not opened, a huge file not read
    // (YAML::LoadFile hung on a FIFO and read /dev/zero without end).
    const YAML::Node root = YAML::Load(read_input_file(path, kMaxModelFileBytes));
    // `study:` may be left out (lash sweep names the study "study"); a model has no `model:`,
    // but a model with a stray `model:` key is still a model (its bodies say so): checked as
    // one, it gets the one problem that key is, not one per model section "unknown in a study".
    if (!root.IsMap()) return false;
    if (root["study"]) return true;
    return root["model"] && !root["bodies"] && !root["joints"];
  } catch (const std::exception&) {
    return false;
  }
}

int check_study(const std::string& path) {
  try {
    const StudySpec spec = load_study_file(path);
    const auto runs = study_runs(spec);
    // Every run's model and transient, as the sweep would start it (a few milliseconds each).
    // Past kCheckedRuns: one run drawn at random among those of every level of every listed
    // parameter, and runs drawn at random up to kCheckedRuns (a fixed seed), in index order; at
    // most kCheckSeconds in all. (Every level's first run took, for a parameter of 5000 levels
    // crossed with one of 4, the 5000 runs of the other's first level only.)
    constexpr std::size_t kCheckedRuns = 2000;
    constexpr double kCheckSeconds = 30.0;
    std::vector<std::size_t> pick;
    if (runs.size() <= kCheckedRuns) {
      for (std::size_t i = 0; i < runs.size(); ++i) pick.push_back(i);
    } else {
      std::mt19937_64 draw(20261127u);
      // Reservoir sampling: each level keeps its k-th run with probability 1/k.
      std::map<std::pair<std::size_t, std::string>, std::pair<std::size_t, std::size_t>> level;
      for (std::size_t i = 0; i < runs.size(); ++i)
        for (std::size_t j = 0; j < spec.parameters.size(); ++j) {
          if (spec.parameters[j].sampled) continue;
          auto& [seen, run] = level[{j, runs[i].values[j]}];
          if (draw() % ++seen == 0) run = i;
        }
      std::set<std::size_t> chosen;
      for (const auto& [key, pick_one] : level) chosen.insert(pick_one.second);
      while (chosen.size() < kCheckedRuns) chosen.insert(static_cast<std::size_t>(draw() % runs.size()));
      pick.assign(chosen.begin(), chosen.end());
    }
    const auto start = std::chrono::steady_clock::now();
    std::size_t checked = 0;
    bool timed_out = false;
    std::vector<std::pair<std::string, std::vector<int>>> errors;  // message → runs, in order
    std::set<int> failing;                                         // their indices
    for (std::size_t i : pick) {
      if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > kCheckSeconds) {
        timed_out = true;
        break;
      }
      ++checked;
      std::string e = study_run_error(spec, runs[i]);
      // A continued run starts from the state the run before it ends in.
      if (e.empty() && runs[i].previous >= 0 && failing.count(runs[i].previous))
        e = "it continues run " + std::to_string(runs[i].previous) + ", which would be an error";
      if (e.empty()) continue;
      failing.insert(runs[i].index);
      auto it = std::find_if(errors.begin(), errors.end(), [&](const auto& p) { return p.first == e; });
      if (it == errors.end()) it = errors.insert(errors.end(), {e, {}});
      it->second.push_back(runs[i].index);
    }
    std::size_t bad = 0;
    for (const auto& [e, list] : errors) bad += list.size();
    const std::string of =
        checked == runs.size()
            ? std::to_string(runs.size()) + (runs.size() == 1 ? " run" : " runs")
            : std::to_string(checked) + " of its " + std::to_string(runs.size()) + " runs (" +
                  (timed_out ? "those checked in " + std::to_string(static_cast<int>(kCheckSeconds)) + " s"
                             : std::string("every level, and runs drawn at random")) + ")";
    const std::string models =
        std::to_string(spec.model_texts.size()) + " model" + (spec.model_texts.size() == 1 ? "" : "s");
    if (bad == 0) {
      std::cout << path << ": ok: study '" << spec.name << "', " << of << " of " << models << "\n";
      return kExitOk;
    }
    // What the sweep would record as errors, each message once with its runs.
    constexpr std::size_t kShown = 10;
    for (std::size_t k = 0; k < errors.size() && k < kShown; ++k) {
      const auto& [e, list] = errors[k];
      std::string which;
      for (std::size_t n = 0; n < list.size() && n < 8; ++n) which += (n ? ", " : "") + std::to_string(list[n]);
      if (list.size() > 8) which += ", … (" + std::to_string(list.size()) + " runs)";
      std::cerr << (bad == checked ? "error" : "warning") << ": run" << (list.size() == 1 ? " " : "s ")
                << which << ": " << e << "\n";
    }
    if (errors.size() > kShown)
      std::cerr << "… and " << errors.size() - kShown << " more messages\n";
    if (bad == checked) {
      std::cerr << path << ": every one of " << of << " would be an error; nothing would be computed\n";
      return kExitBadInput;
    }
    std::cout << path << ": ok: study '" << spec.name << "', " << of << " of " << models << "; "
              << bad << " of " << (checked == runs.size() ? "them" : "those checked")
              << " would be recorded as errors (above)\n";
    return kExitOk;
  } catch (const ModelError& e) {
    return study_error(e);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitBadInput;
  }
}

namespace {

/// The end of a sweep: a closing line and the exit code.
int finish(StudyFolder& f, int total, const Progress& progress, int interrupted_by,
           const std::string& write_error, bool quiet) {
  const std::string& out = f.folder();
  const int recorded = static_cast<int>(f.db().finished().size());
  if (!write_error.empty()) {
    std::cerr << "\nerror: " << write_error << "\n" << recorded << " of " << total
              << " runs are recorded in " << out << "/study.db; "
              << (recorded < total ? "`--resume` runs the rest"
                                   : "`--resume` writes runs.csv and sections.csv again")
              << "\n";
    return kExitIo;
  }
  if (interrupted_by != 0) {
    std::cerr << "\ninterrupted by signal " << interrupted_by << ": " << recorded << " of " << total
              << " runs are recorded in " << out << "/study.db; `--resume` runs the rest\n";
    return kExitInterrupted;
  }
  const int failed = f.db().failed();
  if (!quiet)
    fmt::print("study: {} runs in {}/study.db ({} failed); runs.csv and sections.csv beside it\n",
               recorded, out, failed);
  if (recorded > 0 && failed == recorded) {
    // Nothing to analyse: a script running `lash sweep && lash report` stops here. Every run is
    // recorded (a --resume does not run them again), so the cause is the study or its model.
    const RunRecord first = f.db().recorded(*f.db().finished().begin());
    std::cerr << "error: every one of the " << recorded << " runs failed; run "
              << first.index << ": " << first.message << "\n";
    return kExitFailed;
  }
  return kExitOk;
}

bool under_mpi_launcher() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(v)) return true;
  return false;
}

#ifndef LASH_MPI
/// The number of processes the MPI launcher started (Open MPI's or a PMI launcher's variable),
/// 1 when there is none.
int launcher_world_size() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (const char* n = std::getenv(v)) return std::max(1, std::atoi(n));
  return 1;
}

/// `lash-mpi` in this program's folder, or "" if there is none.
std::string mpi_program() {
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return "";
  const auto p = self.parent_path() / "lash-mpi";
  return std::filesystem::is_regular_file(p, ec) ? p.string() : "";
}
#endif

#ifdef LASH_MPI
constexpr int kTagWork = 1, kTagResult = 2;

void send_text(const std::string& s, int to, int tag) {
  MPI_Send(s.data(), static_cast<int>(s.size()), MPI_CHAR, to, tag, MPI_COMM_WORLD);
}

void broadcast_text(std::string& s) {
  long n = static_cast<long>(s.size());
  MPI_Bcast(&n, 1, MPI_LONG, 0, MPI_COMM_WORLD);
  s.resize(n);
  if (n > 0) MPI_Bcast(s.data(), static_cast<int>(n), MPI_CHAR, 0, MPI_COMM_WORLD);
}

/// Rank > 0: runs what rank 0 hands out until told to stop.
int mpi_worker(std::atomic<int>& interrupt) {
  std::string bundle;
  broadcast_text(bundle);
  if (bundle.empty()) return kExitOk;  // rank 0 refused the study; it says why
  const auto j = nlohmann::json::from_msgpack(bundle);
  std::map<std::string, std::string> models = j.at("models");
  const StudySpec spec = load_study_text(j.at("text"), j.at("file"),
                                         [&](const std::string& p) { return models.at(p); });
  const auto runs = study_runs(spec);
  send_text("", 0, kTagResult);  // ready
  for (;;) {
    int index = -1;
    MPI_Recv(&index, 1, MPI_INT, 0, kTagWork, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (index < 0) break;
    const RunRecord rec = run_study_point(spec, runs.at(index), &interrupt);
    nlohmann::json message = to_json(rec);
    message["signal"] = interrupt.load();  // this rank's own stop request, for rank 0
    const std::vector<std::uint8_t> bytes = nlohmann::json::to_msgpack(message);
    send_text(std::string(bytes.begin(), bytes.end()), 0, kTagResult);
  }
  return kExitOk;
}
#endif

}  // namespace

SweepCommand::SweepCommand(CLI::App& app, char** argv) : argv_(argv) {
  sub_ = app.add_subcommand(
      "sweep", "Run every case of a study file (docs/studies.md) on all cores, or on the processes "
               "of an MPI job; results in OUTPUT/study.db (SQLite), runs.csv and sections.csv");
  sub_->add_option("study", study_, "Study file (YAML)")->required();
  sub_->add_option("-o,--output", out_, "Output folder (default: out/<study file name>)")
      ->check([](const std::string& f) {
        return f.empty() ? std::string("is empty: name a folder, or leave out -o for "
                                       "out/<study file name>")
                         : std::string();
      })
      ->transform([](std::string f) { return lash::folder_name(std::move(f)); });
  sub_->add_option("-j,--jobs", jobs_, "Runs at once on this machine (default and 0: every core)")
      ->check(CLI::Range(0, 4096));
  sub_->add_flag("--resume", resume_,
                 "Finish a study in OUTPUT: only the runs its database does not hold are run");
  sub_->add_flag("-q,--quiet", quiet_, "No progress line and no closing summary");
}

int SweepCommand::run(std::atomic<int>& interrupt, const std::function<void()>& install_handlers) const {
  const std::string out =
      out_.empty() ? "out/" + std::filesystem::path(study_).stem().string() : out_;
  [[maybe_unused]] int rank = 0;  // this process's MPI rank (lash-mpi only)
  int size = 1;
  if (under_mpi_launcher()) {
#ifdef LASH_MPI
    MPI_Init(nullptr, nullptr);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
#else
    if (launcher_world_size() > 1) {
      // MPI is linked into lash-mpi only: hand the command over with the same arguments.
      if (const std::string mpi = mpi_program(); !mpi.empty()) {
        execv(mpi.c_str(), argv_);
        std::cerr << "error: cannot start " << mpi << " for an MPI sweep: " << std::strerror(errno)
                  << "\n";
        return kExitIo;
      }
      std::cerr << "error: no lash-mpi beside this lash (it is built when libopenmpi-dev is found "
                   "at build time); run `lash sweep` without mpirun, or rebuild with it\n";
      return kExitBadInput;
    }
#endif
  }
  install_handlers();
#ifdef LASH_MPI
  struct Finalize {
    bool on;
    ~Finalize() {
      if (on) MPI_Finalize();
    }
  } finalize{under_mpi_launcher()};
  if (rank > 0) return mpi_worker(interrupt);
#endif
  std::string bundle;
  StudySpec spec;
  std::unique_ptr<StudyFolder> folder;
  int code = -1;
  try {
    spec = load_study_file(study_);
    if (size > 1 && !spec.continuation.empty()) {  // refused before the folder is made
      std::cerr << "error: " << study_ << ": continuation runs each chain one run after another on "
                   "one machine; run it without mpirun\n";
      code = kExitBadInput;
    } else {
      folder = std::make_unique<StudyFolder>(out, spec, resume_);
    }
  } catch (const ModelError& e) {
    code = study_error(e);
  } catch (const IoError& e) {
    std::cerr << "error: " << e.what() << "\n";
    code = kExitIo;
  } catch (const std::exception& e) {  // the folder, or a structure the reader did not foresee
    std::cerr << "error: " << e.what() << "\n";
    code = kExitBadInput;
  }
  if (code < 0) {
    nlohmann::json models = nlohmann::json::object();
    for (const auto& [p, t] : spec.model_texts) models[p] = t;
    // MessagePack, not JSON text: its strings are bytes, so a path or a model text that is not
    // UTF-8 (Latin-1) reaches the workers as it is (JSON's writer refuses it).
    const std::vector<std::uint8_t> bytes = nlohmann::json::to_msgpack(
        nlohmann::json{{"file", spec.file}, {"text", spec.text}, {"models", models}});
    bundle.assign(bytes.begin(), bytes.end());
  }
#ifdef LASH_MPI
  if (size > 1) broadcast_text(bundle);  // empty: the workers stop
#endif
  if (code >= 0) return code;

  const int total = static_cast<int>(folder->runs().size());
  Progress progress(total, folder->already(), folder->db().failed(), !quiet_);
  if (!quiet_ && folder->already() > 0)
    fmt::print(stderr, "sweep: {} of {} runs already in {}/study.db; running the other {}\n",
               folder->already(), total, out, folder->todo().size());
  std::string write_error;
  int worker_signal = 0;  // a signal an MPI worker rank received (it stops the sweep)
  try {
#ifdef LASH_MPI
    if (size > 1) {
      // Rank 0 hands out one run at a time to whichever rank asks (runs differ a lot in cost) and
      // keeps the database; the ranks need no shared file system.
      size_t next = 0;
      int active = size - 1;
      while (active > 0) {
        // Polled with growing pauses (up to 2 ms) rather than MPI_Probe, which Open MPI answers
        // by spinning: this rank only hands out runs, and spinning took a whole core from them.
        MPI_Status st;
        int arrived = 0;
        for (auto pause = std::chrono::microseconds(20);;
             pause = std::min(2 * pause, std::chrono::microseconds(2000))) {
          MPI_Iprobe(MPI_ANY_SOURCE, kTagResult, MPI_COMM_WORLD, &arrived, &st);
          if (arrived) break;
          std::this_thread::sleep_for(pause);
        }
        int n = 0;
        MPI_Get_count(&st, MPI_CHAR, &n);
        std::string msg(n, '\0');
        MPI_Recv(msg.data(), n, MPI_CHAR, st.MPI_SOURCE, kTagResult, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        if (!msg.empty() && write_error.empty()) {
          const nlohmann::json message = nlohmann::json::from_msgpack(msg);
          const RunRecord rec = record_from_json(message);
          // A rank stopped by a signal of its own stops the sweep as one to this rank would:
          // the runs it would be handed all came back interrupted, and unrecorded.
          if (const int signal = message.value("signal", 0); signal != 0 && worker_signal == 0)
            worker_signal = signal;
          if (rec.status != "interrupted") {  // rerun by --resume
            try {
              folder->db().add(folder->runs().at(rec.index), rec, "rank " + std::to_string(st.MPI_SOURCE));
              progress.add(rec);
            } catch (const std::exception& e) {
              write_error = e.what();
            }
          }
        }
        int index = -1;
        if (next < folder->todo().size() && interrupt.load() == 0 && worker_signal == 0 &&
            write_error.empty())
          index = folder->todo()[next++].index;
        MPI_Send(&index, 1, MPI_INT, st.MPI_SOURCE, kTagWork, MPI_COMM_WORLD);
        if (index < 0) --active;
      }
      try {
        folder->db().export_csv(out);
      } catch (const std::exception& e) {
        write_error += (write_error.empty() ? "" : "; then ") + std::string(e.what());
      }
    } else
#endif
    {
      write_error = run_study_threads(*folder, spec, jobs_, &interrupt,
                                      [&](const RunRecord& rec) { progress.add(rec); });
    }
  } catch (const std::exception& e) {  // reading the database (the chains' recorded states)
    write_error = e.what();
  }
  progress.print(true);
  return finish(*folder, total, progress, interrupt.load() != 0 ? interrupt.load() : worker_signal,
                write_error, quiet_);
}

}  // namespace lash::cli
