/// @file lash_module.cpp
/// The compiled half of the Python package `lash` (module `lash._lash`): the C++ free functions
/// one to one — load a model (io/model_loader.hpp), simulate it (core/simulate.hpp) with an
/// in-memory observer, analyse a run (study/run_analysis.hpp) and the model-free analysis
/// functions (analysis/) — plus YAML emitting and parsing with yaml-cpp for models built in code.
/// The Python side (python/lash/*.py) wraps these in Model, Result and lash.analysis.
/// Long calls release the GIL and run on a worker thread while the calling thread polls
/// PyErr_CheckSignals: Ctrl-C sets RunOptions::interrupt and raises KeyboardInterrupt.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <type_traits>

#include "analysis/dynamics_analysis.hpp"
#include "analysis/signal.hpp"
#include "core/elements/registry.hpp"
#include "core/extrema.hpp"
#include "core/simulate.hpp"
#include "io/diagnostics.hpp"
#include "io/files.hpp"
#include "io/model_loader.hpp"
#include "io/results_writer.hpp"
#include "io/state_file.hpp"
#include "study/linear_modes.hpp"
#include "study/run_analysis.hpp"
#include "study/study_db.hpp"
#include "study/sweep.hpp"

namespace py = pybind11;

namespace {

/// A loaded, validated model with the text it was loaded from (after overrides).
struct CompiledModel {
  lash::LoadedModel loaded;
  std::vector<lash::ChannelInfo> channels;
};

/// A NumPy array that takes over `v` (no copy): the vector lives as long as the array.
py::array_t<double> to_numpy(std::vector<double>&& v, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<double>(std::move(v));
  py::capsule free_when_done(owned, [](void* p) { delete static_cast<std::vector<double>*>(p); });
  return py::array_t<double>(shape, owned->data(), free_when_done);
}
py::array_t<double> to_numpy(std::vector<double>&& v) {
  const auto n = static_cast<py::ssize_t>(v.size());
  return to_numpy(std::move(v), {n});
}

/// The identifier of Python's main thread (threading.main_thread().ident), set when the module
/// is imported. A function-local static initialised by calling Python deadlocked two threads
/// whose first run started together: one waited in the static's guard holding the GIL, the
/// other held the guard and waited for the GIL.
unsigned long g_main_thread_ident = 0;

/// Runs `work` on a worker thread with the GIL released; called from Python's main thread, the
/// calling thread checks for signals every 50 ms. On one (Ctrl-C: Python's handler raises
/// KeyboardInterrupt), `interrupt` is set, the work stops at its next output, and the Python
/// exception is raised once it has. Signal handlers run only in the main thread, so another
/// thread just waits, without taking the GIL: a daemon thread that takes it while the
/// interpreter finalizes is ended there (pthread_exit), which must not find the worker running.
template <class R>
R run_interruptible(const std::function<R()>& work, std::atomic<int>& interrupt) {
  R result{};
  std::exception_ptr error;
  bool done = false, signalled = false;
  std::mutex m;
  std::condition_variable cv;
  const bool main_thread = PyThread_get_thread_ident() == g_main_thread_ident;
  {
    py::gil_scoped_release release;
    std::thread worker([&] {
      try {
        result = work();
      } catch (...) {
        error = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(m);
      done = true;
      cv.notify_all();
    });
    // Whatever unwinds this frame (the thread ended while it waits) stops and joins the worker
    // first: it writes into this frame, and a joinable std::thread destroyed calls terminate.
    struct StopAndJoin {
      std::thread& worker;
      std::atomic<int>& interrupt;
      ~StopAndJoin() {
        if (!worker.joinable()) return;
        interrupt.store(SIGINT);
        worker.join();
      }
    } stop_and_join{worker, interrupt};
    std::unique_lock<std::mutex> lock(m);
    while (!done) {
      cv.wait_for(lock, std::chrono::milliseconds(50));
      if (done || signalled || !main_thread) continue;
      lock.unlock();
      {
        py::gil_scoped_acquire gil;
        // Runs the Python signal handlers (main thread only); -1: one raised, e.g. KeyboardInterrupt.
        if (PyErr_CheckSignals() != 0) signalled = true;
      }
      if (signalled) interrupt.store(SIGINT);
      lock.lock();
    }
    lock.unlock();
    worker.join();
  }
  if (signalled) throw py::error_already_set();  // the exception the handler raised
  if (error) std::rethrow_exception(error);
  return result;
}

/// Gathers a run's outputs and events in memory, in the column order of channel_info.
class Collector : public lash::Observer {
 public:
  Collector(const lash::Model& model, size_t channels, size_t expected)
      : extrema(model), model_(model), nch_(channels) {
    time.reserve(expected);
    values.reserve(expected * channels);
  }
  void output(double t, const Eigen::VectorXd& y, const lash::Workspace& ws) override {
    time.push_back(t);
    const size_t offset = values.size();
    values.resize(offset + nch_);
    lash::channel_values(model_, ws, y, values.data() + offset);
    extrema.sample(t, values.data() + offset);
    if (time.size() == 1)
      for (int k = 0; k < ws.nc; ++k) initial_contact.push_back(ws.contact[k].in_contact);
  }
  /// The exact extrema between outputs, as `lash run`'s summary.json has them.
  bool wants_steps() const override { return true; }
  void step(double t0, double t1, const Eigen::VectorXd& y, const lash::Workspace& ws,
            lash::StepProbe& probe) override {
    extrema.step(t0, t1, y, ws, probe);
  }
  void event(const lash::ContactEvent& e, const lash::Workspace&) override {
    extrema.restart();
    event_time.push_back(e.t);
    event_joint.push_back(e.clearance);
    event_onset.push_back(e.onset);
    event_velocity.push_back(e.velocity);
  }
  lash::ChannelExtrema extrema;
  std::vector<double> time, values, event_time, event_velocity;
  std::vector<int> event_joint;
  std::vector<bool> event_onset, initial_contact;

 private:
  const lash::Model& model_;
  size_t nch_;
};

py::dict status_dict(const lash::RunStatus& s) {
  py::dict d;
  d["outcome"] = lash::outcome_name(s.outcome);
  d["ok"] = s.ok;
  d["time"] = s.t;
  d["element"] = s.element;
  d["message"] = s.message;
  return d;
}

py::dict run_result_dict(const lash::RunResult& r) {
  py::dict d;
  d["status"] = status_dict(r.status);
  py::dict integ;
  integ["name"] = r.integrator;
  integ["steps"] = r.stats.steps;
  integ["rejected_steps"] = r.stats.rejected_steps;
  integ["rhs_evaluations"] = r.stats.rhs_evaluations;
  integ["events"] = r.stats.events;
  integ["missed_events"] = r.missed_events;
  integ["projections"] = r.stats.projections;
  integ["wall_seconds"] = r.wall_seconds;
  integ["outputs"] = r.outputs;
  d["integrator"] = integ;
  d["max_constraint_violation"] = r.max_constraint_violation;
  d["warnings"] = r.warnings;
  py::dict fs;
  fs["time"] = r.final_state.t;
  fs["y"] = std::vector<double>(r.final_state.y.data(),
                                r.final_state.y.data() + r.final_state.y.size());
  d["final_state"] = fs;
  return d;
}

std::vector<std::string> clearance_joint_names(const lash::Model& m) {
  std::vector<std::string> names;
  for (const auto& j : m.joints)
    if (j.clearance) names.push_back(j.name);
  return names;
}

/// `work` run as run_interruptible runs it, and a failure of the model itself (no consistent
/// initial state) named with its file and the element's line, as `lash run` names it (lash
/// analysis's "joint 'rod_slider': initial assembly failed ..." named no file).
template <class R>
R run_located(const CompiledModel& cm, const std::function<R()>& work, std::atomic<int>& interrupt) {
  try {
    return run_interruptible(work, interrupt);
  } catch (const lash::ModelError&) {
    throw;
  } catch (const lash::IoError&) {
    throw;
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(cm.loaded.located(e.what()));
  }
}

/// lash.simulate's engine: the model's solver settings from t = 0 to end_time.
/// The state a run continues from: a final_state.json (a path, as `lash run --from`) or a
/// Result's final_state dict (time, step, names, y, modes). Checked as `--from` checks it:
/// std::invalid_argument naming what does not fit.
lash::State start_state(const lash::Model& model, const py::object& start) {
  lash::Workspace ws(model);
  lash::State st;
  if (py::isinstance<py::str>(start)) {
    try {
      st = lash::read_state(start.cast<std::string>(), model, ws);
    } catch (const lash::IoError&) {  // cannot be read (no such file): IoError, an OSError
      throw;
    } catch (const std::runtime_error& e) {
      throw std::invalid_argument(e.what());
    }
  } else {
    const py::dict d = start.cast<py::dict>();
    for (const char* key : {"time", "y", "names", "modes"})
      if (!d.contains(key))
        throw std::invalid_argument(std::string("start: a Result's final_state has '") + key +
                                    "'; this one has not");
    // Each entry by name and type (a pybind11 cast error named none, and was taken for the
    // model's own failure).
    auto as = [&](const char* key, const char* what, auto value) {
      try {
        // A bool is an int to pybind11 (True read as 1 s); refused as every other argument does.
        if constexpr (std::is_same_v<decltype(value), double>)
          if (py::isinstance<py::bool_>(d[key])) throw py::cast_error();
        return py::cast<decltype(value)>(d[key]);
      } catch (const py::cast_error&) {
        throw py::type_error(std::string("start: '") + key + "' must be " + what + ", got " +
                             py::str(py::type::of(d[key]).attr("__name__")).cast<std::string>());
      }
    };
    st.t = as("time", "a number (s)", 0.0);
    st.step = d.contains("step") ? as("step", "a number (s)", 0.0) : 0.0;
    if (!std::isfinite(st.step) || st.step < 0)
    {
      char got[32];  // %g, as the CLI says it (std::to_string wrote -1e-9 as -0.000000)
      std::snprintf(got, sizeof got, "%g", st.step);
      throw std::invalid_argument("start: 'step' must be a finite step size >= 0 s, got " +
                                  std::string(got));
    }
    const auto names = as("names", "a list of names", std::vector<std::string>{});
    const auto y = as("y", "a list of numbers", std::vector<double>{});
    const auto expected = lash::state_names(model, ws);
    if (y.size() != names.size())
      throw std::invalid_argument("start: 'y' has " + std::to_string(y.size()) + " entries and "
                                  "'names' " + std::to_string(names.size()));
    if (names != expected) {
      size_t i = 0;
      while (i < names.size() && i < expected.size() && names[i] == expected[i]) ++i;
      throw std::invalid_argument(
          "start: the state does not match the model: entry " + std::to_string(i) + " is '" +
          (i < names.size() ? names[i] : std::string("(nothing)")) + "' in the state but '" +
          (i < expected.size() ? expected[i] : std::string("(nothing)")) + "' in the model");
    }
    st.y = Eigen::Map<const Eigen::VectorXd>(y.data(), static_cast<Eigen::Index>(y.size()));
    const auto modes = as("modes", "a dict of clearance joint names to bool",
                          std::map<std::string, bool>{});
    const std::vector<std::string> joints = clearance_joint_names(model);
    for (const std::string& joint : joints) {
      if (!modes.count(joint))
        throw std::invalid_argument("start: no contact mode for clearance joint '" + joint + "'");
      st.modes.push_back({modes.at(joint)});
    }
    for (const auto& [joint, mode] : modes)
      if (std::find(joints.begin(), joints.end(), joint) == joints.end())
        throw std::invalid_argument("start: '" + joint + "' in 'modes' is no clearance joint of "
                                    "the model");
    st.model = model.name;
  }
  if (const std::string bad = lash::resume_problem(model, ws, st); !bad.empty())
    throw std::invalid_argument("start: " + bad);
  return st;
}

py::dict simulate(const CompiledModel& cm, const py::object& start) {
  const lash::Model& model = cm.loaded.model;
  std::optional<lash::State> from;
  if (!start.is_none()) from = start_state(model, start);
  std::atomic<int> interrupt{0};
  const double n = model.solver.end_time / model.solver.output_interval;
  const size_t expected = n > 0 && n < 1e8 ? static_cast<size_t>(n) + 2 : 16;
  auto collector = std::make_shared<Collector>(model, cm.channels.size(), expected);
  std::function<lash::RunResult()> work = [&] {
    lash::Workspace ws(model);
    lash::RunOptions options;
    options.interrupt = &interrupt;
    options.from = from ? &*from : nullptr;
    return lash::simulate(model, ws, *collector, {}, {}, options);
  };
  const lash::RunResult r = run_located(cm, work, interrupt);
  py::dict d = run_result_dict(r);
  {
    // What y holds, entry by entry, and each clearance joint's contact mode (final_state.json's
    // names and modes).
    py::dict fs = d["final_state"];
    fs["names"] = lash::state_names(model, lash::Workspace(model));
    py::dict modes;
    const std::vector<std::string> names = clearance_joint_names(model);
    for (size_t k = 0; k < names.size() && k < r.final_state.modes.size(); ++k)
      modes[py::str(names[k])] = r.final_state.modes[k].in_contact;
    fs["modes"] = modes;
    fs["step"] = r.final_state.step;
  }
  const auto rows = static_cast<py::ssize_t>(collector->time.size());
  const auto cols = static_cast<py::ssize_t>(cm.channels.size());
  d["time"] = to_numpy(std::move(collector->time));
  d["values"] = to_numpy(std::move(collector->values), {rows, cols});
  py::dict ev;
  ev["time"] = to_numpy(std::move(collector->event_time));
  std::vector<std::string> joints = clearance_joint_names(model);
  py::list joint;
  for (int k : collector->event_joint) joint.append(joints[k]);
  ev["joint"] = joint;
  ev["onset"] = py::array(py::cast(collector->event_onset));
  ev["velocity"] = to_numpy(std::move(collector->event_velocity));
  d["events"] = ev;
  d["initial_contact"] = collector->initial_contact;
  std::vector<double> lo, t_lo, hi, t_hi;
  for (const auto& e : collector->extrema.extrema()) {
    lo.push_back(e.min), t_lo.push_back(e.t_min), hi.push_back(e.max), t_hi.push_back(e.t_max);
  }
  py::dict ext;
  ext["min"] = lo, ext["t_min"] = t_lo, ext["max"] = hi, ext["t_max"] = t_hi;
  d["extrema"] = ext;
  // summary.json's blocks that are not computed from the arrays, as `lash run` writes them
  // (JSON text, read by Result.summary).
  nlohmann::json blocks = {{"solver", lash::solver_summary(model)},
                           {"peaks", lash::peaks_summary(collector->extrema)},
                           {"model_counts", {{"bodies", model.bodies.size()},
                                             {"joints", model.joints.size()},
                                             {"clearance_joints", model.clearance_joint_count()}}}};
  for (const auto& jt : model.joints)
    if (jt.clearance) blocks["clearance_parameters"][jt.name] = lash::clearance_parameters(jt);
  d["summary_blocks"] = blocks.dump();
  return d;
}

lash::AnalysisOptions analysis_options(const py::dict& o, std::atomic<int>* interrupt) {
  lash::AnalysisOptions a;
  for (const auto& [key, value] : o) {
    const auto k = key.cast<std::string>();
    if (k == "ideal_twin") a.ideal_twin = value.cast<bool>();
    else if (k == "lyapunov") a.lyapunov = value.cast<bool>();
    else if (k == "lyapunov_d0") a.lyapunov_d0 = value.cast<double>();
    else if (k == "lyapunov_method") a.lyapunov_method = value.cast<std::string>();
    else if (k == "poincare_driver") a.poincare_driver = value.cast<std::string>();
    else if (k == "section_planes") a.section_planes = value.cast<std::vector<std::string>>();
    else if (k == "discard_periods") a.discard_periods = value.cast<int>();
    else if (k == "fft_channels") a.fft_channels = value.cast<std::vector<std::string>>();
    else if (k == "phase") a.phase = value.cast<std::vector<std::pair<std::string, std::string>>>();
    else if (k == "continuous_contact_time") a.continuous_contact_time = value.cast<double>();
    else if (k == "stats_window") {
      const auto w = value.cast<std::pair<double, double>>();
      a.stats_t0 = w.first, a.stats_t1 = w.second;
    } else if (k == "stats_angle") {
      const auto w = value.cast<std::pair<double, double>>();
      a.stats_angle0 = w.first, a.stats_angle1 = w.second;
    } else
      throw std::invalid_argument("unknown analysis option '" + k + "'");
  }
  a.interrupt = interrupt;
  return a;
}

py::dict verdict_dict(const lash::MotionVerdict& v) {
  py::dict d;
  d["kind"] = v.kind;
  d["evidence"] = v.evidence;
  d["rule"] = v.rule;
  d["lyapunov_exponent"] = v.lyapunov_exponent;
  d["period"] = v.period;
  d["distinct_points"] = v.distinct_points;
  d["sections"] = v.sections;
  d["off_harmonic_peaks"] = v.off_harmonic_peaks;
  return d;
}

py::dict modes_dict(const lash::ModeSummary& m) {
  py::dict d;
  py::list episodes;
  for (const auto& e : m.episodes) episodes.append(py::make_tuple(e.start, e.end, e.continuous));
  d["episodes"] = episodes;
  d["free_flight_share"] = m.free_flight_share;
  d["impact_share"] = m.impact_share;
  d["continuous_share"] = m.continuous_share;
  d["impacts"] = m.impacts;
  d["impact_velocities"] = to_numpy(std::vector<double>(m.impact_velocities));
  return d;
}

/// lash.analysis.analyze's engine: analyze_run with its typed results as dicts of arrays.
py::dict analyze(const CompiledModel& cm, const py::dict& options) {
  std::atomic<int> interrupt{0};
  const lash::AnalysisOptions ao = analysis_options(options, &interrupt);
  lash::check_options(ao);
  std::function<lash::RunAnalysis()> work = [&] { return lash::analyze_run(cm.loaded.model, ao); };
  lash::RunAnalysis ra = run_located(cm, work, interrupt);
  py::dict d;
  d["result"] = run_result_dict(ra.result);
  d["period_driver"] = ra.period_driver;
  d["period"] = ra.period;
  d["verdict"] = verdict_dict(ra.verdict);
  if (ra.poincare) {
    const auto& p = *ra.poincare;
    py::dict pd;
    pd["kind"] = p.kind;
    pd["planes"] = p.planes;
    pd["period"] = p.period;
    pd["discarded_periods"] = p.discarded_periods;
    // One column per coordinate, also with no point (shape (0, 2k)).
    const size_t width = p.points.empty() ? p.coordinates.size() : p.points.front().size();
    std::vector<double> flat;
    for (const auto& pt : p.points) flat.insert(flat.end(), pt.begin(), pt.end());
    pd["points"] = to_numpy(std::move(flat), {static_cast<py::ssize_t>(p.points.size()),
                                              static_cast<py::ssize_t>(width)});
    pd["times"] = to_numpy(std::vector<double>(p.times));
    pd["variables"] = p.variables;
    pd["coordinates"] = p.coordinates;
    pd["distinct"] = p.distinct;
    pd["tolerance"] = p.tolerance;
    d["poincare"] = pd;
  } else {
    d["poincare"] = py::none();
  }
  py::dict spectra;
  for (auto& s : ra.spectra) {
    py::dict sd;
    sd["frequency"] = to_numpy(std::move(s.frequency));
    sd["amplitude"] = to_numpy(std::move(s.amplitude));
    sd["window"] = s.window;
    sd["discarded_time"] = s.discarded_time;
    spectra[py::str(s.channel)] = sd;
  }
  d["spectra"] = spectra;
  py::dict stats;
  for (const auto& s : ra.statistics) {
    py::dict sd;
    sd["samples"] = s.samples;
    sd["min"] = s.min;
    sd["max"] = s.max;
    sd["peak"] = s.peak;
    sd["rms"] = s.rms;
    sd["crest"] = s.crest;
    sd["t0"] = s.t0;
    sd["t1"] = s.t1;
    stats[py::str(s.channel)] = sd;
  }
  d["statistics"] = stats;
  py::dict clearance;
  for (const auto& c : ra.clearance) {
    py::dict cd = modes_dict(c.modes);
    cd["clearance"] = c.clearance;
    cd["continuous_contact_time"] = c.continuous_contact_time;
    clearance[py::str(c.joint)] = cd;
  }
  d["clearance_joints"] = clearance;
  if (ra.lyapunov) {
    const auto& l = *ra.lyapunov;
    py::dict ld;
    ld["method"] = l.method;
    ld["spectrum"] = l.spectrum;
    ld["spectrum_history"] = l.spectrum_history;
    ld["events_mapped"] = l.events_mapped;
    ld["events_unmapped"] = l.events_unmapped;
    ld["estimated"] = l.estimated;
    ld["ok"] = l.ok;
    ld["exponent"] = l.exponent;
    ld["renormalisations"] = l.renormalisations;
    ld["interval"] = l.interval;
    ld["d0"] = l.d0;
    ld["t0"] = l.t0;
    ld["history"] = l.history;
    ld["message"] = l.message;
    d["lyapunov"] = ld;
  } else {
    d["lyapunov"] = py::none();
  }
  if (ra.ideal_twin) {
    py::dict cmp;
    for (const auto& c : ra.ideal_twin->comparison) {
      py::dict cd;
      cd["rms_deviation"] = c.rms_deviation;
      cd["max_deviation"] = c.max_deviation;
      cd["ideal_peak"] = c.ideal_peak;
      if (std::isnan(c.peak_ratio))
        cd["peak_ratio"] = py::none();
      else
        cd["peak_ratio"] = c.peak_ratio;
      cmp[py::str(c.channel)] = cd;
    }
    d["ideal_twin"] = cmp;
  } else {
    d["ideal_twin"] = py::none();
  }
  return d;
}

// --- YAML for models built in code ----------------------------------------------------------

/// A Python string as UTF-8; a lone surrogate ('b\udcff', from bytes decoded with
/// surrogateescape) is a ValueError naming it (pybind11's cast said "Unable to cast Python
/// instance to C++ type").
std::string utf8_of(const py::handle& h) {
  const py::str s = py::reinterpret_borrow<py::str>(h);
  try {
    return s.attr("encode")("utf-8").cast<std::string>();
  } catch (py::error_already_set& e) {
    if (!e.matches(PyExc_UnicodeEncodeError)) throw;
    const long start = e.value().attr("start").cast<long>();
    const std::string ch = py::repr(s[py::int_(start)]).cast<std::string>();
    throw py::value_error("model data: " + py::repr(s).cast<std::string>().substr(0, 200) +
                          " is not valid UTF-8 text (character " + std::to_string(start) + ", " +
                          ch + "); give text without lone surrogates");
  }
}

/// Python data (dict, list, tuple, str, int, float, bool, None) as a YAML node; floats are
/// written as Python's repr, the shortest text that reads back to the same double.
YAML::Node to_yaml(const py::handle& h) {
  if (h.is_none()) return YAML::Node(YAML::NodeType::Null);
  if (py::isinstance<py::bool_>(h)) return YAML::Node(h.cast<bool>() ? "true" : "false");
  if (py::isinstance<py::int_>(h)) return YAML::Node(py::str(h).cast<std::string>());
  if (py::isinstance<py::float_>(h)) return YAML::Node(py::repr(h).cast<std::string>());
  if (py::isinstance<py::str>(h)) return YAML::Node(utf8_of(h));
  if (py::isinstance<py::dict>(h)) {
    YAML::Node n(YAML::NodeType::Map);
    for (const auto& [k, v] : h.cast<py::dict>()) n[utf8_of(py::str(k))] = to_yaml(v);
    return n;
  }
  if (py::isinstance<py::list>(h) || py::isinstance<py::tuple>(h)) {
    YAML::Node n(YAML::NodeType::Sequence);
    bool scalars = true;
    for (const auto& v : h) {
      n.push_back(to_yaml(v));
      scalars = scalars && !py::isinstance<py::dict>(v) && !py::isinstance<py::list>(v);
    }
    if (scalars) n.SetStyle(YAML::EmitterStyle::Flow);  // positions: [0.1, 0]
    return n;
  }
  if (py::hasattr(h, "__float__"))  // NumPy scalars
    return YAML::Node(py::repr(py::float_(py::reinterpret_borrow<py::object>(h))).cast<std::string>());
  throw py::type_error("cannot write a " + py::str(h.get_type()).cast<std::string>() +
                       " into a model file");
}

/// A YAML scalar as the Python value it reads as: int, float, bool, None or str.
py::object scalar(const std::string& s) {
  if (s == "true" || s == "True") return py::bool_(true);
  if (s == "false" || s == "False") return py::bool_(false);
  if (s == "~" || s == "null") return py::none();
  // A whole number only as written canonically ("007", "+5" and "0x1F" stay text: element
  // names, and the loader reads them itself), any size (Python's int, never clamped); a real
  // number only in decimal notation (not "inf", "nan" or hexadecimal).
  static const std::regex integer("-?(0|[1-9][0-9]*)");
  static const std::regex real(
      "[-+]?((\\.[0-9]+|[0-9]+\\.[0-9]*)([eE][-+]?[0-9]+)?|[0-9]+[eE][-+]?[0-9]+)");
  if (std::regex_match(s, integer))
    return py::reinterpret_steal<py::object>(PyLong_FromString(s.c_str(), nullptr, 10));
  if (std::regex_match(s, real)) return py::float_(std::strtod(s.c_str(), nullptr));
  return py::str(s);
}

/// Most values Model.data builds: YAML aliases expand, and a few lines of them ("billion
/// laughs", in a `description` the loader ignores) would expand without bound.
constexpr long kMaxYamlValues = 10'000'000;

py::object from_yaml(const YAML::Node& n, long& values, int depth = 0) {
  if (depth > 1000)
    throw std::length_error("the model nests more than 1000 maps and lists deep; Model.data "
                            "cannot hold it");
  if (++values > kMaxYamlValues)
    throw std::length_error("the model holds more than " + std::to_string(kMaxYamlValues) +
                            " values once its YAML aliases are expanded; Model.data cannot "
                            "hold it (lash.simulate reads the file without expanding them)");
  switch (n.Type()) {
    case YAML::NodeType::Map: {
      py::dict d;
      for (const auto& kv : n)
        d[py::str(kv.first.Scalar())] = from_yaml(kv.second, values, depth + 1);
      return std::move(d);
    }
    case YAML::NodeType::Sequence: {
      py::list l;
      for (const auto& v : n) l.append(from_yaml(v, values, depth + 1));
      return std::move(l);
    }
    case YAML::NodeType::Scalar:
      return n.Tag() == "!" ? py::object(py::str(n.Scalar())) : scalar(n.Scalar());
    default:
      return py::none();
  }
}

// --- argument checks of the model-free analysis functions ----------------------------------
// The C++ functions take their inputs as the study layer builds them (one entry per event in
// every list, times in order); from Python anything may arrive, so the bindings check it and
// raise ValueError (std::invalid_argument) naming the function, the arguments and what they hold.

std::string number(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

/// `function`: `names` (as "times, onset and velocities") must have equal lengths `sizes`.
void check_equal_lengths(const std::string& function, const std::string& names,
                         const std::vector<std::pair<std::string, size_t>>& sizes) {
  for (const auto& [name, size] : sizes)
    if (size != sizes.front().second) {
      std::string got;
      for (const auto& [n, k] : sizes) got += (got.empty() ? "" : ", ") + n + " " + std::to_string(k);
      throw std::invalid_argument(function + ": " + names + " must have the same length, got " + got);
    }
}

/// `function`: `t` must be non-decreasing (and not NaN).
void check_non_decreasing(const std::string& function, const std::string& name,
                          const std::vector<double>& t) {
  for (size_t i = 0; i < t.size(); ++i)
    if (std::isnan(t[i]) || (i > 0 && t[i] < t[i - 1]))
      throw std::invalid_argument(
          function + ": " + name + " must be non-decreasing, got " + name + "[" +
          std::to_string(i) + "] = " + number(t[i]) +
          (i > 0 ? " after " + name + "[" + std::to_string(i - 1) + "] = " + number(t[i - 1]) : ""));
}

/// `s` as Python text: UTF-8, any other byte as \xNN.
py::str text(const std::string& s) {
  return py::reinterpret_steal<py::str>(
      PyUnicode_DecodeUTF8(s.data(), static_cast<Py_ssize_t>(s.size()), "backslashreplace"));
}

}  // namespace

PYBIND11_MODULE(_lash, m) {
  g_main_thread_ident =
      py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>();
  m.doc() = "Lash's C++ engine (use the package lash, which wraps this module).";

  // lash::ModelError → lash.ModelError(ValueError), with every problem as `diagnostics`.
  static py::exception<lash::ModelError> model_error(m, "ModelError", PyExc_ValueError);
  static py::exception<lash::IoError> io_error(m, "IoError", PyExc_OSError);
  // Messages name files, and a file name need not be UTF-8: its other bytes show as \xNN (as
  // lash.Model's messages show them), where decoding as UTF-8 raised UnicodeDecodeError
  // instead of the error.
  py::register_exception_translator([](std::exception_ptr p) {
    const auto raise = [](PyObject* type, const std::string& what) {
      PyErr_SetObject(type, text(what).ptr());
    };
    try {
      if (p) std::rethrow_exception(p);
    } catch (const lash::ModelError& e) {
      py::list diagnostics;
      for (const auto& d : e.diagnostics())
        diagnostics.append(py::make_tuple(text(d.file), d.line, d.column, text(d.element), text(d.message)));
      py::object type = py::reinterpret_borrow<py::object>(model_error.ptr());
      std::string message;  // from the diagnostics: what() ends at a NUL one of them holds
      for (const auto& d : e.diagnostics()) message += d.str() + "\n";
      py::object instance = type(text(message));
      instance.attr("diagnostics") = diagnostics;
      PyErr_SetObject(model_error.ptr(), instance.ptr());
    } catch (const lash::IoError& e) {
      raise(io_error.ptr(), e.what());
    } catch (const py::builtin_exception&) {  // py::type_error, ...: pybind11's translator
      throw;
    } catch (const std::invalid_argument& e) {  // pybind11's own mapping, with the decoding above
      raise(PyExc_ValueError, e.what());
    } catch (const std::range_error& e) {
      raise(PyExc_ValueError, e.what());
    } catch (const std::overflow_error& e) {
      raise(PyExc_OverflowError, e.what());
    } catch (const std::runtime_error& e) {
      raise(PyExc_RuntimeError, e.what());
    }
  });

  py::class_<CompiledModel, std::shared_ptr<CompiledModel>>(m, "CompiledModel",
      "A loaded, validated model (lash::LoadedModel).")
      .def_property_readonly("name", [](const CompiledModel& c) { return c.loaded.model.name; })
      .def_property_readonly("resolved_yaml",
                             [](const CompiledModel& c) { return c.loaded.resolved_yaml; })
      .def_property_readonly("channels", [](const CompiledModel& c) {
        py::list l;
        for (const auto& ch : c.channels) l.append(py::make_tuple(ch.name, ch.unit, ch.description));
        return l;
      })
      .def_property_readonly("bodies", [](const CompiledModel& c) {
        std::vector<std::string> v;
        for (const auto& b : c.loaded.model.bodies) v.push_back(b.name);
        return v;
      })
      .def_property_readonly("joints", [](const CompiledModel& c) {
        std::vector<std::string> v;
        for (const auto& j : c.loaded.model.joints) v.push_back(j.name);
        return v;
      })
      .def_property_readonly("clearance_joints",
                             [](const CompiledModel& c) { return clearance_joint_names(c.loaded.model); })
      .def_property_readonly("end_time", [](const CompiledModel& c) { return c.loaded.model.solver.end_time; })
      .def_property_readonly("output_interval",
                             [](const CompiledModel& c) { return c.loaded.model.solver.output_interval; });

  m.def("load_text",
        [](const std::string& text, const std::string& filename,
           const std::vector<std::string>& overrides) {
          auto c = std::make_shared<CompiledModel>(
              CompiledModel{lash::load_model_text(text, filename, overrides), {}});
          c->channels = lash::channel_info(c->loaded.model);
          return c;
        },
        py::arg("text"), py::arg("filename"), py::arg("overrides") = std::vector<std::string>{},
        "lash::load_model_text: parse, apply overrides, validate; raises ModelError.");
  m.def("read_model_file",
        [](const py::bytes& path, const std::string& name) {
          // The checks of load_model_file (io/files.hpp: a regular file, at most
          // kMaxModelFileBytes) before anything is read, with its messages; they name the file as
          // `name` (the path as UTF-8 text), `path` being the file system's bytes.
          const std::string raw = path;
          auto reason = [&](const std::exception& e) {
            std::string what = e.what();
            if (what.rfind(raw + ": ", 0) == 0) what.erase(0, raw.size() + 2);
            return what;
          };
          try {
            return py::bytes(lash::read_input_file(raw, lash::kMaxModelFileBytes));
          } catch (const std::invalid_argument& e) {
            throw lash::ModelError({{name, 0, 0, "", "cannot read the model file: " + reason(e)}});
          } catch (const lash::IoError& e) {
            throw lash::IoError(name, reason(e));
          }
        },
        py::arg("path"), py::arg("name"),
        "lash::read_input_file with the model file's limits; raises ModelError for what is not a "
        "regular file or is too large (as `lash check`), IoError when it cannot be read.");
  m.def("sweep",
        [](const std::string& study, const std::string& output, int jobs, bool resume) {
          const lash::StudySpec spec = lash::load_study_file(study);
          lash::StudyFolder folder(output, spec, resume);
          const int already = folder.already();
          std::atomic<int> interrupt{0};
          const std::function<std::string()> work = [&] {
            return lash::run_study_threads(folder, spec, jobs, &interrupt, nullptr);
          };
          const std::string error = run_interruptible(work, interrupt);
          if (!error.empty()) {  // (the database's error names it already)
            const std::string db = output + "/study.db";
            throw lash::IoError(db, error.rfind(db + ": ", 0) == 0 ? error.substr(db.size() + 2) : error);
          }
          py::dict d;
          d["total"] = folder.runs().size();
          d["already"] = already;
          d["recorded"] = folder.db().finished().size();
          return d;
        },
        py::arg("study"), py::arg("output"), py::arg("jobs") = 0, py::arg("resume") = false,
        "lash sweep on local threads (lash::StudyFolder + lash::run_study_threads); raises "
        "ModelError for a bad study file, ValueError for a folder that holds another study.");
  m.def("read_study",
        [](const std::string& db) {
          const lash::StudyTable t = lash::read_study(db);
          py::dict d;
          d["name"] = t.name;
          d["total_runs"] = t.total_runs;
          d["parameters"] = t.parameters;
          py::list rows;
          for (const auto& r : t.rows) {
            py::dict row;
            row["run"] = r.run;
            for (size_t p = 0; p < t.parameters.size(); ++p)
              row[py::str(t.parameters[p])] = std::isnan(r.numbers[p]) ? py::object(text(r.values[p]))
                                                                        : py::object(py::float_(r.numbers[p]));
            row["status"] = r.status;
            row["verdict"] = r.verdict;
            row["message"] = text(r.message);  // may name a file whose name is not UTF-8
            row["wall_seconds"] = r.wall_seconds;
            for (const auto& [name, v] : r.metrics) row[py::str(name)] = v;
            rows.append(row);
          }
          d["rows"] = rows;
          py::dict sections;
          for (size_t c = 0; c < t.section_channels.size(); ++c) {
            std::vector<int> run;
            std::vector<double> value;
            for (const auto& [r, v] : t.points[c]) run.push_back(r), value.push_back(v);
            py::dict col;
            col["run"] = run;
            col["value"] = value;
            sections[py::str(t.section_channels[c])] = col;
          }
          d["sections"] = sections;
          return d;
        },
        py::arg("db"), "lash::read_study: a study database as dicts.");
  m.def("assemble",
        [](const CompiledModel& cm) {
          // As `lash check` assembles: its failure and warnings named with the file.
          lash::Workspace ws(cm.loaded.model);
          try {
            lash::initial_state(cm.loaded.model, ws);
          } catch (const std::runtime_error& e) {
            throw std::runtime_error(cm.loaded.located(e.what()));
          }
          std::vector<std::string> warnings;
          for (const std::string& w : ws.warnings) warnings.push_back(cm.loaded.located(w));
          return warnings;
        },
        py::arg("model"),
        "The model assembled at t = 0 as `lash check` does: its warnings (file-located); raises "
        "RuntimeError when no consistent initial state exists.");
  m.def("linear_modes",
        [](const CompiledModel& cm, bool at_equilibrium) {
          std::atomic<int> interrupt{0};  // Ctrl-C: KeyboardInterrupt within one column or step
          std::function<lash::LinearModes()> work = [&] {
            return lash::linear_modes(cm.loaded.model, at_equilibrium, &interrupt);
          };
          const lash::LinearModes lm = run_located(cm, work, interrupt);
          py::dict d;
          d["dof"] = lm.dof;
          py::list modes;
          for (const lash::LinearMode& mode : lm.modes) {
            py::dict md;
            md["frequency"] = mode.frequency;
            md["damping_ratio"] = mode.damping_ratio;
            md["eigenvalue"] = mode.eigenvalue;
            modes.append(md);
          }
          d["modes"] = modes;
          d["real_rates"] = lm.real_rates;
          if (lm.equilibrium) {
            py::dict e;
            e["newton_steps"] = lm.equilibrium->newton_steps;
            e["residual"] = lm.equilibrium->residual;
            e["largest_move"] = lm.equilibrium->largest_move;
            e["largest_move_coordinate"] = lm.equilibrium->largest_move_coordinate;
            e["largest_turn"] = lm.equilibrium->largest_turn;
            e["largest_turn_coordinate"] = lm.equilibrium->largest_turn_coordinate;
            d["equilibrium"] = e;
          } else {
            d["equilibrium"] = py::none();
          }
          return d;
        },
        py::arg("model"), py::arg("at_equilibrium") = false,
        "The mechanism linearised at rest (`lash modes`): dof, modes (frequency Hz, "
        "damping_ratio, eigenvalue), real_rates (1/s), equilibrium (None, or where the static "
        "equilibrium lies).");
  m.def("simulate", &simulate, py::arg("model"), py::arg("start") = py::none(),
        "lash::simulate with an in-memory observer (from `start`: a final_state.json path or a "
        "Result's final_state dict); returns a dict of arrays.");
  m.def("analyze", &analyze, py::arg("model"), py::arg("options") = py::dict(),
        "lash::analyze_run; returns a dict of its typed results.");
  m.def("emit_yaml", [](const py::object& data) {
    YAML::Emitter out;
    out.SetIndent(2);
    out << to_yaml(data);
    return std::string(out.c_str()) + "\n";
  }, py::arg("data"), "Python data as YAML text (yaml-cpp's emitter).");
  m.def("parse_yaml", [](const std::string& text, const std::string& filename) {
          long values = 0;
          py::object data = from_yaml(YAML::Load(text), values);
          // A duplicate key (the parser keeps one value) or a second document (it reads the
          // first): refused as the loader refuses them, not dropped from the data.
          if (auto problems = lash::yaml_structure_problems(text, filename); !problems.empty())
            throw lash::ModelError(problems);
          return data;
        },
        py::arg("text"), py::arg("filename"),
        "YAML text as Python data (yaml-cpp's parser); ModelError on duplicate keys or a second "
        "document.");

  // --- the model-free analysis functions (analysis/) ----------------------------------------
  m.def("amplitude_spectrum",
        [](const std::vector<double>& x, double dt, const std::string& window) {
          lash::Window w;
          if (window == "hann") w = lash::Window::hann;
          else if (window == "rectangular") w = lash::Window::rectangular;
          else throw std::invalid_argument("window must be 'hann' or 'rectangular', got '" + window + "'");
          lash::Spectrum s = lash::amplitude_spectrum(x, dt, w);
          py::dict d;
          d["frequency"] = to_numpy(std::move(s.frequency));
          d["amplitude"] = to_numpy(std::move(s.amplitude));
          d["psd"] = to_numpy(std::move(s.psd));
          d["window"] = s.window;
          return d;
        },
        py::arg("x"), py::arg("dt"), py::arg("window") = "hann");
  // Points of one dimension each (`function` names the caller in the message).
  const auto check_points = [](const std::vector<std::vector<double>>& points, const char* function) {
    for (size_t i = 1; i < points.size(); ++i)
      if (points[i].size() != points[0].size())
        throw std::invalid_argument(
            std::string(function) + ": every point must have the same number of coordinates, got "
            "points[0] with " + std::to_string(points[0].size()) + " and points[" +
            std::to_string(i) + "] with " + std::to_string(points[i].size()));
  };
  m.def("count_distinct",
        [check_points](const std::vector<std::vector<double>>& points, double tol) {
          check_points(points, "count_distinct");
          if (!(tol >= 0))
            throw std::invalid_argument("count_distinct: tol must be a distance >= 0, got " +
                                        number(tol));
          return lash::count_distinct(points, tol);
        },
        py::arg("points"), py::arg("tol"));
  m.def("classify_motion",
        [](double lyapunov, double period, int distinct, int sections, int peaks, double min_end,
           int recurring, double contraction) {
          if (distinct < 0 || sections < 0 || distinct > sections)
            throw std::invalid_argument(
                "classify_motion: expected 0 <= distinct <= sections (distinct points among the "
                "sections taken), got distinct " + std::to_string(distinct) + ", sections " +
                std::to_string(sections));
          if (std::isinf(lyapunov))
            throw std::invalid_argument("classify_motion: lyapunov must be a finite exponent (1/s), or "
                                        "NaN when none was computed; got " + number(lyapunov));
          if (!std::isfinite(min_end))
            throw std::invalid_argument("classify_motion: min_end_time must be a finite time (s), got " +
                                        number(min_end));
          if (recurring < -1 || recurring > distinct)
            throw std::invalid_argument("classify_motion: expected 0 <= recurring <= distinct, or -1 "
                                        "(all recur), got recurring " + std::to_string(recurring) +
                                        ", distinct " + std::to_string(distinct));
          if (contraction < 0 || std::isinf(contraction))
            throw std::invalid_argument("classify_motion: contraction must be a finite ratio >= 0 "
                                        "(section_contraction), or NaN when none was computed; got " +
                                        number(contraction));
          const lash::Verdict v = lash::classify_motion(lyapunov, period, distinct, sections, peaks,
                                                        min_end, std::nan(""), recurring, contraction);
          return py::make_tuple(v.kind, v.evidence);
        },
        py::arg("lyapunov"), py::arg("period"), py::arg("distinct"), py::arg("sections"),
        py::arg("non_harmonic_peaks") = -1, py::arg("min_end_time") = 0.0,
        py::arg("recurring") = -1, py::arg("contraction") = std::nan(""));
  m.def("section_contraction",
        [check_points](const std::vector<std::vector<double>>& points) {
          check_points(points, "section_contraction");
          return lash::section_contraction(points);
        },
        py::arg("points"));
  m.def("verdict_rule", [] { return std::string(lash::verdict_rule()); });
  m.def("contact_modes",
        [](const std::vector<double>& times, const std::vector<bool>& onset,
           const std::vector<double>& velocities, bool in_contact_at_t0, double t0, double t1,
           double continuous_time) {
          check_equal_lengths("contact_modes", "times, onset and velocities (one entry per event)",
                              {{"times", times.size()}, {"onset", onset.size()},
                               {"velocities", velocities.size()}});
          check_non_decreasing("contact_modes", "times", times);
          if (!std::isfinite(t0) || !std::isfinite(t1))
            throw std::invalid_argument("contact_modes: t0 and t1 must be finite times (s), got t0 = " +
                                        number(t0) + ", t1 = " + number(t1));
          if (!(t0 <= t1))
            throw std::invalid_argument("contact_modes: expected t0 <= t1, got t0 = " + number(t0) +
                                        ", t1 = " + number(t1));
          if (!(continuous_time >= 0) || !std::isfinite(continuous_time))
            throw std::invalid_argument("contact_modes: continuous_time must be a finite time >= 0 s, got " +
                                        number(continuous_time));
          return modes_dict(lash::contact_modes(times, onset, velocities, in_contact_at_t0, t0, t1,
                                                continuous_time));
        },
        py::arg("times"), py::arg("onset"), py::arg("velocities"), py::arg("in_contact_at_t0"),
        py::arg("t0"), py::arg("t1"), py::arg("continuous_time"));
  m.def("decimate_min_max",
        [](const std::vector<double>& t, const std::vector<double>& v, long long buckets) {
          check_equal_lengths("decimate_min_max", "t and v", {{"t", t.size()}, {"v", v.size()}});
          if (buckets < 0)
            throw std::invalid_argument("decimate_min_max: buckets must be >= 0, got " +
                                        std::to_string(buckets));
          std::vector<double> to, vo;
          lash::decimate_min_max(t, v, static_cast<size_t>(buckets), to, vo);
          return py::make_tuple(to_numpy(std::move(to)), to_numpy(std::move(vo)));
        },
        py::arg("t"), py::arg("v"), py::arg("buckets"));
}
