#include "io/results_writer.hpp"

#include "io/number_format.hpp"
#include "io/state_file.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace lash {

nlohmann::json solver_summary(const Model& model) {
  const SolverSettings& s = model.solver;
  return nlohmann::json{{"integrator", s.integrator == IntegratorKind::bdf ? "bdf" : "dopri5"},
                 {"rtol", s.rtol},
                 {"atol", s.atol},
                 {"end_time", s.end_time},
                 {"output_interval", s.output_interval},
                 {"max_step", s.max_step},
                 {"initial_state", s.initial_state == InitialStateRule::ideal ? "ideal" : "given"},
                 {"baumgarte_alpha", s.baumgarte_alpha},
                 {"baumgarte_beta", s.baumgarte_beta}};
}

nlohmann::json clearance_parameters(const Joint& joint) {
  return {{"clearance", joint.clearance->clearance},
          {"stiffness", joint.clearance->contact.stiffness},
          {"normal_law", std::string(normal_law_name(joint.clearance->normal_law))},
          {"friction_law", std::string(friction_law_name(joint.clearance->friction_law))}};
}

nlohmann::json peaks_summary(const ChannelExtrema& extrema) {
  return {{"method",
           "tracked at every output, accepted integrator step and event; turning points "
           "between steps refined by Brent's method on the dense output"},
          {"refinements", extrema.refinements()},
          {"evaluations", extrema.evaluations()}};
}

const std::vector<std::string>& ResultsWriter::run_files() {
  // summary.json first: from here on, no summary of the earlier run stands beside new rows.
  static const std::vector<std::string> files = {
      "summary.json", "final_state.json", "timeseries.csv", "timeseries.h5", "events.csv",
      "model_resolved.yaml",
      "analysis.json", "report_data.json", "report.html", "figures", "figures.log"};
  return files;
}

ResultsWriter::ResultsWriter(const Model& model, const std::string& folder,
                             const std::string& resolved_yaml, std::vector<std::string> overrides,
                             std::string from, OutputSettings output)
    : model_(model), folder_(folder), resolved_yaml_(resolved_yaml),
      overrides_(std::move(overrides)), from_(std::move(from)), output_(std::move(output)),
      extrema_(model) {
  extrema_.keep_last_step();  // a write error stops the run at an output its last step passed
  // A selection that matches nothing, or a format this build lacks, is refused before the
  // folder is touched.
  channels_ = channel_info(model);
  selected_ = select_channels(channels_, output_.channels);
  if (output_.format == OutputFormat::hdf5 && !hdf5_available())
    throw std::invalid_argument("--format hdf5: this lash was built without HDF5 (libhdf5-dev)");
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec) throw IoError(folder, "cannot create the output folder: " + ec.message());
  // A study's folder (lash sweep) is not a run's: its report would be the study's, and a
  // sweep --resume would find a run's files among its own.
  if (std::filesystem::exists(folder + "/study.db", ec))
    throw std::invalid_argument(folder + "/study.db: this folder holds a study of `lash sweep`; "
                                         "a run's results would mix with it: choose another "
                                         "output folder");
  // All or nothing: a folder with something in the way is refused before anything is removed.
  for (const bool check_only : {true, false})
    for (const auto& f : run_files())
      remove_earlier_output(folder + "/" + f, f == "figures" ? kFiguresMarker : "", check_only);
  write_file_atomic(folder + "/model_resolved.yaml", resolved_yaml_ + "\n");
  ev_ = RowFile(folder + "/events.csv");
  values_.assign(channels_.size(), 0.0);
  joints_.assign(model.clearance_joint_count(), JointStats{});
  if (output_.format == OutputFormat::hdf5) {
    std::vector<ChannelInfo> cols;
    for (std::size_t i : selected_) cols.push_back(channels_[i]);
    h5_ = std::make_unique<Hdf5Series>(folder + "/timeseries.h5", cols);
    picked_.assign(selected_.size(), 0.0);
  } else {
    ts_ = RowFile(folder + "/timeseries.csv");
    std::string header = "time";
    for (std::size_t i : selected_) header += "," + channels_[i].name;
    write_rows(ts_, header + "\n");
  }
  write_rows(ev_, "time,joint,event,velocity\n");
}

void ResultsWriter::write_rows(RowFile& file, std::string_view rows) {
  if (!file.is_open()) return;  // this file failed earlier
  try {
    file.append(rows);
  } catch (const IoError& e) {
    if (write_error_.empty()) write_error_ = e.what();
    file.abandon();
  }
}

void ResultsWriter::flush_events_with_series() {
  const long long out = h5_ ? h5_->rows_written() : ts_.rows_written();
  if (out == series_rows_out_ || !ev_.is_open()) return;
  series_rows_out_ = out;
  try {
    ev_.flush();
  } catch (const IoError& e) {
    if (write_error_.empty()) write_error_ = e.what();
    ev_.abandon();
  }
}

void ResultsWriter::write_series_row(double t) {
  if (h5_) {
    if (!h5_->is_open()) return;  // failed earlier
    for (std::size_t k = 0; k < selected_.size(); ++k) picked_[k] = values_[selected_[k]];
    try {
      h5_->append(t, picked_.data());
    } catch (const IoError& e) {
      if (write_error_.empty()) write_error_ = e.what();
      h5_->abandon();
    }
    return;
  }
  // One buffered row, one write; format_g9 (%.9g, identical bytes) is 2-4x faster than
  // std::to_chars, itself ~1.6x faster than fmt: formatting dominated the CSV's cost.
  const std::size_t room = (selected_.size() + 1) * (kG9MaxChars + 1) + 1;
  if (row_.size() < room) row_.resize(room);
  char* const begin = row_.data();
  char* p = format_g9(t, begin);
  for (std::size_t i : selected_) {
    *p++ = ',';
    p = format_g9(values_[i], p);
  }
  *p++ = '\n';
  write_rows(ts_, std::string_view(begin, static_cast<std::size_t>(p - begin)));
}

void ResultsWriter::output(double t, const Eigen::VectorXd& y, const Workspace& ws) {
  if (!write_error_.empty()) return;  // the run stops at this output
  channel_values(model_, ws, y, values_.data());
  write_series_row(t);
  flush_events_with_series();
  // Peaks of every channel, selected for the time series or not (summary.json), exact between
  // outputs (core/extrema.hpp).
  extrema_.sample(t, values_.data());
  if (rows_ == 0) {
    t_first_ = t;
    for (int k = 0; k < ws.nc; ++k)
      if (ws.contact[k].in_contact) joints_[k].in_contact = true, joints_[k].onset_time = t;
  }
  ++rows_;
  t_last_ = t;
}

void ResultsWriter::event(const ContactEvent& e, const Workspace& ws) {
  const std::string& name = model_.joints[ws.clearance_joints[e.clearance]].name;
  write_rows(ev_, fmt::format("{:.12g},{},{},{:.9g}\n", e.t, name,
                              e.onset ? "onset" : "separation", e.velocity));
  extrema_.restart();  // the right-hand side changes here
  JointStats& s = joints_[e.clearance];
  if (e.onset) {
    ++s.impacts;
    s.in_contact = true;
    s.onset_time = e.t;
    s.max_impact_velocity = std::max(s.max_impact_velocity, e.velocity);
  } else {
    ++s.separations;
    if (s.in_contact) s.contact_time += e.t - s.onset_time;
    s.in_contact = false;
  }
}

void ResultsWriter::close_files(const RunResult& r) {
  if (files_closed_) return;
  files_closed_ = true;
  for (RowFile* f : {&ts_, &ev_}) {  // each keeps its whole rows, whatever the other's fate
    try {
      f->close();
    } catch (const IoError& e) {
      if (write_error_.empty()) write_error_ = e.what();
    }
  }
  if (h5_) {
    try {
      h5_->close();
    } catch (const IoError& e) {
      if (write_error_.empty()) write_error_ = e.what();
      h5_->abandon();
    }
  }
  if (r.final_state.y.size() > 0) {
    try {
      write_state(folder_ + "/final_state.json", model_, Workspace(model_), r.final_state);
    } catch (const std::exception& e) {
      if (write_error_.empty()) write_error_ = e.what();
    }
  }
}

RunStatus ResultsWriter::finish(const RunResult& r) {
  using nlohmann::json;
  close_files(r);
  RunStatus status = r.status;
  // A run stopped at an output its last step had passed (a write error, an interruption): the
  // extrema are over the run up to where it stopped, as the files and final_state.json are.
  extrema_.end_at(r.status.t);
  // Rows of the time series on disk (the CSV's header is not one), and the last one's time.
  const long long series_rows = h5_ ? h5_->rows_written() : std::max(0LL, ts_.rows_written() - 1);
  auto last_time_on_disk = [&] {
    if (h5_) return h5_->last_time();
    if (write_error_.empty()) return series_rows > 0 ? t_last_ : std::nan("");
    return lash::last_row_time(ts_.path());  // not every row computed reached the file
  };
  last_row_time_ = last_time_on_disk();
  auto time_or_null = [](double t) { return std::isnan(t) ? nlohmann::json() : nlohmann::json(t); };
  if (!write_error_.empty() && status.outcome != RunOutcome::write_error) {
    // The run itself may have ended well or not; the results on disk are incomplete either way.
    const std::string before = status.ok ? std::string() : " (the run had stopped: " + status.message + ")";
    status.ok = false;
    status.outcome = RunOutcome::write_error;
    status.message = "results could not be written: " + write_error_ + before;
  }
  json j;
  j["status"] = {{"outcome", outcome_name(status.outcome)},
                 {"ok", status.ok},
                 {"time", status.t},
                 {"element", status.element},
                 {"message", status.message}};
  const double span = t_last_ - t_first_;
  json channels = json::object();
  for (size_t i = 0; i < channels_.size(); ++i) {
    const ChannelExtremum& p = extrema_.extrema()[i];
    json& c = channels[channels_[i].name];
    c = {{"unit", channels_[i].unit}, {"description", channels_[i].description}};
    if (p.seen) {
      c.update({{"min", p.min},
                {"t_min", p.t_min},
                {"max", p.max},
                {"t_max", p.t_max},
                {"peak", std::max(std::abs(p.min), std::abs(p.max))}});
    } else {  // no finite value (a run that failed at its first output): not 0
      for (const char* k : {"min", "t_min", "max", "t_max", "peak"}) c[k] = nullptr;
    }
    if (p.non_finite) c["non_finite"] = true;
  }
  j["channels"] = channels;
  j["peaks"] = peaks_summary(extrema_);
  json cj = json::object();
  int c = 0;
  for (const auto& jt : model_.joints) {
    if (!jt.clearance) continue;
    JointStats s = joints_[c++];
    if (s.in_contact) s.contact_time += t_last_ - s.onset_time;
    const double contact_share = span > 0 ? s.contact_time / span : 0.0;
    cj[jt.name] = {{"impacts", s.impacts},
                   {"separations", s.separations},
                   {"contact_share", contact_share},
                   {"free_flight_share", 1.0 - contact_share},
                   {"max_impact_velocity", s.max_impact_velocity}};
    cj[jt.name].update(clearance_parameters(jt));
  }
  j["clearance_joints"] = cj;
  j["integrator"] = {{"name", r.integrator},
                     {"steps", r.stats.steps},
                     {"rejected_steps", r.stats.rejected_steps},
                     {"rhs_evaluations", r.stats.rhs_evaluations},
                     {"events", r.stats.events},
                     {"projections", r.stats.projections},
                     {"wall_seconds", r.wall_seconds},
                     {"outputs", series_rows}};
  json written = json::array();
  for (std::size_t i : selected_) written.push_back(channels_[i].name);
  j["output"] = {{"format", h5_ ? "hdf5" : "csv"},
                 {"file", h5_ ? "timeseries.h5" : "timeseries.csv"},
                 {"rows", series_rows},
                 {"last_time", time_or_null(last_row_time_)},
                 {"patterns", output_.channels},
                 {"channels", written}};
  j["max_constraint_violation"] = r.max_constraint_violation;
  j["start"] = {{"time", t_first_}, {"from", from_.empty() ? nlohmann::json() : json(from_)}};
  j["integrator"]["missed_events"] = r.missed_events;
  j["model"] = {{"name", model_.name},
                {"file", model_.source},
                {"overrides", overrides_},
                {"bodies", model_.bodies.size()},
                {"joints", model_.joints.size()},
                {"clearance_joints", model_.clearance_joint_count()},
                {"resolved", resolved_yaml_}};
  j["solver"] = solver_summary(model_);
  for (const auto& [key, value] : extra_.items()) j[key] = value;
  auto text = [&] { return j.dump(2, ' ', false, json::error_handler_t::replace) + "\n"; };
  try {
    write_file_atomic(folder_ + "/summary.json", text());
  } catch (const IoError& e) {
    // Rows are given up only from a CSV, and only for room on a full disk.
    if (write_error_.empty() || h5_ || !(e.error_number() == ENOSPC || e.error_number() == EDQUOT))
      throw;
    // The disk is full of rows: give up the last of them so the summary saying what the others
    // are fits (twice its size, for the temporary copy and the file system's blocks).
    const long long dropped = drop_last_rows(folder_ + "/timeseries.csv", 2 * text().size() + 8192);
    j["integrator"]["outputs"] = std::max(0LL, ts_.rows_written() - 1 - dropped);
    j["output"]["rows"] = j["integrator"]["outputs"];
    last_row_time_ = lash::last_row_time(folder_ + "/timeseries.csv");
    j["output"]["last_time"] = time_or_null(last_row_time_);
    j["status"]["message"] = status.message + "; the last " + std::to_string(dropped) +
                             " rows of timeseries.csv were removed to make room for this summary";
    status.message = j["status"]["message"].get<std::string>();
    write_file_atomic(folder_ + "/summary.json", text());
  }
  return status;
}

}  // namespace lash
