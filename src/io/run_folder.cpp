#include "io/run_folder.hpp"

#include "io/hdf5_series.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <sys/stat.h>

#include "io/files.hpp"
#include "io/state_file.hpp"

namespace lash {

namespace {

/// A line's ending as a Windows editor saves it (CR LF): the CR is no part of the last field
/// (it made "'-3.91123009' is not a finite number", the CR invisible in the message).
void drop_cr(std::string& line) {
  if (!line.empty() && line.back() == '\r') line.pop_back();
}

using nlohmann::json;

std::string fmt_g(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

[[noreturn]] void damaged(const std::string& what) { throw RunFolderError(what); }

/// A number of a CSV field, the whole field; NaN and ±inf are numbers (a failed run writes them).
bool parse_number(const char* b, const char* e, double& v) {
  if (b == e) return false;
  if (*b == '+') return false;  // the writer never writes one
  const auto r = std::from_chars(b, e, v);
  return r.ec == std::errc() && r.ptr == e;
}

/// Splits a line at commas.
std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  size_t a = 0;
  for (size_t i = 0; i <= line.size(); ++i)
    if (i == line.size() || line[i] == ',') out.push_back(line.substr(a, i - a)), a = i + 1;
  return out;
}

/// Lines of a file (counting '\n') and whether its last byte ends a line; throws IoError.
std::pair<long long, bool> count_lines(const std::string& path) {
  // A link to /dev/zero or a FIFO would be read for ever: only a regular file is a run's file.
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw IoError(path, std::string("cannot be opened: ") + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) damaged(path + ": not a regular file (a run writes a text file there)");
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw IoError(path, std::string("cannot be opened: ") + std::strerror(errno));
  std::vector<char> buf(1 << 20);
  long long lines = 0;
  char last = '\n';
  size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), f)) > 0) {
    for (size_t i = 0; i < n; ++i) lines += buf[i] == '\n';
    last = buf[n - 1];
  }
  const bool err = std::ferror(f);
  std::fclose(f);
  if (err) throw IoError(path, "read failed");
  return {lines, last == '\n'};
}

/// A member of the summary, or the message that it is missing.
const json& member(const json& j, const std::string& path, const std::string& key) {
  if (!j.is_object() || !j.contains(key)) damaged(path + ": damaged (no '" + key + "'); run the model again");
  return j[key];
}

/// `name`'s value (its last part the key in `parent`: "status.outcome") as a T, or damaged()
/// naming the field, what it holds and what was expected (not a JSON library's "cannot use at()
/// with string").
template <class T>
T field(const json& parent, const std::string& path, const std::string& name) {
  const std::string key = name.substr(name.rfind('.') + 1);
  const std::string owner = name.find('.') == std::string::npos ? "" : name.substr(0, name.rfind('.'));
  auto wrong = [&](const std::string& what) {
    damaged(path + ": damaged (" + what + "); run the model again");
  };
  if (!parent.is_object())
    wrong(owner + " is " + parent.dump().substr(0, 40) + ", expected an object");
  if (!parent.contains(key)) wrong("no '" + name + "'");
  const json& v = parent.at(key);
  const std::string got = name + " is " + v.dump().substr(0, 40);
  if constexpr (std::is_same_v<T, std::string>) {
    if (!v.is_string()) wrong(got + ", expected text");
  } else if constexpr (std::is_same_v<T, bool>) {
    if (!v.is_boolean()) wrong(got + ", expected true or false");
  } else if constexpr (std::is_same_v<T, double>) {
    if (!v.is_number()) wrong(got + ", expected a number");
  } else {
    static_assert(std::is_same_v<T, std::vector<std::string>>);
    if (!v.is_array() || !std::all_of(v.begin(), v.end(), [](const json& e) { return e.is_string(); }))
      wrong(got + ", expected a list of texts");
  }
  return v.get<T>();
}

RunOutcome outcome_of(const std::string& s) {
  if (s == "completed") return RunOutcome::completed;
  if (s == "interrupted") return RunOutcome::interrupted;
  if (s == "write_error") return RunOutcome::write_error;
  return RunOutcome::failed;
}

/// The rows of timeseries.csv, read one at a time and checked as they come.
struct CsvRows {
  std::ifstream in;
  std::string path;
  size_t width = 0;  ///< values per row, time included
  long long line = 1;
  double t_last = -std::numeric_limits<double>::infinity();
  bool next(double& t, double* values) {
    std::string s;
    if (!std::getline(in, s)) {
      if (in.bad()) throw IoError(path, "read failed");
      return false;
    }
    drop_cr(s);
    ++line;
    const std::string where = path + ":" + std::to_string(line);
    size_t col = 0, a = 0;
    for (size_t i = 0; i <= s.size(); ++i) {
      if (i < s.size() && s[i] != ',') continue;
      if (col >= width)
        damaged(where + ": more than " + std::to_string(width) +
                " fields (time and one per channel of the header)");
      double v;
      if (!parse_number(s.data() + a, s.data() + i, v))
        damaged(where + ":" + std::to_string(a + 1) + ": '" + s.substr(a, i - a) +
                "' is not a number");
      // A run writes finite values only (a non-finite one stops it); the time is checked below.
      if (col > 0 && !std::isfinite(v))
        damaged(where + ":" + std::to_string(a + 1) + ": '" + s.substr(a, i - a) +
                "' is not a finite number (a run stops before it would write one)");
      if (col == 0) t = v;
      else values[col - 1] = v;
      ++col;
      a = i + 1;
    }
    if (col != width)
      damaged(where + ": " + std::to_string(col) + " fields, expected " + std::to_string(width) +
              " (time and one per channel of the header): the row is cut");
    if (!std::isfinite(t)) damaged(where + ":1: time " + s.substr(0, s.find(',')) + " is not a finite number");
    if (!(t > t_last)) damaged(where + ": time " + s.substr(0, s.find(',')) + " does not follow the row before");
    t_last = t;
    return true;
  }
};

}  // namespace

RecordedRun read_run_folder(const std::string& dir, const Model& model) {
  namespace fs = std::filesystem;
  const std::string summary_path = dir + "/summary.json", model_path = dir + "/model_resolved.yaml";
  RecordedRun run;
  // A count (rows, steps, events): a whole number >= 0 as the run wrote it (1e30 became
  // -9223372036854775808, a conversion with no defined result).
  auto count = [&](const json& parent, const std::string& name) -> long {
    field<double>(parent, summary_path, name);  // there, and a number
    const json& v = parent.at(name.substr(name.find('.') + 1));
    if (!v.is_number_integer() || (v.is_number_unsigned() ? v.get<unsigned long long>() > 1ULL << 62
                                                          : v.get<long long>() < 0))
      damaged(summary_path + ": damaged (" + name + " is " + v.dump().substr(0, 40) +
              ", expected a whole number >= 0); run the model again");
    return v.get<long>();
  };

  // summary.json: the run's own account, written last; without it the run did not finish.
  if (!fs::exists(summary_path))
    damaged(summary_path + ": missing: the run did not finish (killed?), so its files are not "
                           "known to be whole; run the model again");
  json sum;
  try {
    sum = json::parse(read_input_file(summary_path, kMaxModelFileBytes));
  } catch (const json::exception& e) {
    damaged(summary_path + ": damaged (not valid JSON: " + e.what() + "); run the model again");
  } catch (const std::invalid_argument& e) {
    damaged(e.what());
  }
  // The model it ran: exactly the text of model_resolved.yaml (an edited model would give a
  // report of a run that never happened).
  const json& resolved = member(member(sum, summary_path, "model"), summary_path, "resolved");
  if (!resolved.is_string()) damaged(summary_path + ": damaged (model.resolved is not text)");
  if (resolved.get<std::string>() + "\n" != read_input_file(model_path, kMaxModelFileBytes))
    damaged(model_path + ": differs from the model this run used (summary.json model.resolved): "
                         "edited after the run? It no longer matches the run's results; run the "
                         "edited model with `lash run` instead");
  // The model file the run was given (report_data's model.file), not its copy in the folder.
  if (const json& m = sum.at("model"); m.contains("file") && m.at("file").is_string())
    run.model_file = m.at("file").get<std::string>();
  try {
    const json& st = member(sum, summary_path, "status");
    RunStatus& s = run.result.status;
    s.outcome = outcome_of(field<std::string>(st, summary_path, "status.outcome"));
    s.ok = field<bool>(st, summary_path, "status.ok");
    s.t = field<double>(st, summary_path, "status.time");
    s.element = field<std::string>(st, summary_path, "status.element");
    s.message = field<std::string>(st, summary_path, "status.message");
    const json& in = member(sum, summary_path, "integrator");
    run.result.integrator = field<std::string>(in, summary_path, "integrator.name");
    run.result.stats.steps = count(in, "integrator.steps");
    run.result.stats.rejected_steps = count(in, "integrator.rejected_steps");
    run.result.stats.rhs_evaluations = count(in, "integrator.rhs_evaluations");
    run.result.stats.events = count(in, "integrator.events");
    run.result.stats.projections = in.contains("projections") ? count(in, "integrator.projections") : 0;
    run.result.wall_seconds = field<double>(in, summary_path, "integrator.wall_seconds");
    run.result.outputs = count(in, "integrator.outputs");
    run.result.missed_events = count(in, "integrator.missed_events");
    run.result.max_constraint_violation = field<double>(sum, summary_path, "max_constraint_violation");
    if (sum.contains("warnings"))
      run.result.warnings = field<std::vector<std::string>>(sum, summary_path, "warnings");
    // Every channel's exact extrema over the run (tracked between outputs while it ran).
    if (sum.contains("channels") && sum["channels"].is_object())
      for (const auto& [name, c] : sum["channels"].items()) {
        if (!c.is_object() || !c.contains("min") || !c["min"].is_number()) continue;
        ChannelExtremum e;
        const std::string at = "channels." + name + ".";
        e.min = field<double>(c, summary_path, at + "min");
        e.t_min = field<double>(c, summary_path, at + "t_min");
        e.max = field<double>(c, summary_path, at + "max");
        e.t_max = field<double>(c, summary_path, at + "t_max");
        e.seen = true;
        run.extrema[name] = e;
      }
  } catch (const json::exception& e) {
    damaged(summary_path + ": damaged (" + e.what() + "); run the model again");
  }
  const RunStatus& status = run.result.status;
  if (status.outcome == RunOutcome::interrupted)
    damaged(summary_path + ": the run did not complete (status.outcome interrupted at t = " +
            fmt_g(status.t) + " s), so its results cover part of the run only; continue it with "
            "`lash run --from` or run the model again");
  if (status.outcome == RunOutcome::write_error)
    damaged(summary_path + ": the run stopped when its results could not be written "
            "(status.outcome write_error at t = " + fmt_g(status.t) + " s: " + status.message +
            "), so they cover part of the run only; make room (or fix the folder) and run the "
            "model again");
  // A continued run (--from) holds its own stretch of time only; the analyses make the run
  // again from t = 0 (sections, the Lyapunov exponent, the ideal twin) and would mix in time
  // that is not in the folder.
  if (sum.contains("start") && sum["start"].is_object() && sum["start"].contains("from") &&
      sum["start"]["from"].is_string())
    damaged(summary_path + ": a run continued from " + sum["start"]["from"].get<std::string>() +
            " (start.from), which holds t >= " +
            fmt_g(sum["start"].value("time", 0.0)) + " s only; `analyze` and `report` take a "
            "whole run from t = 0 (as `--from` with `--report` is refused): run the model from "
            "its start, with the end_time you want");
  const json& output = member(sum, summary_path, "output");
  long long rows = 0;
  std::string file;
  try {
    rows = count(output, "output.rows");
    file = field<std::string>(output, summary_path, "output.file");
    run.columns = field<std::vector<std::string>>(output, summary_path, "output.channels");
  } catch (const json::exception& e) {
    damaged(summary_path + ": damaged (" + e.what() + "); run the model again");
  }
  if (file != "timeseries.csv" && file != "timeseries.h5")
    damaged(summary_path + ": damaged (output.file is '" + file + "')");
  run.read.push_back("status and integrator statistics: summary.json (outcome " +
                     std::string(outcome_name(status.outcome)) + ")");

  // final_state.json: where the run stopped, in the model's layout.
  const std::string state_path = dir + "/final_state.json";
  if (!fs::exists(state_path)) damaged(state_path + ": missing (every finished run writes it)");
  try {
    run.result.final_state = read_state(state_path, model, Workspace(model));
  } catch (const IoError&) {
    throw;
  } catch (const std::exception& e) {
    const std::string m = e.what();
    damaged(m.find(state_path) == std::string::npos ? state_path + ": " + m : m);
  }
  run.read.push_back("final state: final_state.json (t = " + fmt_g(run.result.final_state.t) + " s)");

  // events.csv: every row, now (a few thousand at most per second of run).
  const std::string events_path = dir + "/events.csv";
  if (!fs::exists(events_path)) damaged(events_path + ": missing");
  {
    std::vector<std::string> joints;
    for (const auto& j : model.joints)
      if (j.clearance) joints.push_back(j.name);
    const auto [lines, whole] = count_lines(events_path);
    if (!whole) damaged(events_path + ":" + std::to_string(lines + 1) + ": the last row is cut (no line end)");
    std::ifstream in(events_path);
    std::string line;
    long long n = 0;
    if (!std::getline(in, line) || (drop_cr(line), line != "time,joint,event,velocity"))
      damaged(events_path + ":1: expected the header 'time,joint,event,velocity'");
    while (std::getline(in, line)) {
      drop_cr(line);
      ++n;
      const std::string where = events_path + ":" + std::to_string(n + 1);
      const auto f = split(line);
      if (f.size() != 4) damaged(where + ": " + std::to_string(f.size()) + " fields, expected 4 (time,joint,event,velocity)");
      RecordedEvent e;
      if (!parse_number(f[0].data(), f[0].data() + f[0].size(), e.t) || !std::isfinite(e.t))
        damaged(where + ":1: time '" + f[0] + "' is not a finite number");
      const auto it = std::find(joints.begin(), joints.end(), f[1]);
      if (it == joints.end()) damaged(where + ": '" + f[1] + "' is not a clearance joint of the model");
      e.joint = static_cast<int>(it - joints.begin());
      if (f[2] != "onset" && f[2] != "separation")
        damaged(where + ": event '" + f[2] + "', expected onset or separation");
      e.onset = f[2] == "onset";
      if (!parse_number(f[3].data(), f[3].data() + f[3].size(), e.velocity) ||
          !std::isfinite(e.velocity))
        damaged(where + ": velocity '" + f[3] + "' is not a finite number");
      if (!run.events.empty() && e.t < run.events.back().t)
        damaged(where + ": time " + f[0] + " is before the row above");
      run.events.push_back(e);
    }
    // The rows: the events the integrator located and the crossings it missed, corrected
    // at the end of a step (summary.json integrator.missed_events).
    const long long expected = run.result.stats.events + run.result.missed_events;
    if (n != expected)
      damaged(events_path + ": " + std::to_string(n) + " events, summary.json counts " +
              std::to_string(expected) + " (integrator.events " +
              std::to_string(run.result.stats.events) + " and missed_events " +
              std::to_string(run.result.missed_events) + "): cut or edited after the run");
    run.read.push_back("contact events: events.csv (" + std::to_string(n) + ")");
  }

  // The time series: header and row count now, each row as it is read.
  run.series_file = dir + "/" + file;
  if (!fs::exists(run.series_file)) damaged(run.series_file + ": missing (summary.json lists it)");
  if (file == "timeseries.h5") {
    std::shared_ptr<Hdf5Rows> h5;
    try {
      h5 = std::make_shared<Hdf5Rows>(run.series_file, run.columns, rows);
    } catch (const std::invalid_argument& e) {
      damaged(e.what());
    }
    // The time column checked as the CSV reader checks it: finite, each row after the last.
    auto row = std::make_shared<long long>(0);
    auto t_last = std::make_shared<double>(-std::numeric_limits<double>::infinity());
    const std::string where = run.series_file;
    const std::vector<std::string> columns = run.columns;
    run.next_row = [h5, row, t_last, where, columns](double& t, double* v) {
      if (!h5->next(t, v)) return false;
      ++*row;
      char at[64];
      std::snprintf(at, sizeof at, "%.17g", t);
      if (!std::isfinite(t))
        damaged(where + ": time of row " + std::to_string(*row) + " (" + at + ") is not a finite number");
      for (size_t c = 0; c < columns.size(); ++c)
        if (!std::isfinite(v[c])) {
          std::snprintf(at, sizeof at, "%.17g", v[c]);
          damaged(where + ": " + columns[c] + " of row " + std::to_string(*row) + " (" + at +
                  ") is not a finite number (a run stops before it would write one)");
        }
      if (!(t > *t_last))
        damaged(where + ": time of row " + std::to_string(*row) + " (" + at +
                ") does not follow the row before");
      *t_last = t;
      return true;
    };
    run.read.push_back("time series: " + file + " (" + std::to_string(rows) + " rows, " +
                       std::to_string(run.columns.size()) + " channels)");
    return run;
  }
  const auto [lines, whole] = count_lines(run.series_file);
  if (!whole)
    damaged(run.series_file + ":" + std::to_string(lines + 1) + ": the last row is cut (no line end)");
  if (lines - 1 != rows)
    damaged(run.series_file + ": " + std::to_string(std::max(0LL, lines - 1)) +
            " rows, summary.json says " + std::to_string(rows) + ": cut or edited after the run");
  auto csv = std::make_shared<CsvRows>();
  csv->path = run.series_file;
  csv->in.open(run.series_file);
  if (!csv->in) throw IoError(run.series_file, "cannot be opened");
  std::string header;
  std::getline(csv->in, header);
  drop_cr(header);
  std::string expected = "time";
  for (const auto& c : run.columns) expected += "," + c;
  if (header != expected)
    damaged(run.series_file + ":1: the header differs from the channels summary.json lists "
                              "(output.channels)");
  csv->width = run.columns.size() + 1;
  run.next_row = [csv](double& t, double* v) { return csv->next(t, v); };
  run.read.push_back("time series: " + file + " (" + std::to_string(rows) + " rows, " +
                     std::to_string(run.columns.size()) + " channels)");
  return run;
}

}  // namespace lash
