#include "models/thompson/thompson.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>


namespace chatterlab {

namespace thompson {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

double natural_frequency_rad_s(const ThompsonParameters& p) {
  return std::sqrt(p.stiffness_n_per_m / p.mass_kg);
}

double wheel_period_s(const ThompsonParameters& p) { return 60.0 / p.wheel_speed_rpm; }
double work_period_s(const ThompsonParameters& p) { return 60.0 / p.work_speed_rpm; }

// The boundary relation with c eliminated (2-61, 2-62): on Re H(jw) = -P the stability index is
// 1/a = -sqrt(P/|u| - P^2), u = k - m w^2 < 0, for wn < w < w_inf (|u| < 1/P). Increasing in w.
double boundary_inverse_index(const ThompsonParameters& p, double w) {
  const double u = p.stiffness_n_per_m - p.mass_kg * w * w;
  const double P = process_line_m_per_n(p);
  return -std::sqrt(std::max(P / -u - P * P, 0.0));
}

}  // namespace

PlungeRegenerativeParameters equivalent_g1(const ThompsonParameters& p) {
  PlungeRegenerativeParameters g1;
  g1.wheel_speed_rpm = p.wheel_speed_rpm;
  g1.work_speed_rpm = p.work_speed_rpm;
  g1.contact_stiffness_n_per_m = 1.0 / p.contact_compliance_m_per_n;
  g1.wheel_wear_stiffness_n_per_m = 1.0 / p.wheel_wear_compliance_m_per_n;
  g1.work_removal_stiffness_n_per_m = 1.0 / p.work_removal_compliance_m_per_n;
  g1.modes = {{natural_frequency_rad_s(p) / kTwoPi,
               p.damping_n_s_per_m / (2.0 * std::sqrt(p.stiffness_n_per_m * p.mass_kg)),
               p.stiffness_n_per_m}};
  return g1;
}

double cutting_compliance_m_per_n(const ThompsonParameters& p) {
  return p.wheel_wear_compliance_m_per_n + p.work_removal_compliance_m_per_n;
}

double hertz_parameter(const ThompsonParameters& p) {
  return 1.0 + 2.0 * p.contact_compliance_m_per_n / cutting_compliance_m_per_n(p);
}

double process_line_m_per_n(const ThompsonParameters& p) {
  return 0.5 * cutting_compliance_m_per_n(p) + p.contact_compliance_m_per_n;
}

BoundaryQuartic boundary_quartic(const ThompsonParameters& p) {
  const double P = process_line_m_per_n(p), k = p.stiffness_n_per_m;
  return {2.0 * P * P * P * (1.0 + k * P), 2.0 * P * (1.0 + 2.0 * k * P)};
}

double boundary_damping_n_s_per_m(const ThompsonParameters& p, double a) {
  const BoundaryQuartic q = boundary_quartic(p);
  const double a2 = a * a;
  return std::sqrt(2.0 * p.mass_kg * a2 / (q.alpha * a2 * a2 + q.beta * a2 + 2.0 * p.stiffness_n_per_m));
}

double unconditional_damping_n_s_per_m(const ThompsonParameters& p) {
  // max over t = a^2 of t/(alpha t^2 + beta t + 2k) is at t = sqrt(2k/alpha) (2-46); with the
  // alpha, beta above, beta + 2 sqrt(2 k alpha) = 2P (sqrt(kP) + sqrt(1 + kP))^2, so
  // c_m = sqrt(m) (sqrt(k + 1/P) - sqrt(k)), written without the cancellation.
  const double inverse_P = 1.0 / process_line_m_per_n(p), k = p.stiffness_n_per_m;
  return std::sqrt(p.mass_kg) * inverse_P / (std::sqrt(k + inverse_P) + std::sqrt(k));
}

double unconditional_damping_eq_2_48_n_s_per_m(const ThompsonParameters& p) {
  // D = 1/K for rigid contact (2-49); contact enters as K -> K H (2-59), i.e. D -> D/H.
  const double D = 1.0 / (cutting_compliance_m_per_n(p) * hertz_parameter(p));
  const double k = p.stiffness_n_per_m;
  const double ratio = D / (k + D);
  return std::sqrt(2.0 * p.mass_kg * (D + k) * (1.0 - std::sqrt(1.0 - ratio * ratio)));
}

double absolute_stability_damping_eq_2_65_n_s_per_m(const ThompsonParameters& p) {
  // c^2/m + 2 c sqrt(k/m) - 2/(K H) = 0, positive root by the quadratic formula.
  const double m = p.mass_kg, b = 2.0 * std::sqrt(p.stiffness_n_per_m / m);
  const double constant = 2.0 / (cutting_compliance_m_per_n(p) * hertz_parameter(p));
  return 0.5 * m * (-b + std::sqrt(b * b + 4.0 * constant / m));
}

std::optional<StabilityIndexBand> conditional_boundaries(const ThompsonParameters& p) {
  // alpha t^2 - (2m/c0^2 - beta) t + 2k = 0, t = a^2 (2-50).
  const BoundaryQuartic q = boundary_quartic(p);
  const double c0 = p.damping_n_s_per_m;
  const double b = 2.0 * p.mass_kg / (c0 * c0) - q.beta;
  const double discriminant = b * b - 8.0 * q.alpha * p.stiffness_n_per_m;
  if (b <= 0.0 || discriminant < 0.0) return std::nullopt;
  const double t_large = (b + std::sqrt(discriminant)) / (2.0 * q.alpha);
  const double t_small = 2.0 * p.stiffness_n_per_m / (q.alpha * t_large);  // product of the roots
  return StabilityIndexBand{-std::sqrt(t_small), -std::sqrt(t_large)};
}

namespace {
struct Eq264 {
  double b, discriminant, denominator;
};
Eq264 eq_2_64(const ThompsonParameters& p) {
  const double K = cutting_compliance_m_per_n(p), H = hertz_parameter(p), k = p.stiffness_n_per_m;
  const double c = p.damping_n_s_per_m;
  const double b = 2.0 * p.mass_kg / (K * c * c) - k * K * H * H - H;
  const double denominator = 2.0 * H * H * H + k * K * H * H * H * H;
  return {b, b * b - k * K * denominator, denominator};
}
}  // namespace

double eq_2_64_discriminant(const ThompsonParameters& p) { return eq_2_64(p).discriminant; }

std::optional<DimensionlessBand> dimensionless_boundaries(const ThompsonParameters& p) {
  const Eq264 e = eq_2_64(p);
  if (e.b <= 0.0 || e.discriminant < 0.0) return std::nullopt;
  const double root = std::sqrt(e.discriminant);
  return DimensionlessBand{-std::sqrt((e.b - root) / e.denominator),
                           -std::sqrt((e.b + root) / e.denominator)};
}

double boundary_frequency_rad_s(const ThompsonParameters& p, double z) {
  const double K = cutting_compliance_m_per_n(p), H = hertz_parameter(p), k = p.stiffness_n_per_m;
  return natural_frequency_rad_s(p) * std::sqrt(1.0 + (2.0 / (k * K)) * H * z * z / (H * H * z * z + 1.0));
}

double inverse_stability_index_m_per_n(const ThompsonParameters& p, double w) {
  return 0.5 * (p.wheel_wear_compliance_m_per_n / std::tan(0.5 * w * wheel_period_s(p)) +
                p.work_removal_compliance_m_per_n / std::tan(0.5 * w * work_period_s(p)));
}

SpeedCriterion speed_criterion(const ThompsonParameters& p) {
  const double wn = natural_frequency_rad_s(p), P = process_line_m_per_n(p);
  const double w_end = std::sqrt((p.stiffness_n_per_m + 1.0 / P) / p.mass_kg);  // |u| = 1/P
  // Poles of 1/a(w): the two revolution lattices. Between consecutive poles 1/a(w) falls from +inf
  // to -inf (cot decreases) while the boundary relation rises from -inf (at wn) to 0 (at w_end):
  // their difference is monotone, so each interval holds at most one crossing, found by bisection.
  std::vector<double> edges{wn, w_end};
  for (double period : {wheel_period_s(p), work_period_s(p)}) {
    const double spacing = kTwoPi / period;
    for (double n = std::ceil(wn / spacing); n * spacing < w_end; n += 1.0)
      if (n * spacing > wn) edges.push_back(n * spacing);
  }
  std::sort(edges.begin(), edges.end());
  auto mismatch = [&](double w) {
    return boundary_inverse_index(p, w) - inverse_stability_index_m_per_n(p, w);
  };
  SpeedCriterion out;
  for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
    double lo = edges[i], hi = edges[i + 1];
    if (!(hi > lo * (1.0 + 1e-14))) continue;
    if (hi == w_end && !(mismatch(hi - 1e-12 * hi) > 0.0)) continue;  // no sign change
    for (int it = 0; it < 200 && hi - lo > 4e-16 * hi; ++it) {
      const double mid = 0.5 * (lo + hi);
      (mismatch(mid) < 0.0 ? lo : hi) = mid;
    }
    const double w = 0.5 * (lo + hi);
    const double u = p.stiffness_n_per_m - p.mass_kg * w * w;
    const double v = std::sqrt(std::max(-u / P - u * u, 0.0));  // c w on the boundary (2-61)
    const double c = v / w;
    ++out.crossings;
    if (c > out.critical_damping_n_s_per_m) {
      out.critical_damping_n_s_per_m = c;
      out.frequency_rad_s = w;
      out.stability_index_n_per_m = 1.0 / boundary_inverse_index(p, w);
    }
  }
  out.chatter_margin = out.critical_damping_n_s_per_m / p.damping_n_s_per_m - 1.0;
  return out;
}

}  // namespace thompson

// ------------------------------------------------------------------ model plugin

namespace {

const ParamTable<ThompsonParameters>& parameters_table() {
  using P = ThompsonParameters;
  static const ParamTable<P> table = [] {
    ParamTable<P> t;
    t.add(&P::mass_kg, "mass_kg", "kg", "equivalent mass m of the wheel spindle")
        .positive()
        .required();
    t.add(&P::damping_n_s_per_m, "damping_n_s_per_m", "N s/m", "measured damping c0 of the spindle")
        .positive()
        .required();
    t.add(&P::stiffness_n_per_m, "stiffness_n_per_m", "N/m", "spindle stiffness k")
        .positive()
        .required();
    t.add(&P::wheel_wear_compliance_m_per_n, "wheel_wear_compliance_m_per_n", "m/N",
          "wheel wear compliance Kg = 1/kg")
        .positive()
        .required();
    t.add(&P::work_removal_compliance_m_per_n, "work_removal_compliance_m_per_n", "m/N",
          "workpiece grinding (removal) compliance Kw = 1/kw")
        .positive()
        .required();
    t.add(&P::contact_compliance_m_per_n, "contact_compliance_m_per_n", "m/N",
          "wheel-work contact compliance Kc = 1/kc (rigid contact: a small value)")
        .positive()
        .required();
    t.add(&P::wheel_speed_rpm, "wheel_speed_rpm", "rpm", "wheel speed n_g; Tg = 60/n_g")
        .positive()
        .required();
    t.add(&P::work_speed_rpm, "work_speed_rpm", "rpm", "workpiece speed n_w; Tw = 60/n_w")
        .positive()
        .required();
    return t;
  }();
  return table;
}

Json number_or_null(std::optional<double> value) { return value ? Json(*value) : Json(); }

}  // namespace

Thompson::Thompson(const ParamValues& values) : Thompson(parameters_table().read(values)) {}
Thompson::Thompson(ThompsonParameters parameters)
    : parameters_(parameters), equivalent_(thompson::equivalent_g1(parameters)) {}

PluginInfo Thompson::info() {
  return PluginInfo{
      .name = "thompson",
      .description = "Thompson's doubly regenerative grinding model with its closed-form "
                     "unconditional/conditional stability criteria (G2 eqs 2-22..2-65)",
      .params = parameters_table().specs(),
      .thread_safety = ThreadSafety::shareable,
      .models_md_ids = "G2 (G1 eq 2-16 with one mode)",
      // One 251.6 Hz mode, zeta 0.05 (c = 2 zeta sqrt(k m)), kc 1e8, kg 1e9, kw 2e8 N/m, the G8
      // speeds: conditionally stable (c0 < c_m = 18.8 kN s/m), chattering at these speeds.
      .example_params = Json::parse(R"({
          "mass_kg": 20.0, "damping_n_s_per_m": 3162.3, "stiffness_n_per_m": 5.0e7,
          "wheel_wear_compliance_m_per_n": 1.0e-9, "work_removal_compliance_m_per_n": 5.0e-9,
          "contact_compliance_m_per_n": 1.0e-8, "wheel_speed_rpm": 1450, "work_speed_rpm": 55
      })"),
  };
}

std::unique_ptr<CharacteristicFunction> Thompson::characteristic() const {
  return std::make_unique<PlungeCharacteristic>(equivalent_);
}

std::optional<double> Thompson::wheel_period_s() const { return 60.0 / parameters_.wheel_speed_rpm; }

std::vector<ClosedFormIndicatorSpec> Thompson::indicator_specs() const {
  return {
      {"hertz_parameter", "H = 1 + 2 Kc/K (eq 2-60)", false},
      {"unconditional_damping_n_s_per_m", "c_m (eq 2-48 with contact): c0 > c_m is stable at all speeds", false},
      {"absolute_stability_damping_n_s_per_m", "damping solving the frequency-domain condition eq 2-65 (equals c_m)", false},
      {"boundary_a1_n_per_m", "conditional boundary a1 (eq 2-51 corrected); null when c0 >= c_m", false},
      {"boundary_a2_n_per_m", "conditional boundary a2 < a1; chatter for a2 < a < a1 (eq 2-52)", false},
      {"boundary_z1", "z1 = a1 K/2 by eq 2-64", false},
      {"boundary_z2", "z2 = a2 K/2 by eq 2-64", false},
      {"speed_critical_damping_n_s_per_m", "largest damping at which these speeds are marginal", false},
      {"speed_stability_index_n_per_m", "stability index a(w) at that crossing (eq 2-39)", false},
      {"speed_crossing_frequency_hz", "frequency of that crossing (eq 2-63)", false},
      {"closed_form_chatter_margin", "speed_critical_damping / c0 - 1: > 0 chatter, < 0 stable", true},
  };
}

std::vector<Json> Thompson::indicator_values() const {
  const ThompsonParameters& p = parameters_;
  const auto band = thompson::conditional_boundaries(p);
  const auto z = thompson::dimensionless_boundaries(p);
  const thompson::SpeedCriterion speeds = thompson::speed_criterion(p);
  const bool crossed = speeds.crossings > 0;
  return {
      thompson::hertz_parameter(p),
      thompson::unconditional_damping_n_s_per_m(p),
      thompson::absolute_stability_damping_eq_2_65_n_s_per_m(p),
      number_or_null(band ? std::optional(band->a1_n_per_m) : std::nullopt),
      number_or_null(band ? std::optional(band->a2_n_per_m) : std::nullopt),
      number_or_null(z ? std::optional(z->z1) : std::nullopt),
      number_or_null(z ? std::optional(z->z2) : std::nullopt),
      speeds.critical_damping_n_s_per_m,
      crossed ? Json(speeds.stability_index_n_per_m) : Json(),
      crossed ? Json(speeds.frequency_rad_s / (2.0 * std::numbers::pi)) : Json(),
      speeds.chatter_margin,
  };
}

std::optional<StiffnessChain> Thompson::stiffness_chain() const {
  return plunge_dynamics::stiffness_chain(thompson::equivalent_g1(parameters_));
}

Complex Thompson::compliance_m_per_n(Complex s) const { return equivalent_.structural_compliance(s); }

CHATTERLAB_REGISTER_MODEL(Thompson);

}  // namespace chatterlab
