// The model loader: a catalogue of bad models, each message asserted with its line and column.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "io/model_loader.hpp"
#include "test_support.hpp"

using namespace lash;

namespace {

const char* kGood = R"Y(name: t
gravity: [0, -9.81]
ground:
  markers: {O: [0, 0]}
bodies:
  crank:
    mass: 0.3
    inertia: 1.0e-4
    position: [0.025, 0]
    markers: {O: [-0.025, 0], A: [0.025, 0]}
  rod:
    mass: 0.21
    inertia: 2.5e-4
    position: [0.11, 0]
    markers: {A: [-0.06, 0], B: [0.06, 0]}
  slider: {mass: 0.14, inertia: 1.0e-4, position: [0.17, 0]}
joints:
  pivot: {type: revolute, journal: crank.O, bearing: ground.O}
  pin: {type: revolute, journal: crank.A, bearing: rod.A}
  gudgeon:
    type: revolute
    journal: rod.B
    bearing: slider
    clearance: 0.5e-3
    journal_radius: 9.5e-3
    material: {youngs_modulus: 207e9, poisson_ratio: 0.3}
    normal_law: lankarani_nikravesh
    restitution: 0.9
  guide: {type: translational, guide: ground.O, slider: slider, axis: [1, 0]}
drivers:
  motor: {joint: pivot, speed_rpm: 5000}
solver:
  end_time: 0.024
  output_interval: 1.0e-5
)Y";

/// Replaces the first occurrence of `from` in the good model.
std::string with(const std::string& from, const std::string& to) {
  std::string s = kGood;
  const auto p = s.find(from);
  EXPECT_NE(p, std::string::npos) << from;
  return s.replace(p, from.size(), to);
}

std::vector<Diagnostic> problems(const std::string& yaml,
                                 const std::vector<std::string>& overrides = {}) {
  try {
    load_model_text(yaml, "model.yaml", overrides);
  } catch (const ModelError& e) {
    return e.diagnostics();
  }
  return {};
}

}  // namespace

TEST(ModelLoader, GoodModelLoadsInSIUnits) {
  const Model m = load_model_text(kGood, "model.yaml").model;
  ASSERT_EQ(m.bodies.size(), 3u);
  ASSERT_EQ(m.joints.size(), 4u);
  EXPECT_EQ(m.clearance_joint_count(), 1);
  const Clearance& c = *m.joints[2].clearance;
  EXPECT_DOUBLE_EQ(c.bearing_radius, 10e-3);
  EXPECT_NEAR(c.contact.stiffness / 6.610e10, 1.0, 5e-4);
  EXPECT_NEAR(m.drivers[0].speed, 523.599, 1e-3);  // rpm → rad/s
  EXPECT_EQ(m.joints[2].a.body, 1);
  EXPECT_EQ(m.joints[2].b.body, 2);
}

TEST(ModelLoader, NegativeClearanceNamesJointLineAndValue) {
  const auto d = problems(with("clearance: 0.5e-3", "clearance: -0.001"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:24:16: joint 'gudgeon': clearance must be >= 0, got -0.001");
}

TEST(ModelLoader, ClearanceLostInTheJournalRadiusIsRejected) {
  // 8.5e63 m + 0.5 mm is 8.5e63 m in double precision: no gap left to fly in.
  const auto d = problems(with("journal_radius: 9.5e-3", "journal_radius: 8.5e63"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_NE(d[0].str().find("joint 'gudgeon': clearance 0.0005 m is lost in journal radius"),
            std::string::npos)
      << d[0].str();
  // A clearance set by an override is said to be one (it pointed at the joint's line in the
  // file, whose own clearance is fine; a study's value then looked like the model's).
  const auto o = problems(kGood, {"joints.gudgeon.clearance=1e-20"});
  ASSERT_EQ(o.size(), 1u);
  EXPECT_EQ(o[0].line, 0) << o[0].str();
  EXPECT_NE(o[0].str().find("is lost in journal radius"), std::string::npos) << o[0].str();
  EXPECT_NE(o[0].str().find("(value set with --set)"), std::string::npos) << o[0].str();
}

TEST(ModelLoader, UnknownKeySuggestsTheNearestOne) {
  const auto d = problems(with("clearance: 0.5e-3", "clearence: 0.5e-3"));
  ASSERT_GE(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:24:5: joint 'gudgeon': unknown key 'clearence', did you mean 'clearance'?");
}

TEST(ModelLoader, LuGreFrictionNeedsItsParameters) {
  const auto ok = with("    restitution: 0.9\n",
                       "    restitution: 0.9\n    friction: {law: lugre, sigma0: 1e5, sigma1: 316, "
                       "mu_static: 0.15, mu_dynamic: 0.1, v_stribeck: 0.001}\n");
  EXPECT_TRUE(problems(ok).empty());
  const auto d = problems(with(
      "    restitution: 0.9\n",
      "    restitution: 0.9\n    friction: {law: lugre, sigma0: 1e5, sigma1: 316, "
      "mu_static: 0.05, mu_dynamic: 0.1}\n"));
  ASSERT_EQ(d.size(), 2u);
  EXPECT_NE(d[0].str().find("missing required key 'v_stribeck'"), std::string::npos) << d[0].str();
  EXPECT_NE(d[1].str().find("mu_static must be >= mu_dynamic, got 0.05 < 0.1"), std::string::npos)
      << d[1].str();
}

TEST(ModelLoader, EveryProblemIsListedAtOnce) {
  std::string s = with("mass: 0.3", "mass: heavy");
  s.replace(s.find("bearing: rod.A"), 14, "bearing: rood.A");
  s.replace(s.find("speed_rpm: 5000"), 15, "speed_rpm: 5000, speed: 3");
  const auto d = problems(s);
  ASSERT_EQ(d.size(), 3u);
  EXPECT_EQ(d[0].str(), "model.yaml:7:11: body 'crank': 'mass' must be a number (kg), got 'heavy'");
  EXPECT_EQ(d[1].str(),
            "model.yaml:19:52: joint 'pin': unknown body 'rood' in 'rood.A', expected one of: "
            "ground, crank, rod, slider (did you mean 'rod'?)");
  EXPECT_EQ(d[2].line, 31);
  EXPECT_NE(d[2].message.find("exactly one of speed_rpm, speed"), std::string::npos);
}

TEST(ModelLoader, UnknownMarkerListsTheBodysMarkers) {
  const auto d = problems(with("journal: rod.B", "journal: rod.C"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].line, 22);
  EXPECT_EQ(d[0].message, "unknown marker 'C' on body 'rod', expected one of: A, B");
}

TEST(ModelLoader, UnknownLawsAndTypes) {
  auto d = problems(with("normal_law: lankarani_nikravesh", "normal_law: lankarani"));
  ASSERT_EQ(d.size(), 1u) << d[0].str() << "\n" << d[1].str();
  EXPECT_NE(d[0].message.find("unknown normal_law 'lankarani', expected one of: hertz, "
                              "hunt_crossley, lankarani_nikravesh, flores, impact"),
            std::string::npos);
  d = problems(with("type: translational", "type: prismatc"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:29:17: joint 'guide': unknown joint type 'prismatc', expected "
                        "one of: revolute, translational, fixed, distance");
}

TEST(ModelLoader, MissingRequiredKeys) {
  auto d = problems(with("    mass: 0.21\n", ""));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:12:5: body 'rod': missing required key 'mass' (kg)");
  d = problems(with("  end_time: 0.024\n", ""));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].element, "solver");
  EXPECT_NE(d[0].message.find("missing required key 'end_time'"), std::string::npos);
}

TEST(ModelLoader, AKeyLeftEmptyIsAnErrorAtTheKeyNotItsDefault) {
  // An empty value (`key:` with nothing after it, or ~) was taken for a missing key: a
  // forgotten clearance made the joint ideal and a forgotten stiffness a spring of 0 N/m, and
  // the runs completed without a word.
  auto d = problems(with("    clearance: 0.5e-3\n", "    clearance:\n"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(),
            "model.yaml:24:5: joint 'gudgeon': 'clearance' must be a number (m), got an empty value");
  // At the key, not at the next token (the value's own position, two lines on).
  d = problems(with("    mass: 0.21\n", "    mass:\n"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:12:5: body 'rod': 'mass' must be a number (kg), got an empty value");
  d = problems(with("gravity: [0, -9.81]", "gravity: ~"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(),
            "model.yaml:2:1: model: 'gravity' must be a pair of finite numbers [x, y] (m/s²), got an empty value");
  d = problems(with("speed_rpm: 5000", "speed_rpm: "));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(),
            "model.yaml:31:25: driver 'motor': 'speed_rpm' must be a number (rev/min), got an empty value");
  // A map left empty: said once, not again as what it would have given.
  d = problems(with("    material: {youngs_modulus: 207e9, poisson_ratio: 0.3}", "    material:"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:26:5: joint 'gudgeon': 'material' must be a map of keys (key: "
                        "value), got an empty value");
  d = problems(with("  output_interval: 1.0e-5\n", "  output_interval: 1.0e-5\n  baumgarte:\n"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:35:3: solver: 'baumgarte' must be a map of keys (key: "
                        "value), got an empty value");
  // In clearance_defaults, said at the default's key.
  d = problems(with("joints:\n", "clearance_defaults:\n  min_impact_velocity:\njoints:\n"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:18:3: joint 'gudgeon': 'min_impact_velocity' must be a number (m/s), got an empty value");
  // A key the element's law does not read: a material beside the contact stiffness.
  d = problems(with("    material: {youngs_modulus: 207e9, poisson_ratio: 0.3}",
                    "    stiffness: 6.6e10\n    material:"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:27:5: joints.gudgeon: 'material' has an empty value: give one, "
                        "or leave the key out for its default");
  // An empty body name, at its key.
  d = problems(with("  motor: {joint: pivot, speed_rpm: 5000}", "  motor: {body: , speed_rpm: 5000}"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:31:11: driver 'motor': 'body' must be a body name, got an empty value");
  // Collections may be empty: a section whose entries are all commented out.
  EXPECT_TRUE(problems(std::string(kGood) + "loads:\n  # spring: {type: spring_damper}\nsensors:\n").empty());
}

TEST(ModelLoader, ImpactLawNeedsItsDampingParameters) {
  const auto d = problems(with("normal_law: lankarani_nikravesh", "normal_law: impact"));
  ASSERT_EQ(d.size(), 2u);
  EXPECT_NE(d[0].message.find("damping_max"), std::string::npos);
  EXPECT_NE(d[1].message.find("damping_depth"), std::string::npos);
}

TEST(ModelLoader, BadExpressionIsReportedWhereItIsWritten) {
  const auto d = problems(with("speed_rpm: 5000", "motion: \"step5(time, 0, 0, 0.085)\""));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].line, 31);
  EXPECT_NE(d[0].message.find("bad expression"), std::string::npos);
}

TEST(ModelLoader, InvalidYamlPointsAtTheSyntaxError) {
  const auto d = problems("bodies:\n  a: {mass: 1\n");
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].file, "model.yaml");
  EXPECT_GT(d[0].line, 0);
  EXPECT_NE(d[0].message.find("not valid YAML"), std::string::npos);
  // A tab in a line's indentation: the parser's "end of map not found" is reported at the tab.
  // A comment indented with a tab is not taken for it.
  const auto t = problems(with("  pin: {type", "\t# a note\n\tpin: {type"));
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].str(), "model.yaml:20:1: not valid YAML: a tab in the indentation (YAML indents "
                        "with spaces only; the parser said 'end of map not found' at 20:2)");
}

TEST(ModelLoader, DriverOnAClearanceJointIsRejected) {
  const auto d = problems(with("joint: pivot", "joint: gudgeon"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_NE(d[0].message.find("is a clearance joint"), std::string::npos);
}

TEST(Overrides, ChangeValuesAndSwitchJointsToClearance) {
  auto m = load_model_text(kGood, "model.yaml",
                           {"joints.gudgeon.clearance=0.25e-3", "drivers.motor.speed_rpm=3000",
                            "joints.pin.clearance=1e-4", "joints.pin.journal_radius=5e-3",
                            "joints.pin.stiffness=1e9", "joints.pin.normal_law=hertz"})
               .model;
  EXPECT_DOUBLE_EQ(m.joints[2].clearance->clearance, 0.25e-3);
  EXPECT_NEAR(m.drivers[0].speed, 3000 * 2 * M_PI / 60, 1e-9);
  ASSERT_TRUE(m.joints[1].clearance.has_value());
  EXPECT_DOUBLE_EQ(m.joints[1].clearance->bearing_radius, 5.1e-3);
  EXPECT_DOUBLE_EQ(m.joints[1].clearance->contact.stiffness, 1e9);
  // A parent that does not exist is an error, not a silent new branch.
  const auto d = problems(kGood, {"joints.pin.material.youngs_modulus=1e11"});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "--set joints.pin.material.youngs_modulus: no 'joints.pin.material' in the model");
}

TEST(Overrides, AValueReachedThroughAnAliasChangesThereOnly) {
  // An anchor's node and its aliases are one node: written in place, --set b.position moved
  // body a too, and a bearing material shared through *steel changed the journal's and the
  // defaults' as well.
  const std::string text =
      "name: m\n"
      "bodies:\n"
      "  a: &body {mass: 1, inertia: 1, position: [0, 0]}\n"
      "  b: *body\n"
      "  c: {mass: &m 2, inertia: *m, position: [3, 0]}\n"
      "solver: {end_time: 0.01}\n";
  const auto lm = load_model_text(text, "m.yaml", {"bodies.b.position=[1, 0]", "bodies.c.mass=5"});
  ASSERT_EQ(lm.model.bodies.size(), 3u);
  EXPECT_EQ(lm.model.bodies[0].r0, Vec2(0, 0));
  EXPECT_EQ(lm.model.bodies[1].r0, Vec2(1, 0));
  EXPECT_EQ(lm.model.bodies[1].mass, 1.0);
  EXPECT_EQ(lm.model.bodies[2].mass, 5.0);
  EXPECT_EQ(lm.model.bodies[2].inertia, 2.0);  // the alias of the mass it was
  // The model as run shows each body with its own values, in the file's order.
  EXPECT_EQ(load_model_text(lm.resolved_yaml, "again.yaml").resolved_yaml, lm.resolved_yaml);
  const auto again = load_model_text(lm.resolved_yaml, "again.yaml").model;
  EXPECT_EQ(again.bodies[0].name, "a");
  EXPECT_EQ(again.bodies[0].r0, Vec2(0, 0));
  EXPECT_EQ(again.bodies[1].r0, Vec2(1, 0));
  EXPECT_EQ(again.bodies[2].inertia, 2.0);
  EXPECT_NE(lm.resolved_yaml.find("b: {mass: 1, inertia: 1, position: [1, 0]}"), std::string::npos)
      << lm.resolved_yaml;
  // The file's own values beside the changed one keep their places in the file: a bad clearance
  // is reported at its line, not as "(value set with --set)" (the copied map's entries were new
  // nodes in a first version).
  std::string flores = lash::test::read_file(lash::test::example_path("flores_slider_crank.yaml"));
  const auto swap = [&](const std::string& from, const std::string& to) {
    ASSERT_NE(flores.find(from), std::string::npos) << from;
    flores.replace(flores.find(from), from.size(), to);
  };
  swap("material: {youngs_modulus", "material: &steel {youngs_modulus");
  swap("slider.O, clearance: 0.5e-3}", "slider.O, clearance: -0.5e-3, material: *steel}");
  const auto d = problems(flores, {"joints.rod_slider.material.youngs_modulus=100e9"});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str().rfind("model.yaml:51:", 0), 0u) << d[0].str();
  EXPECT_NE(d[0].str().find("clearance must be >= 0"), std::string::npos) << d[0].str();
  EXPECT_EQ(d[0].str().find("--set"), std::string::npos) << d[0].str();
}

TEST(Overrides, SectionsOfDefaultsAreMadeWhereTheFileHasNone) {
  // A model that states no solver settings (all but end_time have defaults) takes
  // --set solver.end_time (Python's t_end): it was "no 'solver' in the model". The same for
  // clearance_defaults; other sections and deeper paths still need their parents.
  const std::string text = R"Y(
ground: {markers: {O: [0, 0]}}
bodies:
  bob: {mass: 1, inertia: 1e-6, position: [0.1, -1], markers: {P: [-0.1, 1]}}
joints:
  piv: {type: revolute, journal: bob.P, bearing: ground.O}
)Y";
  const Model m = load_model_text(text, "bob.yaml", {"solver.end_time=2", "solver.rtol=1e-7"}).model;
  EXPECT_EQ(m.solver.end_time, 2.0);
  EXPECT_EQ(m.solver.rtol, 1e-7);
  EXPECT_NO_THROW(load_model_text(text, "bob.yaml",
                                  {"solver.end_time=2", "clearance_defaults.restitution=0.5"}));
  auto d = problems(text, {"solver.bad.key=1"});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "--set solver.bad.key: no 'solver.bad' in the model");
  d = problems(text, {"loads.spring.stiffness=1"});
  ASSERT_FALSE(d.empty());
  EXPECT_EQ(d[0].str(), "--set loads.spring.stiffness: no 'loads' in the model");
  // Without an end time, the model says what it lacks, not the override.
  d = problems(text, {"solver.rtol=1e-7"});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_NE(d[0].str().find("missing required key 'end_time'"), std::string::npos) << d[0].str();
  // A step limit no integrator can take at end_time: refused naming max_step (the run failed
  // with "step size underflow (h = 1e-300)").
  d = problems(text, {"solver.end_time=2", "solver.max_step=1e-300"});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml: solver: max_step 1e-300 s is below the smallest step an integrator "
                        "can take at end_time (7.11e-15 s); 0 leaves the step unlimited (value set with --set)");
  EXPECT_TRUE(problems(text, {"solver.end_time=2", "solver.max_step=1e-14"}).empty());
  // An element replaced by a --set value that is no map: said to be the --set's, not placed at
  // the element's line as if the file held it.
  d = problems(text, {"solver.end_time=2", "joints.piv=5"});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml: joint 'piv': expected a map of keys such as {type: revolute, journal: "
                        "..., bearing: ...}, got '5' (value set with --set)");
}

TEST(ModelLoader, AKeyThatIsNoNameIsRefusedAtItsPlace) {
  // `~:` (a null key) became an element named "null" (channels null.Fx, ...).
  const auto d = problems("name: m\nbodies:\n  a: {mass: 1, inertia: 1}\njoints:\n"
                          "  ~: {type: revolute, journal: a.O, bearing: ground.O}\n"
                          "  ? [x, y]\n  : {type: revolute, journal: a.O, bearing: ground.O}\n"
                          "solver: {end_time: 1}\n", {});
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].str(), "model.yaml:5:3: a key must be a name, got nothing (~, null or an empty key)");
  EXPECT_EQ(d[1].str(), "model.yaml:6:5: a key must be a name, got a list");
}

TEST(Overrides, ClearanceZeroMakesTheJointIdeal) {
  const Model m = load_model_text(kGood, "model.yaml", {"joints.gudgeon.clearance=0"}).model;
  EXPECT_EQ(m.clearance_joint_count(), 0);
}

TEST(Overrides, BadPathsAndValuesAreReported) {
  auto d = problems(kGood, {"joints.gudgon.clearance=1e-4"});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "--set joints.gudgon.clearance: no 'joints.gudgon' in the model, did you mean 'gudgeon'?");
  d = problems(kGood, {"joints.gudgeon.clearance=abc"});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml: joint 'gudgeon': 'clearance' must be a number (m), got 'abc' (value set with --set)");
  d = problems(kGood, {"no_equals_sign"});
  ASSERT_EQ(d.size(), 1u);
}

TEST(ModelLoader, ExamplesLoad) {
  const std::vector<std::string> names{
      "flores_slider_crank.yaml", "flores_slider_crank_ideal.yaml",
      "flores_slider_crank_crank_rod_clearance.yaml", "flores_slider_crank_lugre.yaml",
      "flores_slider_crank_flexible_rod.yaml", "spin_up_beam.yaml",
      "tmd_slider_crank.yaml", "radial_engine_5.yaml", "press_slider_crank.yaml",
      "amiri_slider_crank.yaml", "amiri_slider_crank_absorbers.yaml", "amiri_four_bar.yaml",
      "amiri_four_bar_absorbers.yaml", "erkaya_articulated.yaml", "erkaya_compliant.yaml",
      "erkaya_compliant_beam.yaml", "breaker_linkage_flexible.yaml",
      "press_slider_crank_flexible_rod.yaml",
      "breaker_linkage.yaml"};
  for (const auto& name : names) {
    EXPECT_NO_THROW(load_model_file(lash::test::example_path(name))) << name;
    // The channels finalize() listed are those a workspace of the model lists.
    const Model m = load_model_file(lash::test::example_path(name)).model;
    const auto listed = channel_info(m), again = channel_info(m, Workspace(m));
    ASSERT_EQ(listed.size(), again.size()) << name;
    EXPECT_GT(listed.size(), 10u) << name;
    for (size_t i = 0; i < listed.size(); ++i)
      EXPECT_TRUE(listed[i].name == again[i].name && listed[i].unit == again[i].unit &&
                  listed[i].description == again[i].description)
          << name << ": " << listed[i].name;
  }
  // The list is every example: a new file in examples/ must be added here (and to the README).
  for (const auto& entry : std::filesystem::directory_iterator(lash::test::example_path(""))) {
    if (entry.path().extension() != ".yaml") continue;
    EXPECT_NE(std::find(names.begin(), names.end(), entry.path().filename().string()), names.end())
        << entry.path().filename() << " is not in this list";
  }
  // What the new examples are for.
  const Model lugre = load_model_file(lash::test::example_path("flores_slider_crank_lugre.yaml")).model;
  ASSERT_TRUE(lugre.joints[2].clearance.has_value());
  EXPECT_EQ(lugre.joints[2].clearance->friction_law, FrictionLaw::lugre);
  const LuGreParams& g = lugre.joints[2].clearance->lugre;
  EXPECT_LE(g.v_damping, 4 * std::sqrt(2 * M_E) * std::min(g.mu_static, g.mu_dynamic) / g.sigma1)
      << "v_damping keeps the law passive";
  const Model tmd = load_model_file(lash::test::example_path("tmd_slider_crank.yaml")).model;
  ASSERT_EQ(tmd.bodies.size(), 4u);
  EXPECT_EQ(tmd.bodies[3].type, BodyType::point_mass);
  ASSERT_EQ(tmd.loads.size(), 1u);
  EXPECT_EQ(tmd.loads[0].type, LoadType::bushing);
  EXPECT_EQ(tmd.loads[0].frame_body, 1);  // the rod
  ASSERT_EQ(tmd.sensors.size(), 1u);
  EXPECT_EQ(tmd.sensors[0].type, SensorType::accelerometer);
  // Erkaya et al. 2015: two clearance joints against one and a flexural pivot's torsional spring;
  // five accelerometers in both.
  for (const char* name : {"erkaya_articulated.yaml", "erkaya_compliant.yaml"}) {
    SCOPED_TRACE(name);
    const Model m = load_model_file(lash::test::example_path(name)).model;
    int clearance = 0, springs = 0;
    for (const auto& j : m.joints) clearance += j.clearance.has_value();
    for (const auto& l : m.loads) springs += l.type == LoadType::torsional_spring_damper;
    const bool compliant = std::string(name) == "erkaya_compliant.yaml";
    EXPECT_EQ(clearance, compliant ? 1 : 2);
    EXPECT_EQ(springs, compliant ? 1 : 0);
    EXPECT_EQ(m.sensors.size(), 5u);
  }
  // The breaker linkage: 9 moving bodies, 10 revolute and 3 prismatic pairs, one degree of
  // freedom by Grübler's count once its driver is removed (9·3 − 2·13 = 1), clearance with the
  // Adams IMPACT law and stepped friction at A and J.
  const Model breaker = load_model_file(lash::test::example_path("breaker_linkage.yaml")).model;
  ASSERT_EQ(breaker.bodies.size(), 9u);
  int revolute = 0, prismatic = 0;
  std::vector<std::string> clearance;
  for (const auto& j : breaker.joints) {
    revolute += j.type == JointType::revolute;
    prismatic += j.type == JointType::translational;
    if (j.clearance) {
      clearance.push_back(j.name);
      EXPECT_EQ(j.clearance->normal_law, NormalLaw::impact) << j.name;
      EXPECT_EQ(j.clearance->friction_law, FrictionLaw::adams_stepped) << j.name;
    }
  }
  EXPECT_EQ(revolute, 10);
  EXPECT_EQ(prismatic, 3);
  EXPECT_EQ(3 * static_cast<int>(breaker.bodies.size()) - 2 * (revolute + prismatic), 1);
  EXPECT_EQ(clearance, (std::vector<std::string>{"A", "J"}));
}

TEST(ModelLoader, NonFiniteNumbersAndBadNamesAreRejected) {
  auto d = problems(with("gravity: [0, -9.81]", "gravity: [.nan, -9.81]"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:2:10: model: 'gravity' must be a pair of finite numbers [x, y] "
                        "(m/s²), got [.nan, -9.81]");
  for (const char* bad : {"  slider-1: {mass", "  9slider: {mass", "  slidé: {mass", "  s lider: {mass"}) {
    d = problems(with("  slider: {mass", bad));
    ASSERT_GE(d.size(), 1u) << bad;
    EXPECT_NE(d[0].message.find("a body name must be letters, digits and '_'"), std::string::npos)
        << bad;
  }
  // Names that are identifiers pass this check (the joints then name a body that is missing).
  for (const char* good : {"  _slider_9: {mass", "  Z: {mass"})
    for (const auto& p : problems(with("  slider: {mass", good)))
      EXPECT_EQ(p.message.find("a body name must be"), std::string::npos) << good << ": " << p.message;
}

TEST(ModelLoader, PrescribedMotionMustDependOnTimeOnly) {
  const auto d = problems(with("speed_rpm: 5000", "motion: \"crank.phi + time\""));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_NE(d[0].message.find("function of time only"), std::string::npos) << d[0].str();
}

TEST(ModelLoader, MotionThatCannotBeDifferentiatedIsRejectedWithAHint) {
  // A driver needs exact time derivatives: a switch written with ?: is refused at load time,
  // pointing at the expression, with the way out; as a load the same text would be accepted.
  const auto d = problems(with("speed_rpm: 5000", "motion: \"time < 0.01 ? 0 : time - 0.01\""));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(),
            "model.yaml:31:33: driver 'motor': bad expression in 'motion': cannot differentiate "
            "'time < 0.01 ? 0 : time - 0.01' in time: comparisons, '&&', '||' and 'c ? a : b' "
            "have no derivative; switch between motions smoothly with step() or step5(), or use "
            "min, max, abs");
  // A speed profile needs one derivative; a constant-looking number stays a constant speed.
  EXPECT_TRUE(problems(with("speed_rpm: 5000", "speed: \"step5(time, 0, 0, 0.01, 100)\"")).empty());
  const auto s = problems(with("speed_rpm: 5000", "speed: \"time > 1 ? 1 : 0\""));
  ASSERT_EQ(s.size(), 1u);
  EXPECT_NE(s[0].message.find("bad expression in 'speed': cannot differentiate"), std::string::npos)
      << s[0].str();
  EXPECT_TRUE(problems(with("speed_rpm: 5000", "motion: \"max(0, time - 0.01)^3\"")).empty());
  // Derivatives that are not finite at time 0 (√t's 1/(2√t)): reported at the expression, with
  // its driver; they were found only when the run started, with no line and no element.
  for (const auto& [key, text, order] :
       std::vector<std::tuple<std::string, std::string, int>>{{"motion", "sqrt(t)", 1},
                                                               {"motion", "abs(t)^1.5", 2},
                                                               {"speed", "sqrt(t)", 1}}) {
    const auto n = problems(with("speed_rpm: 5000", key + ": \"" + text + "\""));
    ASSERT_EQ(n.size(), 1u) << text;
    EXPECT_EQ(n[0].line, 31) << n[0].str();
    EXPECT_NE(n[0].str().find("driver 'motor': bad expression in '" + key + "': expression '" + text +
                              "' failed at time 0 s: its time derivative of order " +
                              std::to_string(order) + " is not finite"),
              std::string::npos)
        << n[0].str();
  }
}

TEST(ModelLoader, MissingSectionPointsIntoTheFileNotAtAnOverride) {
  std::string s = kGood;
  s = s.substr(0, s.find("solver:"));
  const auto d = problems(s);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:1:1: solver: missing required key 'end_time' (s)");
}

TEST(ModelLoader, JointGeometryAndMaterialOverrideTheDefaults) {
  std::string s = with("joints:\n", R"Y(clearance_defaults:
  journal_radius: 9.5e-3
  journal_material: {youngs_modulus: 70e9, poisson_ratio: 0.33}
  bearing_material: {youngs_modulus: 70e9, poisson_ratio: 0.33}
joints:
)Y");
  s.replace(s.find("    journal_radius: 9.5e-3\n"), 27, "    bearing_radius: 20e-3\n");
  const Model m = load_model_text(s, "model.yaml").model;
  const Clearance& c = *m.joints[2].clearance;
  EXPECT_DOUBLE_EQ(c.bearing_radius, 20e-3);  // the joint's clearance + bearing_radius
  EXPECT_DOUBLE_EQ(c.journal_radius, 19.5e-3);
  // The joint's steel `material` wins over the aluminium per-side defaults.
  EXPECT_NEAR(c.contact.stiffness,
              hertz_cylinder_stiffness(20e-3, 19.5e-3, 207e9, 0.3, 207e9, 0.3), 1.0);
}

TEST(Overrides, FlowListsAndMaps) {
  const Model m = load_model_text(kGood, "model.yaml",
                                  {"bodies.slider.position=[0.2, 0.01]",
                                   "joints.gudgeon.friction={law: coulomb, mu: 0.1}"})
                      .model;
  EXPECT_DOUBLE_EQ(m.bodies[2].r0.x(), 0.2);
  EXPECT_DOUBLE_EQ(m.bodies[2].r0.y(), 0.01);
  EXPECT_EQ(m.joints[2].clearance->friction_law, FrictionLaw::coulomb);
  EXPECT_DOUBLE_EQ(m.joints[2].clearance->friction.mu, 0.1);
  // A malformed list is reported against the override, not a line of the file.
  const auto d = problems(kGood, {"bodies.slider.position=[0.2, x]"});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].line, 0);
  EXPECT_NE(d[0].message.find("(value set with --set)"), std::string::npos) << d[0].str();
}

TEST(ModelLoader, NewElementsAreCheckedWithLocatedMessages) {
  const std::string yaml = R"(name: bad_elements
bodies:
  arm: {mass: 1, inertia: 0.01, markers: {P: [0.1, 0]}}
  bob: {mass: 0.1, angle: 0.3}
joints:
  pin: {type: revolute, journal: arm, bearing: ground}
drivers:
  turn: {body: bob, coordinate: phi, speed: 1}
loads:
  mount: {type: bushing, from: arm.P, to: bob, frame: wheel, stiffness: [1, 1]}
sensors:
  acc: {type: accelerometer, at: arm.Q, axis: [1, 0]}
  probe: {type: velocity, at: arm.P, gravity: true}
solver: {end_time: 1}
)";
  const auto d = problems(yaml);
  std::vector<std::string> got;
  for (const auto& x : d) got.push_back(x.str());
  auto has = [&](const std::string& text) {
    for (const auto& g : got)
      if (g.find(text) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("model.yaml:4:27: body 'bob': a body without 'inertia' is a point mass, which has no angle"))
      << ::testing::PrintToString(got);
  EXPECT_TRUE(has("model.yaml:8:16: driver 'turn': body 'bob' is a point mass (no inertia): it has no angle to drive"))
      << ::testing::PrintToString(got);
  EXPECT_TRUE(has("model.yaml:10:55: load 'mount': unknown body 'wheel'")) << ::testing::PrintToString(got);
  EXPECT_TRUE(has("model.yaml:12:34: sensor 'acc': unknown marker 'Q' on body 'arm'")) << ::testing::PrintToString(got);
  EXPECT_TRUE(has("sensor 'probe': 'gravity' applies to accelerometers only")) << ::testing::PrintToString(got);
}

TEST(ModelLoader, FinalizeProblemsPointAtTheElement) {
  // A torque on a point mass is found by the core's finalize; the message still points into the file.
  const std::string yaml = R"(name: torque_on_point
bodies:
  bob: {mass: 0.1}
loads:
  twist: {type: torque, body: bob, torque: "1"}
solver: {end_time: 1}
)";
  const auto d = problems(yaml);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:5:10: load 'twist': body 'bob' is a point mass: it takes no torque");
  // A torsional spring from a body to itself would act on nothing yet count its energy, as a
  // spring or a bushing would: refused like them.
  const std::string pivot = R"(name: pivot_on_itself
bodies:
  bar: {mass: 1, inertia: 0.1}
joints:
  hinge: {type: revolute, journal: bar, bearing: ground}
loads:
  pivot: {type: torsional_spring_damper, bodies: [bar, bar], stiffness: 5, free_angle: 0.5}
solver: {end_time: 1}
)";
  const auto p = problems(pivot);
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p[0].str(), "model.yaml:7:10: load 'pivot': both ends are on body 'bar'; a torsional "
                        "spring acts between two bodies");
}

TEST(ModelLoader, ChannelClashesPointAtTheElementAndNameBothOwners) {
  // A joint and a load named 'hang' (both write hang.Fx, .Fy, .F); a sensor whose mass adds a
  // point mass 'probe_mass' and a joint 'probe_mount' beside a body and a joint of those names.
  const std::string yaml = R"(name: clash
ground: {markers: {O: [0, 0]}}
bodies:
  am: {mass: 0.5, position: [0.3, 0.1]}
  probe_mass: {mass: 1.0, position: [1, 0]}
joints:
  hang: {type: distance, from: ground.O, to: am}
  probe_mount: {type: distance, from: ground.O, to: probe_mass}
loads:
  hang: {type: spring_damper, from: ground.O, to: am, stiffness: 5}
sensors:
  probe: {type: accelerometer, at: am, mass: 0.01}
solver: {end_time: 0.1}
)";
  const auto d = problems(yaml);
  ASSERT_EQ(d.size(), 3u);  // one a clash, not one a channel
  EXPECT_EQ(d[0].str(), "model.yaml:10:9: load 'hang': load 'hang' writes 'hang.Fx', 'hang.Fy', "
                        "'hang.F', as joint 'hang' does; elements may share a name only when their "
                        "channels differ: rename one of them");
  EXPECT_EQ(d[1].line, 12);
  EXPECT_NE(d[1].message.find("the point mass 'probe_mass' added by sensor 'probe' (its mass) "
                              "writes 'probe_mass.x', 'probe_mass.y', 'probe_mass.vx' and 3 more, "
                              "as body 'probe_mass' does"),
            std::string::npos)
      << d[1].message;
  EXPECT_EQ(d[2].line, 12);
  EXPECT_NE(d[2].message.find("the joint 'probe_mount' added by sensor 'probe' (its mass) writes "
                              "'probe_mount.Fx'"),
            std::string::npos)
      << d[2].message;
}

TEST(ModelLoader, DuplicateKeysAndNamesAreErrorsWithBothPlaces) {
  // Two joints named `pin`: yaml-cpp keeps both, a lookup would take the first silently.
  auto d = problems(with("  guide: {type", "  pin: {type: revolute, journal: rod.B, bearing: slider}\n  guide: {type"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:29:3: duplicate key 'pin' (first at line 19, column 3); each key "
                        "and each element name may appear once in a map");
  // A repeated key inside an element.
  d = problems(with("  end_time: 0.024", "  end_time: 0.024\n  end_time: 0.048"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].line, 34);
  EXPECT_NE(d[0].message.find("duplicate key 'end_time' (first at line 33, column 3)"), std::string::npos);
  // Several, in the file's order whatever their depth; a map reached twice through an alias is
  // reported once.
  d = problems("name: a\nbase: &b {x: 1, x: 2}\nother: *b\nname: c\n");
  ASSERT_GE(d.size(), 2u);
  EXPECT_EQ(d[0].str(), "model.yaml:2:17: duplicate key 'x' (first at line 2, column 11); each key "
                        "and each element name may appear once in a map");
  EXPECT_EQ(d[1].line, 4);
  EXPECT_NE(d[1].message.find("duplicate key 'name' (first at line 1, column 1)"), std::string::npos);
  if (d.size() > 2) {
    EXPECT_EQ(d[2].message.find("duplicate key"), std::string::npos) << d[2].str();
  }
}

TEST(ModelLoader, TextMustBeUtf8AndOneDocument) {
  // A Latin-1 'é' (0xE9) in a comment on line 2, column 17.
  auto d = problems(with("gravity: [0, -9.81]", "gravity: [0, -9.81] # \xE9t\xE9"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:2:23: not UTF-8 text (byte 0xE9); save the model file with UTF-8 encoding");
  // Valid UTF-8 (the same text encoded properly) loads; an overlong '/' (0xC0 0xAF) does not.
  EXPECT_TRUE(problems(with("gravity: [0, -9.81]", "gravity: [0, -9.81] # \xC3\xA9t\xC3\xA9")).empty());
  EXPECT_EQ(problems(std::string(kGood) + "# \xC0\xAF\n").size(), 1u);
  // An override that is not UTF-8.
  d = problems(kGood, {"name=\xFF"});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_NE(d[0].message.find("not UTF-8"), std::string::npos);
  // A second document after the model.
  d = problems(std::string(kGood) + "---\nname: other\n");
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].line, 35);  // the "---"
  EXPECT_NE(d[0].message.find("a second YAML document"), std::string::npos);
  d = problems(std::string(kGood) + "...\n---\nname: other\n");
  ASSERT_EQ(d.size(), 1u);
  EXPECT_NE(d[0].message.find("a second YAML document"), std::string::npos);
  // One document with its markers, and "---" inside a block scalar, are one model.
  EXPECT_TRUE(problems("--- # the model\n" + std::string(kGood) + "...\n").empty());
  EXPECT_TRUE(problems(with("name: t\n", "name: t\ndescription: |\n  ---\n  ...\n")).empty());
}

TEST(ModelLoader, TheModelAsRunIsTheFileTextUnlessOverridden) {
  // Without overrides model_resolved.yaml is the file itself, comments kept; with one, the model
  // after it, emitted again from the tree.
  const std::string text = std::string(kGood) + "# a closing comment\n";
  const LoadedModel plain = load_model_text(text, "model.yaml");
  EXPECT_EQ(plain.resolved_yaml + "\n", text);
  const LoadedModel set = load_model_text(text, "model.yaml", {"solver.end_time=0.5"});
  EXPECT_EQ(set.resolved_yaml.find("# a closing comment"), std::string::npos);
  EXPECT_NE(set.resolved_yaml.find("end_time: 0.5"), std::string::npos) << set.resolved_yaml;
  EXPECT_EQ(load_model_text(set.resolved_yaml, "again.yaml").model.solver.end_time, 0.5);
}

TEST(ModelLoader, TheNumberOfOutputsIsBoundedBeforeRunning) {
  auto d = problems(with("output_interval: 1.0e-5", "output_interval: 1e-300"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].line, 34);
  EXPECT_NE(d[0].message.find("end_time / output_interval = 2.4e+298 outputs, more than max_outputs = 2000000"),
            std::string::npos) << d[0].message;
  // 2.4e7 outputs: refused by default, accepted when max_outputs is raised on purpose.
  EXPECT_EQ(problems(with("output_interval: 1.0e-5", "output_interval: 1.0e-9")).size(), 1u);
  EXPECT_TRUE(problems(with("output_interval: 1.0e-5", "output_interval: 1.0e-9\n  max_outputs: 3.0e7")).empty());
  EXPECT_EQ(problems(kGood, {"solver.max_outputs=0.5"}).size(), 1u);
  // A refused end_time is not compared with output_interval (its stand-in of 1 s gave "got 2 > 1").
  d = problems(kGood, {"solver.end_time=-5", "solver.output_interval=2"});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_NE(d[0].message.find("end_time must be > 0, got -5"), std::string::npos) << d[0].message;
  EXPECT_EQ(problems(kGood, {"solver.end_time=1", "solver.output_interval=2"}).size(), 1u);
}

TEST(ModelLoader, RelativeToleranceIsOneTheErrorControlCanHonour) {
  // rtol 0.5 made DOPRI5's first step fail with "step size underflow"; 1e-17 is below round-off.
  for (const char* bad : {"solver.rtol=0.5", "solver.rtol=1e-17", "solver.rtol=0"}) {
    auto d = problems(kGood, {bad});
    ASSERT_EQ(d.size(), 1u) << bad;
    EXPECT_NE(d[0].message.find("rtol must be in [1e-14, 0.1]"), std::string::npos) << d[0].message;
  }
  EXPECT_TRUE(problems(kGood, {"solver.rtol=0.1"}).empty());
  EXPECT_TRUE(problems(kGood, {"solver.rtol=1e-14"}).empty());
}

TEST(ModelLoader, AbsoluteToleranceIsOneTheErrorControlCanHonour) {
  // atol 1e-300 and 1e-20 were accepted and the run stopped at t = 0 ("step size underflow").
  for (const char* bad : {"solver.atol=1e-300", "solver.atol=1e-20", "solver.atol=0", "solver.atol=2"}) {
    auto d = problems(kGood, {bad});
    ASSERT_EQ(d.size(), 1u) << bad;
    EXPECT_NE(d[0].message.find("atol must be in [1e-18, 1]"), std::string::npos) << d[0].message;
  }
  EXPECT_TRUE(problems(kGood, {"solver.atol=1e-18"}).empty());
  EXPECT_TRUE(problems(kGood, {"solver.atol=1"}).empty());
}

TEST(ModelLoader, AnElementThatIsNotAMapIsReportedAtItsLine) {
  // `pin: [1, 2]` was "unknown joint type 'null' ... (value set with --set)": no line, a --set
  // that was never given, and a type nobody wrote.
  struct Case {
    std::string from, to, line_col, message;
  };
  const std::string pin = "  pin: {type: revolute, journal: crank.A, bearing: rod.A}";
  for (const Case& c : std::vector<Case>{
           {pin, "  pin: [1, 2]", "19:8", "joint 'pin': expected a map of keys such as {type: revolute"},
           {pin, "  pin: revolute", "19:8", "got 'revolute'"},
           {pin, "  pin:", "19:3", "joint 'pin': expected a map of keys such as"},
           // No type at all: the missing key's node threw yaml-cpp's InvalidNode (a crash).
           {pin, "  pin: {journal: crank.A, bearing: rod.A}", "19:8", "joint 'pin': missing 'type'"},
           {"drivers:", "loads: {f: {point: rod.A, fx: 1}}\ndrivers:", "30:12", "load 'f': missing 'type'"},
           {pin, "  pin: {type: [revolute], journal: crank.A, bearing: rod.A}", "19:15",
            "'type' must be one word, got a list; expected one of: revolute"},
           {"drivers:\n  motor: {joint: pivot, speed_rpm: 5000}", "drivers:\n  motor: [1]", "31:10",
            "driver 'motor': expected a map of keys (key: value), got a list"},
           {"drivers:\n  motor: {joint: pivot, speed_rpm: 5000}", "drivers:\n  motor:", "31:3",
            "driver 'motor': give either 'joint'"},
           {"drivers:", "loads: {f: [1]}\nsensors: {s: 5}\ndrivers:", "30:12",
            "load 'f': expected a map of keys such as {type: force"}}) {
    SCOPED_TRACE(c.to);
    const auto d = problems(with(c.from, c.to));
    ASSERT_EQ(d.size(), c.to.find("sensors") != std::string::npos ? 2u : 1u);
    EXPECT_EQ(std::to_string(d[0].line) + ":" + std::to_string(d[0].column), c.line_col) << d[0].str();
    EXPECT_NE(d[0].str().find(c.message), std::string::npos) << d[0].str();
    EXPECT_EQ(d[0].str().find("--set"), std::string::npos) << d[0].str();
  }
}

TEST(ModelLoader, OneMistakeIsOneProblemSayingWhatWasGiven) {
  // Each of these gave two problems (a contradiction, or a follow-on "unknown marker"), or a
  // message that did not say what was wrong.
  const std::string tmd = lash::test::read_file(lash::test::example_path("tmd_slider_crank.yaml"));
  auto in_tmd = [&](const std::string& to) {
    std::string s = tmd;
    const std::string from = "stiffness: [198951, 198951]";
    return s.replace(s.find(from), from.size(), to);
  };
  struct Case {
    std::string yaml, said;
  };
  for (const Case& c : std::vector<Case>{
           {in_tmd("stiffness: -1"), "stiffness must be >= 0, got -1"},
           {in_tmd("stiffness: [1, -2]"), "must be a number >= 0 or a pair [x, y] of them (N/m), got [1, -2]"},
           {with("    markers: {O: [-0.025, 0], A: [0.025, 0]}", "    markers: {O: [-0.025, .inf], A: [0.025, 0]}"),
            "marker 'O' must be [x, y], finite numbers in body coordinates (m), got [-0.025, .inf]"},
           {with("drivers:", "loads: {f: {type: force, point: rod.A, fx: [1, 2], fy: 0}}\ndrivers:"),
            "'fx' must be a number or an expression (text), got a list"}}) {
    const auto d = problems(c.yaml);
    ASSERT_EQ(d.size(), 1u) << c.said << "\n" << (d.size() > 1 ? d[1].str() : "");
    EXPECT_GT(d[0].line, 0);
    EXPECT_NE(d[0].message.find(c.said), std::string::npos) << d[0].str();
  }
  // An axis of any length is a direction ([1e200, 1e200]'s norm overflowed: "must be a unit vector").
  const Model big = load_model_text(with("axis: [1, 0]", "axis: [1e200, 0]"), "model.yaml").model;
  const Model tiny = load_model_text(with("axis: [1, 0]", "axis: [1e-200, 0]"), "model.yaml").model;
  EXPECT_EQ(big.joints[3].axis, Vec2(1, 0));
  EXPECT_EQ(tiny.joints[3].axis, Vec2(1, 0));
  // A sensor's too: [1e300, 1e300] was refused as "a non-zero vector" at the sensor, and
  // [0, 1e-200] as "[0, 0]".
  for (const char* axis : {"[1e300, 1e300]", "[3e-200, 3e-200]"}) {
    const Model m = load_model_text(std::string(kGood) + "sensors: {a: {type: accelerometer, at: rod.B, axis: " +
                                        axis + "}}\n",
                                    "model.yaml").model;
    ASSERT_EQ(m.sensors.size(), 1u);
    EXPECT_NEAR(m.sensors[0].axis.x(), std::sqrt(0.5), 1e-15) << axis;
    EXPECT_NEAR(m.sensors[0].axis.y(), std::sqrt(0.5), 1e-15) << axis;
  }
}

TEST(ModelLoader, NumbersBelowTheSmallestNormalDoubleAreRefused) {
  // A mass of 1e-320 passed "> 0" and the run stopped at t = 0 ("not finite"); a Young's modulus
  // of 1e-320 ran a link with no stiffness to the end. Refused at their keys; 0 stays 0. A value
  // below even the subnormals reads as 0: a mass of 1e-400 was answered "must be > 0, got 0".
  for (const char* bad : {"bodies.crank.mass=1e-320", "joints.gudgeon.journal_radius=4e-324",
                          "bodies.rod.position=[0.11, -1e-310]", "gravity=[0, 1e-315]",
                          "bodies.crank.mass=1e-400", "gravity=[0, -9.81e-999]"}) {
    auto d = problems(kGood, {bad});
    ASSERT_GE(d.size(), 1u) << bad;
    EXPECT_TRUE(d[0].message.find("below the smallest normal double") != std::string::npos ||
                d[0].message.find("pair of finite numbers") != std::string::npos)
        << d[0].message;
  }
  EXPECT_TRUE(problems(kGood, {"gravity=[0, 0]"}).empty());
  EXPECT_TRUE(problems(kGood, {"gravity=[0.0e-5, -0e400]"}).empty());
  EXPECT_TRUE(problems(kGood, {"bodies.crank.mass=2.3e-308"}).empty());
}

TEST(ModelLoader, OnlyRegularFilesOfBoundedSizeAreRead) {
  try {
    load_model_file("/dev/zero");
    FAIL() << "/dev/zero loaded";
  } catch (const ModelError& e) {
    ASSERT_EQ(e.diagnostics().size(), 1u);
    EXPECT_EQ(e.diagnostics()[0].str(),
              "/dev/zero: cannot read the model file: not a regular file (expected a text file)");
  }
}

TEST(Contact, TheMaterialsStiffnessIsForExponentOnePointFiveOnly) {
  // Hertz's K from the materials is in N/m^1.5; with exponent 1 and no stiffness it was used as
  // N/m, silently: a force of the wrong size and unit.
  const auto d = problems(with("    normal_law: lankarani_nikravesh\n",
                               "    normal_law: lankarani_nikravesh\n    exponent: 1.0\n"));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "model.yaml:28:15: joint 'gudgeon': exponent 1 needs the contact 'stiffness' "
                        "(N/m^exponent): the stiffness derived from the materials is Hertz's, in "
                        "N/m^1.5, for exponent 1.5 only");
  // With its stiffness given, or at 1.5, it loads.
  EXPECT_TRUE(problems(with("    normal_law: lankarani_nikravesh\n",
                            "    normal_law: lankarani_nikravesh\n    exponent: 1.0\n    stiffness: 1.0e9\n"))
                  .empty());
  EXPECT_TRUE(problems(with("    normal_law: lankarani_nikravesh\n",
                            "    normal_law: lankarani_nikravesh\n    exponent: 1.5\n"))
                  .empty());
}
