// A study's results in SQLite (study_db.hpp).
#include "study/study_db.hpp"

#include <sqlite3.h>

#include <chrono>
#include <cmath>
#include <ctime>
#include <map>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <mutex>
#include <sstream>
#include <thread>

#include "io/files.hpp"
#include "io/number_format.hpp"

namespace lash {
namespace {

constexpr int kSchemaVersion = 1;

std::string quoted(const std::string& name) {  // an SQL identifier
  std::string q = "\"";
  for (char c : name) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

/// A prepared statement, finalised on scope exit.
class Stmt {
 public:
  Stmt(sqlite3* db, const std::string& sql, const std::string& path) : path_(path) {
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s_, nullptr) != SQLITE_OK)
      throw IoError(path, std::string("database: ") + sqlite3_errmsg(db));
  }
  ~Stmt() { sqlite3_finalize(s_); }
  Stmt& bind(int i, const std::string& v) {
    sqlite3_bind_text(s_, i, v.c_str(), -1, SQLITE_TRANSIENT);
    return *this;
  }
  Stmt& bind(int i, double v) {
    if (std::isfinite(v)) sqlite3_bind_double(s_, i, v);
    else sqlite3_bind_null(s_, i);
    return *this;
  }
  Stmt& bind(int i, long v) {
    sqlite3_bind_int64(s_, i, v);
    return *this;
  }
  /// A parameter: its number where it is one, else its text.
  Stmt& bind_value(int i, const std::string& text, double number) {
    return std::isnan(number) ? bind(i, text) : bind(i, number);
  }
  bool step() {
    const int rc = sqlite3_step(s_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    throw IoError(path_, std::string("database: ") + sqlite3_errmsg(sqlite3_db_handle(s_)));
  }
  void run() {
    step();
    sqlite3_reset(s_);
    sqlite3_clear_bindings(s_);
  }
  std::string text(int i) const {
    const auto* p = sqlite3_column_text(s_, i);
    return p ? reinterpret_cast<const char*>(p) : "";
  }
  double number(int i) const {
    return sqlite3_column_type(s_, i) == SQLITE_NULL ? std::nan("") : sqlite3_column_double(s_, i);
  }
  bool is_text(int i) const { return sqlite3_column_type(s_, i) == SQLITE_TEXT; }

 private:
  sqlite3_stmt* s_ = nullptr;
  std::string path_;
};

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

/// A CSV field: the shortest exact text; NaN (a metric a run lacks) an empty field.
std::string csv_number(double v) { return std::isnan(v) ? std::string() : shortest_number(v); }

std::string now_utc() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

/// `s` as valid UTF-8, for JSON (whose writer refuses anything else): well-formed sequences
/// (RFC 3629) as they are, every other byte as the four characters \xNN. Distinct texts stay
/// distinct unless one holds such an escape literally; a path or a model text in Latin-1 is
/// compared, not refused.
std::string utf8_escaped(const std::string& s) {
  const auto in = [](unsigned char c, unsigned lo, unsigned hi) { return c >= lo && c <= hi; };
  std::string out;
  out.reserve(s.size());
  for (size_t i = 0; i < s.size();) {
    const auto b = [&](size_t k) { return i + k < s.size() ? static_cast<unsigned char>(s[i + k]) : 0; };
    const unsigned char c = b(0);
    size_t n = 0;
    if (c < 0x80) n = 1;
    else if (in(c, 0xC2, 0xDF)) n = in(b(1), 0x80, 0xBF) ? 2 : 0;
    else if (in(c, 0xE0, 0xEF)) {
      const unsigned lo = c == 0xE0 ? 0xA0 : 0x80, hi = c == 0xED ? 0x9F : 0xBF;
      n = in(b(1), lo, hi) && in(b(2), 0x80, 0xBF) ? 3 : 0;
    } else if (in(c, 0xF0, 0xF4)) {
      const unsigned lo = c == 0xF0 ? 0x90 : 0x80, hi = c == 0xF4 ? 0x8F : 0xBF;
      n = in(b(1), lo, hi) && in(b(2), 0x80, 0xBF) && in(b(3), 0x80, 0xBF) ? 4 : 0;
    }
    if (n > 0) {
      out.append(s, i, n);
      i += n;
    } else {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02X", c);
      out += hex;
      ++i;
    }
  }
  return out;
}

/// The model files' texts by their paths as the study file names them (relative to its folder),
/// so the same study resumes however its own path is spelled (absolute, from another folder);
/// `as_given`: by the paths as this process spelled them (what older databases recorded).
std::string model_texts_json(const StudySpec& spec, bool as_given = false) {
  namespace fs = std::filesystem;
  const fs::path base = fs::path(spec.file).parent_path();
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [path, text] : spec.model_texts) {
    fs::path key = base.empty() || as_given ? fs::path(path) : fs::path(path).lexically_relative(base);
    if (key.empty()) key = path;
    j[utf8_escaped(key.string())] = utf8_escaped(text);
  }
  return j.dump();
}

/// The model files whose text differs between a database's `model_texts` (`stored`) and the
/// study's now, as model_texts_json writes them: `a.yaml, b.yaml (no longer used)`.
std::string changed_models(const std::string& stored, const StudySpec& spec) {
  const nlohmann::json was = nlohmann::json::parse(stored, nullptr, false);
  nlohmann::json now = nlohmann::json::parse(model_texts_json(spec));
  if (!was.is_object()) return "";
  const nlohmann::json given = nlohmann::json::parse(model_texts_json(spec, true));
  auto same_keys = [&](const nlohmann::json& a) {
    if (a.size() != was.size()) return false;
    for (const auto& item : a.items())
      if (!was.contains(item.key())) return false;
    return true;
  };
  if (!same_keys(now) && same_keys(given)) now = given;
  std::string names;
  auto add = [&](const std::string& name) { names += (names.empty() ? "" : ", ") + name; };
  for (const auto& item : now.items())
    if (!was.contains(item.key()) || was[item.key()] != item.value()) add(item.key());
  for (const auto& item : was.items())
    if (!now.contains(item.key())) add(item.key() + " (no longer used)");
  return names;
}

}  // namespace

StudyDb::StudyDb(const std::string& path, const StudySpec& spec, int total_runs) : path_(path) {
  parameters_ = parameter_columns(spec);
  if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) != SQLITE_OK) {
    const std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw IoError(path, "cannot open the study database: " + msg);
  }
  sqlite3_busy_timeout(db_, 10000);
  try {
    exec("PRAGMA journal_mode=WAL");  // one fsync per commit, readers never blocked
    exec("PRAGMA synchronous=FULL");
    bool fresh = true;
    {
      // Fresh: no table at all. Tables without `study` are another program's database, which
      // a study written into would mix with (and --resume would adopt).
      std::string others;
      bool study = false;
      Stmt s(db_, "SELECT name FROM sqlite_master WHERE type='table'", path_);
      while (s.step()) {
        const std::string name = s.text(0);
        study = study || name == "study";
        if (others.size() < 200) others += (others.empty() ? "" : ", ") + name;
      }
      fresh = others.empty();
      if (!fresh && !study)
        throw std::invalid_argument(path + ": not a lash study database (its tables: " + others +
                                    "); choose another output folder");
    }
    if (fresh) {
      std::string runs = "CREATE TABLE runs(run INTEGER PRIMARY KEY";
      for (const auto& p : parameters_) runs += ", " + quoted(p);
      runs += ", status TEXT NOT NULL, message TEXT, verdict TEXT, t_reached REAL, "
              "wall_seconds REAL, steps INTEGER, rhs_evaluations INTEGER, events INTEGER, "
              "worker TEXT, finished TEXT)";
      exec("BEGIN IMMEDIATE");
      exec("CREATE TABLE study(key TEXT PRIMARY KEY, value TEXT)");
      exec("CREATE TABLE parameters(position INTEGER PRIMARY KEY, name TEXT NOT NULL)");
      exec(runs);
      exec("CREATE TABLE metrics(run INTEGER NOT NULL, name TEXT NOT NULL, value REAL, "
           "PRIMARY KEY(run, name))");
      exec("CREATE TABLE sections(run INTEGER NOT NULL, k INTEGER NOT NULL, t REAL NOT NULL, "
           "channel TEXT NOT NULL, value REAL)");
      exec("CREATE INDEX sections_run ON sections(run)");
      exec("CREATE TABLE series(run INTEGER NOT NULL, channel TEXT NOT NULL, time TEXT NOT NULL, "
           "value TEXT NOT NULL)");
      exec("CREATE INDEX series_run ON series(run)");
      exec("CREATE TABLE states(run INTEGER PRIMARY KEY, driver_speed REAL, state TEXT NOT NULL)");
      Stmt st(db_, "INSERT INTO study(key, value) VALUES(?, ?)", path_);
      const std::map<std::string, std::string> info = {
          {"schema_version", std::to_string(kSchemaVersion)},
          {"name", spec.name},
          {"study_file", spec.file},
          {"study_text", spec.text},
          {"model_texts", model_texts_json(spec)},
          {"runs", std::to_string(total_runs)},
          {"created", now_utc()}};
      for (const auto& [k, v] : info) st.bind(1, k).bind(2, v).run();
      Stmt sp(db_, "INSERT INTO parameters(position, name) VALUES(?, ?)", path_);
      for (size_t i = 0; i < parameters_.size(); ++i)
        sp.bind(1, static_cast<long>(i)).bind(2, parameters_[i]).run();
      exec("COMMIT");
    } else {
      std::map<std::string, std::string> info;
      Stmt s(db_, "SELECT key, value FROM study", path_);
      while (s.step()) info[s.text(0)] = s.text(1);
      if (info["schema_version"] != std::to_string(kSchemaVersion))
        throw std::invalid_argument(path + ": a study database of another lash version (schema " +
                                    info["schema_version"] + ")");
      if (info["study_text"] != spec.text)
        throw std::invalid_argument(path + ": holds the results of another study file (" +
                                    info["study_file"] +
                                    " as it was then); resuming would mix two studies: choose "
                                    "another output folder");
      if (info["model_texts"] != model_texts_json(spec) &&
          info["model_texts"] != model_texts_json(spec, true))
      {
        const std::string names = changed_models(info["model_texts"], spec);
        throw std::invalid_argument(
            path + ": the model file(s) changed since this study began" +
            (names.empty() ? "" : " (" + names + ")") +
            "; resuming would mix two models: choose another output folder");
      }
      // A database begun by an earlier lash has no index of series by run, which add() reads
      // (each resumed run would scan every series row).
      exec("CREATE INDEX IF NOT EXISTS series_run ON series(run)");
    }
  } catch (...) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

StudyDb::~StudyDb() { sqlite3_close(db_); }

void StudyDb::exec(const std::string& sql) const {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    throw IoError(path_, "database: " + msg);
  }
}

std::set<int> StudyDb::finished() const {
  std::set<int> out;
  Stmt s(db_, "SELECT run FROM runs", path_);
  while (s.step()) out.insert(static_cast<int>(s.number(0)));
  return out;
}

void StudyDb::add(const StudyRun& run, const RunRecord& r, const std::string& worker) {
  exec("BEGIN IMMEDIATE");
  try {
    // What is left of this run without its row in runs (a database changed by hand: the row
    // deleted, so --resume runs it again) is replaced, not collided with.
    for (const char* table : {"metrics", "sections", "series", "states"}) {
      Stmt d(db_, std::string("DELETE FROM ") + table + " WHERE run = ?", path_);
      d.bind(1, static_cast<long>(r.index)).run();
    }
    std::string sql = "INSERT INTO runs(run";
    for (const auto& p : parameters_) sql += ", " + quoted(p);
    sql += ", status, message, verdict, t_reached, wall_seconds, steps, rhs_evaluations, events, "
           "worker, finished) VALUES(?";
    for (size_t i = 0; i < parameters_.size() + 10; ++i) sql += ", ?";
    sql += ")";
    Stmt s(db_, sql, path_);
    int i = 1;
    s.bind(i++, static_cast<long>(r.index));
    for (size_t p = 0; p < parameters_.size(); ++p) s.bind_value(i++, run.values[p], run.numbers[p]);
    s.bind(i, r.status).bind(i + 1, r.message).bind(i + 2, r.verdict).bind(i + 3, r.t_reached);
    s.bind(i + 4, r.wall_seconds).bind(i + 5, r.steps).bind(i + 6, r.rhs_evaluations);
    s.bind(i + 7, r.events).bind(i + 8, worker).bind(i + 9, now_utc());
    s.run();
    Stmt m(db_, "INSERT INTO metrics(run, name, value) VALUES(?, ?, ?)", path_);
    for (const auto& [name, v] : r.metrics) m.bind(1, static_cast<long>(r.index)).bind(2, name).bind(3, v).run();
    Stmt sec(db_, "INSERT INTO sections(run, k, t, channel, value) VALUES(?, ?, ?, ?, ?)", path_);
    for (size_t k = 0; k < r.section_times.size(); ++k)
      for (size_t c = 0; c < r.section_channels.size(); ++c)
        sec.bind(1, static_cast<long>(r.index)).bind(2, static_cast<long>(k)).bind(3, r.section_times[k])
            .bind(4, r.section_channels[c]).bind(5, r.section_values[k][c]).run();
    Stmt ser(db_, "INSERT INTO series(run, channel, time, value) VALUES(?, ?, ?, ?)", path_);
    const std::string times = nlohmann::json(r.series_time).dump();
    for (size_t c = 0; c < r.series_channels.size(); ++c)
      ser.bind(1, static_cast<long>(r.index)).bind(2, r.series_channels[c]).bind(3, times)
          .bind(4, nlohmann::json(r.series_values[c]).dump()).run();
    if (r.final_state.y.size() > 0) {  // continuation: the next run starts here
      Stmt st(db_, "INSERT INTO states(run, driver_speed, state) VALUES(?, ?, ?)", path_);
      st.bind(1, static_cast<long>(r.index)).bind(2, r.driver_speed)
          .bind(3, state_json(r.final_state).dump()).run();
    }
    exec("COMMIT");
  } catch (...) {
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

RunRecord StudyDb::recorded(int run) const {
  RunRecord r;
  r.index = run;
  {
    Stmt s(db_, "SELECT status, message FROM runs WHERE run = ?", path_);
    s.bind(1, static_cast<long>(run));
    if (!s.step()) throw std::invalid_argument(path_ + ": no run " + std::to_string(run));
    r.status = s.text(0);
    r.message = s.text(1);
  }
  Stmt s(db_, "SELECT driver_speed, state FROM states WHERE run = ?", path_);
  s.bind(1, static_cast<long>(run));
  if (s.step()) {
    r.driver_speed = s.number(0);
    r.final_state = state_from_json(nlohmann::json::parse(s.text(1)));
  }
  return r;
}

void StudyDb::export_csv(const std::string& folder) const {
  const StudyTable t = read_study(path_);
  std::vector<std::string> metric_names;
  for (const auto& row : t.rows)
    for (const auto& [name, v] : row.metrics)
      if (std::find(metric_names.begin(), metric_names.end(), name) == metric_names.end())
        metric_names.push_back(name);
  std::ostringstream out;
  out << "run";
  for (const auto& p : t.parameters) out << "," << csv_field(p);
  out << ",status,verdict,wall_seconds";
  for (const auto& m : metric_names) out << "," << csv_field(m);
  out << ",message\n";
  for (const auto& row : t.rows) {
    out << row.run;
    for (size_t p = 0; p < t.parameters.size(); ++p)
      out << "," << (std::isnan(row.numbers[p]) ? csv_field(row.values[p]) : csv_number(row.numbers[p]));
    out << "," << row.status << "," << row.verdict << "," << csv_number(row.wall_seconds);
    for (const auto& m : metric_names) {
      out << ",";
      for (const auto& [name, v] : row.metrics)
        if (name == m) out << csv_number(v);
    }
    out << "," << csv_field(row.message) << "\n";
  }
  write_file_atomic(folder + "/runs.csv", out.str());

  std::ostringstream sec;
  sec << "run";
  for (const auto& p : t.parameters) sec << "," << csv_field(p);
  sec << ",k,t,channel,value\n";
  std::map<int, const StudyTable::Row*> by_run;
  for (const auto& row : t.rows) by_run[row.run] = &row;
  Stmt s(db_, "SELECT run, k, t, channel, value FROM sections ORDER BY run, k, channel", path_);
  while (s.step()) {
    const int run = static_cast<int>(s.number(0));
    const auto found = by_run.find(run);
    if (found == by_run.end()) continue;  // no row in runs (a database changed by hand): as metrics
    const auto* row = found->second;
    sec << run;
    for (size_t p = 0; p < t.parameters.size(); ++p)
      sec << "," << (std::isnan(row->numbers[p]) ? csv_field(row->values[p]) : csv_number(row->numbers[p]));
    sec << "," << static_cast<long>(s.number(1)) << "," << csv_number(s.number(2)) << ","
        << csv_field(s.text(3)) << "," << csv_number(s.number(4)) << "\n";
  }
  write_file_atomic(folder + "/sections.csv", sec.str());
}

StudyTable read_study(const std::string& path) {
  sqlite3* db = nullptr;
  // Read-write where it may (it writes nothing): a read-only connection to a WAL database
  // creates study.db-wal and study.db-shm and cannot remove them when it closes, so they would
  // be left beside a finished study. Read-only where the folder or file is not writable.
  if (!std::filesystem::exists(path))
    throw IoError(path, "cannot open the study database: no such file");
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK) {
    sqlite3_close(db);
    db = nullptr;
  }
  if (!db && sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    const std::string msg = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    throw IoError(path, "cannot open the study database: " + msg);
  }
  sqlite3_busy_timeout(db, 10000);
  StudyTable t;
  try {
    {
      Stmt s(db, "SELECT key, value FROM study WHERE key IN ('name', 'runs')", path);
      while (s.step()) {
        if (s.text(0) == "name") t.name = s.text(1);
        else t.total_runs = std::atoi(s.text(1).c_str());
      }
    }
    {
      Stmt s(db, "SELECT name FROM parameters ORDER BY position", path);
      while (s.step()) t.parameters.push_back(s.text(0));
    }
    std::string sql = "SELECT run";
    for (const auto& p : t.parameters) sql += ", " + quoted(p);
    sql += ", status, message, verdict, wall_seconds FROM runs ORDER BY run";
    Stmt s(db, sql, path);
    std::map<int, size_t> at;
    while (s.step()) {
      StudyTable::Row row;
      row.run = static_cast<int>(s.number(0));
      int i = 1;
      for (size_t p = 0; p < t.parameters.size(); ++p, ++i) {
        row.values.push_back(s.text(i));
        row.numbers.push_back(s.is_text(i) ? std::nan("") : s.number(i));
        if (!s.is_text(i)) row.values.back() = csv_number(row.numbers.back());
      }
      row.status = s.text(i++);
      row.message = s.text(i++);
      row.verdict = s.text(i++);
      row.wall_seconds = s.number(i++);
      at[row.run] = t.rows.size();
      t.rows.push_back(std::move(row));
    }
    Stmt m(db, "SELECT run, name, value FROM metrics ORDER BY run, rowid", path);
    while (m.step()) {
      const auto it = at.find(static_cast<int>(m.number(0)));
      if (it != at.end()) t.rows[it->second].metrics.push_back({m.text(1), m.number(2)});
    }
    Stmt c(db, "SELECT DISTINCT channel FROM sections ORDER BY channel", path);
    while (c.step()) t.section_channels.push_back(c.text(0));
    t.points.resize(t.section_channels.size());
    Stmt p(db, "SELECT run, channel, value FROM sections ORDER BY run, k", path);
    while (p.step()) {
      const auto ch = std::find(t.section_channels.begin(), t.section_channels.end(), p.text(1));
      t.points[ch - t.section_channels.begin()].push_back({static_cast<int>(p.number(0)), p.number(2)});
    }
  } catch (...) {
    sqlite3_close(db);
    throw;
  }
  sqlite3_close(db);
  return t;
}

StudyFolder::StudyFolder(const std::string& folder, const StudySpec& spec, bool resume)
    : folder_(folder), runs_(study_runs(spec)) {
  lock_ = std::make_shared<FolderLock>(folder);
  const std::string db = folder + "/study.db";
  // A run's folder (lash run) is not a study's: `lash report` would report on one of the two.
  for (const char* f : {"summary.json", "timeseries.csv", "timeseries.h5"})
    if (std::filesystem::exists(folder + "/" + f))
      throw std::invalid_argument(folder + "/" + f + ": this folder holds the results of a run of "
                                  "`lash run`; a study's would mix with them: choose another "
                                  "output folder");
  if (std::filesystem::exists(db) && !resume)
    throw std::invalid_argument(db + ": this folder holds a study already: add --resume to finish it "
                                     "(runs it holds are kept and not run again), or choose another "
                                     "output folder");
  db_ = std::make_unique<StudyDb>(db, spec, static_cast<int>(runs_.size()));
  const auto finished = db_->finished();
  for (const auto& r : runs_)
    if (!finished.count(r.index)) todo_.push_back(r);
}

std::string run_study_threads(StudyFolder& folder, const StudySpec& spec, int jobs,
                              const std::atomic<int>* interrupt,
                              const std::function<void(const RunRecord&)>& on_record) {
  // Threads: one study, one model text, a model and workspace per run; the database is written
  // by the calling thread only.
  // Work units: single runs, or in a continuation study chains of runs, each starting from the
  // one before (from the database when that one was recorded by an earlier, interrupted sweep).
  const auto& todo = folder.todo();
  std::vector<std::vector<const StudyRun*>> units;
  for (const auto& r : todo) {
    if (!units.empty() && r.previous >= 0 && units.back().back()->index == r.previous)
      units.back().push_back(&r);
    else
      units.push_back({&r});
  }
  std::vector<RunRecord> chain_start(units.size());  // the recorded run a chain continues
  std::vector<bool> has_start(units.size(), false);
  for (size_t u = 0; u < units.size(); ++u)
    if (units[u].front()->previous >= 0) {
      chain_start[u] = folder.db().recorded(units[u].front()->previous);
      has_start[u] = true;
    }
  const int n = std::max(1, std::min<int>(jobs > 0 ? jobs : static_cast<int>(std::thread::hardware_concurrency()),
                                          static_cast<int>(units.size())));
  auto interrupted = [&] { return interrupt && interrupt->load() != 0; };
  std::mutex mu;
  std::condition_variable cv;
  std::deque<RunRecord> results;
  std::atomic<size_t> next{0};
  std::atomic<bool> stop{false};
  std::vector<std::thread> workers;
  for (int w = 0; w < n; ++w)
    workers.emplace_back([&] {
      for (;;) {
        const size_t u = next++;
        if (u >= units.size() || stop.load() || interrupted()) break;
        RunRecord before;
        bool have_before = has_start[u];
        if (have_before) before = chain_start[u];
        for (const StudyRun* run : units[u]) {
          if (stop.load() || interrupted()) break;
          RunRecord rec = run_study_point(spec, *run, interrupt, have_before ? &before : nullptr);
          const bool go_on = rec.status != "interrupted";
          if (go_on) {
            before = rec;  // the chain's next run starts where this one ended
            have_before = true;
          }
          {
            std::lock_guard<std::mutex> g(mu);
            results.push_back(std::move(rec));
            cv.notify_one();
          }
          if (!go_on) break;
        }
      }
      RunRecord done;
      done.index = -1;  // this worker is done
      std::lock_guard<std::mutex> g(mu);
      results.push_back(std::move(done));
      cv.notify_one();
    });
  std::string write_error;
  int running = n;
  while (running > 0) {
    std::unique_lock<std::mutex> lk(mu);
    cv.wait(lk, [&] { return !results.empty(); });
    while (!results.empty()) {
      RunRecord rec = std::move(results.front());
      results.pop_front();
      lk.unlock();
      if (rec.index < 0) {
        --running;
      } else if (rec.status != "interrupted" && write_error.empty()) {  // interrupted: rerun by --resume
        try {
          folder.db().add(folder.runs().at(rec.index), rec, "thread");
          if (on_record) on_record(rec);
        } catch (const std::exception& e) {
          write_error = e.what();
          stop.store(true);
        }
      }
      lk.lock();
    }
  }
  for (auto& t : workers) t.join();
  try {
    folder.db().export_csv(folder.folder());
  } catch (const std::exception& e) {  // the database error first: it is why the study stopped
    write_error += (write_error.empty() ? "" : "; then ") + std::string(e.what());
  }
  return write_error;
}

int StudyDb::failed() const {
  Stmt s(db_, "SELECT count(*) FROM runs WHERE status <> 'completed'", path_);
  s.step();
  return static_cast<int>(s.number(0));
}

}  // namespace lash
