// Runs on several threads at once: one const Model per parameter set, shared by the threads that
// simulate it, one Workspace per run. Every output must be bit-identical to the same run done
// serially: nothing is shared between runs but the read-only Model. Also built under
// ThreadSanitizer by `make test-tsan`.
#include <atomic>
#include <string>
#include <thread>
#include <vector>

#include "test_support.hpp"

using namespace lash;
using namespace lash::test;

namespace {

/// Every output row (time and the full state y) and every located event of one run.
class StateRecorder : public Observer {
 public:
  void output(double t, const Eigen::VectorXd& y, const Workspace&) override {
    time.push_back(t);
    rows.emplace_back(y.data(), y.data() + y.size());
  }
  void event(const ContactEvent& e, const Workspace&) override {
    events.push_back({e.t, static_cast<double>(e.clearance), e.onset ? 1.0 : 0.0, e.velocity});
  }
  std::vector<double> time;
  std::vector<std::vector<double>> rows;
  std::vector<std::vector<double>> events;
};

struct Recorded {
  RunResult result;
  StateRecorder rec;
};

Recorded run_once(const Model& model) {
  Recorded r;
  Workspace ws(model);  // this run's own mutable state
  r.result = simulate(model, ws, r.rec);
  return r;
}

/// Eight variants of the Flores slider-crank, 5 ms each (about 40 % of a revolution at
/// 5000 rpm, with impacts): four clearances on dopri5 and four speeds on bdf (SUNDIALS).
std::vector<Model> flores_variants() {
  const std::string base = read_file(example_path("flores_slider_crank.yaml"));
  std::vector<std::vector<std::string>> sets;
  for (const char* c : {"0.1e-3", "0.25e-3", "0.5e-3", "1e-3"})
    sets.push_back({std::string("joints.rod_slider.clearance=") + c});
  for (const char* rpm : {"2000", "3000", "4000", "6000"})
    sets.push_back({std::string("drivers.crank.speed_rpm=") + rpm, "solver.integrator=bdf"});
  std::vector<Model> models;
  for (auto& s : sets) {
    s.push_back("solver.end_time=0.005");
    models.push_back(load_model_text(base, "flores_slider_crank.yaml", s).model);
  }
  return models;
}

void expect_identical(const Recorded& a, const Recorded& b, const std::string& what) {
  EXPECT_EQ(a.result.status.ok, b.result.status.ok) << what;
  EXPECT_EQ(a.result.status.t, b.result.status.t) << what;
  EXPECT_EQ(a.result.stats.steps, b.result.stats.steps) << what;
  EXPECT_EQ(a.result.stats.rejected_steps, b.result.stats.rejected_steps) << what;
  EXPECT_EQ(a.result.stats.rhs_evaluations, b.result.stats.rhs_evaluations) << what;
  EXPECT_EQ(a.result.max_constraint_violation, b.result.max_constraint_violation) << what;
  // Exact == on every double (std::vector's operator==).
  EXPECT_EQ(a.rec.time, b.rec.time) << what;
  ASSERT_EQ(a.rec.rows.size(), b.rec.rows.size()) << what;
  size_t differing = 0;
  for (size_t i = 0; i < a.rec.rows.size(); ++i) differing += a.rec.rows[i] != b.rec.rows[i];
  EXPECT_EQ(differing, 0u) << what << ": rows whose state y differs";
  EXPECT_EQ(a.rec.events, b.rec.events) << what;
}

}  // namespace

TEST(Threads, ConcurrentRunsAreBitIdenticalToSerialOnes) {
  const std::vector<Model> models = flores_variants();  // shared, read-only, by every thread

  // Serial reference.
  std::vector<Recorded> serial;
  for (const Model& m : models) serial.push_back(run_once(m));
  for (size_t i = 0; i < serial.size(); ++i) {
    ASSERT_TRUE(serial[i].result.status.ok) << i << ": " << serial[i].result.status.message;
    ASSERT_EQ(serial[i].rec.time.size(), 501u) << i;  // 0 … 5 ms every 10 µs
    EXPECT_GT(serial[i].rec.events.size(), 0u) << i << ": no impacts, a weak test";
  }
  // The variants differ, so a mix-up between runs would show.
  EXPECT_NE(serial[0].rec.rows.back(), serial[1].rec.rows.back());

  // The same runs on 4 threads, each model twice, the two copies started together so that two
  // threads read the same Model at once.
  constexpr int kThreads = 4;
  const size_t n_jobs = 2 * models.size();
  std::vector<Recorded> parallel(n_jobs);
  std::atomic<size_t> next{0};
  std::vector<std::thread> threads;
  for (int k = 0; k < kThreads; ++k)
    threads.emplace_back([&] {
      for (size_t j; (j = next.fetch_add(1)) < n_jobs;) parallel[j] = run_once(models[j / 2]);
    });
  for (auto& t : threads) t.join();

  for (size_t j = 0; j < n_jobs; ++j)
    expect_identical(parallel[j], serial[j / 2], "variant " + std::to_string(j / 2) + ", copy " +
                                                     std::to_string(j % 2));
}

TEST(Threads, DrivenRunsDifferentiateTheirMotionsConcurrently) {
  // Each Workspace differentiates its drivers' expressions with GiNaC when it is built (not
  // thread-safe itself, serialised inside symbolic_derivatives.cpp); the runs must not notice.
  const std::string base = R"Y(
gravity: [0, -9.81]
bodies:
  crank: {mass: 1.5, inertia: 2e-3, position: [0.05, 0], markers: {P: [-0.05, 0]}}
  rotor: {mass: 1.0, inertia: 1e-3, position: [1, 0]}
joints:
  pivot: {type: revolute, journal: crank.P, bearing: ground}
  shaft: {type: revolute, journal: rotor, bearing: ground.R}
ground: {markers: {R: [1, 0]}}
drivers:
  wobble: {joint: pivot, motion: "0.5*sin(20*time) + step5(time, 0, 0, 0.02, 0.3)"}
  spin: {joint: shaft, speed: "100*step(time, 0, 0, 0.01, 1)*exp(-time)"}
solver: {end_time: 0.05, output_interval: 1e-4}
)Y";
  std::vector<Model> models;
  for (const char* amplitude : {"0.5", "0.25", "0.1", "0.05"}) {
    std::string yaml = base;
    yaml.replace(yaml.find("0.5*sin"), 3, amplitude);
    models.push_back(load_model_text(yaml, "driven.yaml").model);
  }
  std::vector<Recorded> serial;
  for (const Model& m : models) serial.push_back(run_once(m));
  for (const Recorded& r : serial) ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  EXPECT_NE(serial[0].rec.rows.back(), serial[1].rec.rows.back());

  constexpr int kThreads = 4;
  const size_t n_jobs = 3 * models.size();
  std::vector<Recorded> parallel(n_jobs);
  std::atomic<size_t> next{0};
  std::vector<std::thread> threads;
  for (int k = 0; k < kThreads; ++k)
    threads.emplace_back([&] {
      for (size_t j; (j = next.fetch_add(1)) < n_jobs;) parallel[j] = run_once(models[j % models.size()]);
    });
  for (auto& t : threads) t.join();
  for (size_t j = 0; j < n_jobs; ++j)
    expect_identical(parallel[j], serial[j % models.size()], "driven variant " + std::to_string(j));
}
