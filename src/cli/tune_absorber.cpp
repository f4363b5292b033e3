// `lash tune-absorber`: proposes the stiffness and damping of a tuned-mass absorber by Den Hartog's
// rules (analysis/absorber.hpp), prints them with the formulas and a model-file snippet.
#include "cli/tune_absorber.hpp"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <ostream>
#include <stdexcept>

#include "analysis/absorber.hpp"
#include "core/finalize.hpp"

namespace lash::cli {

namespace {

/// Throws std::invalid_argument naming the option unless v is finite and > 0.
void require_positive(const char* option, double v) {
  if (!(std::isfinite(v) && v > 0))
    throw std::invalid_argument(fmt::format("{}: expected a finite number > 0, got {}", option, v));
  if (!std::isnormal(v))  // 1e-320 gave a design of subnormal numbers
    throw std::invalid_argument(fmt::format(
        "{}: {} is below the smallest normal double ({}), where arithmetic has lost its precision",
        option, v, std::numeric_limits<double>::min()));
}

/// Throws unless `point` is a point reference on a moving body: BODY or BODY.MARKER.
void require_point(const std::string& point) {
  const std::string body = point.substr(0, point.find('.'));
  bool ok = !body.empty() && !std::isdigit(static_cast<unsigned char>(body[0]));
  for (char ch : body) ok = ok && (std::isalnum(static_cast<unsigned char>(ch)) || ch == '_');
  if (body.size() < point.size()) {
    const std::string marker = point.substr(body.size() + 1);
    // (One dot: BODY.MARKER; a.b.c named no point and gave a snippet with 'frame: a'.)
    ok = ok && !marker.empty() && marker.find_first_of(" \t:#,[]{}\"'.") == std::string::npos;
  }
  if (!ok)
    throw std::invalid_argument(fmt::format(
        "--attach: expected BODY or BODY.MARKER (body: letters, digits, _), got '{}'", point));
  if (body == "ground")
    throw std::invalid_argument(fmt::format(
        "--attach: expected a point on the vibrating link, got '{}' (on the ground an absorber "
        "does nothing)",
        point));
  if (reserved_name(body))  // a model refuses a body of that name
    throw std::invalid_argument(fmt::format(
        "--attach: '{}' is not a body a model can have (the name '{}' is reserved)", point, body));
  if (body == "absorber")
    throw std::invalid_argument(fmt::format(
        "--attach: '{}' is on the body the snippet adds ('absorber'): the bushing would join it "
        "to itself; name a point of the vibrating link",
        point));
}

/// Throws std::invalid_argument unless every number of the design is finite and > 0: inputs that
/// each pass require_positive can still overflow (k_a = m_a ω_a² at --frequency 1e200) or vanish
/// (m_a = μ M below the smallest double). `frequency`, `mass_ratio` and `mass` are the options
/// with their values ("--frequency 1e+200"; `mass`: the mass given, --primary-mass when `has_m`);
/// the message names those the quantity is computed from, the quantity and its formula.
void require_finite_design(const AbsorberDesign& d, const std::string& frequency,
                           const std::string& mass_ratio, const std::string& mass, bool has_m) {
  // The options each mass is computed from: given, or from the other mass and μ.
  const std::string m_a = has_m ? mass_ratio + ", " + mass : mass;
  const std::string m_p = has_m ? mass : mass + ", " + mass_ratio;
  // k_a and c_a depend on all three: m_a, and ω_a = ω_p / (1 + μ).
  const std::string f_mu_m_a = frequency + ", " + mass_ratio + ", " + mass;
  struct Quantity {
    const char* name;
    double value;
    const char* formula;
    std::string options;
  };
  const Quantity quantities[] = {
      {"absorber_mass", d.absorber_mass, "m_a = μ M (kg)", m_a},
      {"primary_mass", d.primary_mass, "M = m_a / μ (kg)", m_p},
      {"stiffness", d.stiffness, "k_a = m_a ω_a² (N/m)", f_mu_m_a},
      {"damping", d.damping, "c_a = 2 ζ_opt m_a ω_p (N·s/m)", f_mu_m_a},
      {"tuned_frequency", d.absorber_frequency_hz, "f_a = f_p / (1 + μ) (Hz)",
       frequency + ", " + mass_ratio},
      {"primary_stiffness", d.primary_stiffness, "K = M ω_p² (N/m)", frequency + ", " + m_p},
      {"frequency_ratio", d.frequency_ratio, "f_opt = 1 / (1 + μ)", mass_ratio},
      {"damping_ratio", d.damping_ratio, "ζ_opt = sqrt(3μ / (8 (1 + μ)³))", mass_ratio},
      {"absorber_damping_ratio", d.absorber_damping_ratio, "ζ_a = (1 + μ) ζ_opt", mass_ratio},
      {"peak_amplification", d.peak_amplification, "sqrt(1 + 2/μ)", mass_ratio},
  };
  for (const Quantity& q : quantities)
    if (!(std::isnormal(q.value) && q.value > 0))
      throw std::invalid_argument(fmt::format(
          "{}: the design's {} {} comes out as {}; expected inputs for which it is a finite "
          "number > 0 of normal size (these are too large or too small to compute with)",
          q.options, q.name, q.formula, q.value));
}

/// One snippet line: `text` padded so that the comments line up, then `# comment`.
std::string yaml_line(const std::string& text, const std::string& comment) {
  return fmt::format("{:<33} # {}\n", text, comment);
}

/// The absorber as model-file YAML: a point-mass body (no `inertia` key: coordinates x, y and no
/// rotation) and a two-axis bushing to the link whose axes are the link's. A bushing's `frame` is
/// one of the two bodies it joins, or ground; a point mass has no axes, so it is the link here.
std::string yaml_snippet(const AbsorberDesign& d, const std::string& attach) {
  const std::string link = attach.substr(0, attach.find('.'));
  return fmt::format(
             "# Tuned-mass absorber: Den Hartog tuning for a {:.6g} Hz mode, mass ratio {:.6g}\n"
             "# (lash tune-absorber). Merge into the model's bodies: and loads: maps.\n"
             "# The absorber is a point mass (no inertia): it has no rotation to tune.\n"
             "# Both axes of the bushing get the same values for a two-axis absorber: it is\n"
             "# isotropic and absorbs motion in any direction of the plane. Its spring force is\n"
             "# then the same in any frame; its damper acts on the deflection rate seen in the\n"
             "# frame's axes, here the link's: the absorber's motion relative to the link.\n",
             d.primary_frequency_hz, d.mass_ratio) +
         "bodies:\n  absorber:\n" +
         yaml_line(fmt::format("    mass: {:.6g}", d.absorber_mass), "m_a, kg; no inertia: a point mass") +
         yaml_line("    position: [0, 0]",
                   "set to the world position of " + attach + " at the initial pose") +
         "loads:\n  absorber_mount:\n    type: bushing\n" +
         yaml_line("    from: " + attach, "where the absorber sits on the link") +
         "    to: absorber\n" +
         yaml_line("    frame: " + link,
                   "axes of k_a and c_a: " + link + "'s (a point mass has none)") +
         yaml_line(fmt::format("    stiffness: [{:.6g}, {:.6g}]", d.stiffness, d.stiffness),
                   "k_a, N/m (x, y)") +
         yaml_line(fmt::format("    damping: [{:.6g}, {:.6g}]", d.damping, d.damping),
                   "c_a, N·s/m (x, y)");
}

}  // namespace

TuneAbsorberCommand::TuneAbsorberCommand(CLI::App& app) {
  sub_ = app.add_subcommand(
      "tune-absorber",
      "Propose a tuned-mass absorber (stiffness, damping) for one vibration mode of a link by Den "
      "Hartog's rules; prints the formulas used and a model-file snippet");
  sub_->add_option("--frequency", frequency_hz_,
                   "Natural frequency f_p of the mode to absorb, Hz (> 0)")
      ->required();
  sub_->add_option("--mass-ratio", mass_ratio_,
                   "Mass ratio mu = m_a / M (> 0; typically 0.01 to 0.25)")
      ->required();
  primary_mass_option_ = sub_->add_option("--primary-mass", primary_mass_,
                                          "Primary mass M, kg: the modal mass of the mode at the "
                                          "attachment point (or --absorber-mass)");
  absorber_mass_option_ = sub_->add_option("--absorber-mass", absorber_mass_,
                                           "Absorber mass m_a, kg (or --primary-mass)");
  sub_->add_option("--attach", attach_,
                   "Where the absorber sits, BODY.MARKER or BODY, for the YAML snippet "
                   "(default link.P)");
  sub_->add_flag("--json", json_, "Print one JSON object instead of text");
}

int TuneAbsorberCommand::run(std::ostream& out, std::ostream& err) const {
  AbsorberDesign d;
  try {
    // Check the options by their names, then leave the rules to the library.
    require_positive("--frequency", frequency_hz_);
    require_positive("--mass-ratio", mass_ratio_);
    const bool has_m = primary_mass_option_->count() > 0,
               has_ma = absorber_mass_option_->count() > 0;
    if (has_m == has_ma)
      throw std::invalid_argument(
          std::string("expected exactly one of --primary-mass or --absorber-mass, got ") +
          (has_m ? "both" : "neither"));
    if (has_m) require_positive("--primary-mass", primary_mass_);
    if (has_ma) require_positive("--absorber-mass", absorber_mass_);
    require_point(attach_);

    AbsorberInput in;
    in.primary_frequency_hz = frequency_hz_;
    in.mass_ratio = mass_ratio_;
    if (has_m) in.primary_mass = primary_mass_;
    if (has_ma) in.absorber_mass = absorber_mass_;
    d = den_hartog_absorber(in);
    require_finite_design(d, fmt::format("--frequency {}", frequency_hz_),
                          fmt::format("--mass-ratio {}", mass_ratio_),
                          has_m ? fmt::format("--primary-mass {}", primary_mass_)
                                : fmt::format("--absorber-mass {}", absorber_mass_),
                          has_m);
  } catch (const std::invalid_argument& e) {
    err << "lash tune-absorber: " << e.what() << "\n";
    return 2;
  }
  const std::string yaml = yaml_snippet(d, attach_);
  if (mass_ratio_ > 1.0)
    err << "warning: --mass-ratio " << mass_ratio_
        << ": the absorber outweighs the mode's modal mass (designs use about 0.01 to 0.25); the "
           "two-mass model behind the tuning leaves out the link's other modes, which an absorber "
           "this heavy moves too\n";

  if (json_) {
    nlohmann::ordered_json j;
    j["method"] = "den_hartog";
    j["citation"] = kDenHartogCitation;
    j["frequency"] = d.primary_frequency_hz;
    j["mass_ratio"] = d.mass_ratio;
    j["primary_mass"] = d.primary_mass;
    j["absorber_mass"] = d.absorber_mass;
    j["stiffness"] = d.stiffness;
    j["damping"] = d.damping;
    j["tuned_frequency"] = d.absorber_frequency_hz;
    j["frequency_ratio"] = d.frequency_ratio;
    j["damping_ratio"] = d.damping_ratio;
    j["absorber_damping_ratio"] = d.absorber_damping_ratio;
    j["peak_amplification"] = d.peak_amplification;
    j["primary_stiffness"] = d.primary_stiffness;
    j["formulas"] = d.formulas;
    j["yaml"] = yaml;
    out << j.dump(2) << "\n";
    return 0;
  }

  out << fmt::format(
      "Tuned-mass absorber for a {:.6g} Hz mode, mass ratio {:.6g} (Den Hartog's equal peaks)\n\n",
      d.primary_frequency_hz, d.mass_ratio);
  out << fmt::format("  absorber_mass        {:.6g} kg\n", d.absorber_mass);
  out << fmt::format("  stiffness            {:.6g} N/m\n", d.stiffness);
  out << fmt::format("  damping              {:.6g} N·s/m\n", d.damping);
  out << fmt::format("  tuned_frequency      {:.6g} Hz\n", d.absorber_frequency_hz);
  out << fmt::format(
      "  damping_ratio        {:.6g}  (c_a / (2 m_a ω_p), Den Hartog's; {:.6g} "
      "referred to the absorber's own ω_a)\n",
      d.damping_ratio, d.absorber_damping_ratio);
  out << fmt::format("  peak_amplification   {:.6g}  (|X| / x_st of the primary at both peaks)\n",
                     d.peak_amplification);
  out << fmt::format("  primary_mass         {:.6g} kg\n\n", d.primary_mass);
  out << "Formulas: undamped primary M on a spring K, force F0 sin ωt, absorber m_a on k_a and "
         "c_a;\n"
      << kDenHartogCitation << ":\n";
  for (const auto& line : d.formulas) out << "  " << line << "\n";
  out << "The peak amplification is the height of the two points every damping passes through;\n"
         "the true maxima are slightly higher (0.1 % at μ = 0.05, 0.4 % at μ = 0.25). M is the\n"
         "modal mass of the mode at the attachment point, f_p its frequency without the "
         "absorber.\n\n";
  out << "YAML for the model file:\n\n" << yaml;
  return 0;
}

}  // namespace lash::cli
