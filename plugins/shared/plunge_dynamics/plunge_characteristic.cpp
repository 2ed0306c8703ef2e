#include "shared/plunge_dynamics/plunge_characteristic.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace chatterlab {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// a b as the compiler's inline complex product computes it (re = ac - bd, im = ad + bc), without
// the C99 Annex G recovery of infinite operands that std::complex's operator* checks for after
// every product (E is finite wherever the search evaluates it; a non-finite E is refused either
// way): the same bits, fewer branches in the root search's innermost work.
Complex times(Complex a, Complex b) {
  return {a.real() * b.real() - a.imag() * b.imag(), a.real() * b.imag() + a.imag() * b.real()};
}

// Value and derivative carried together (forward-mode differentiation of the factored E).
struct Dual {
  Complex value;
  Complex derivative;
};
Dual operator*(const Dual& a, const Dual& b) {
  return {times(a.value, b.value), times(a.derivative, b.value) + times(a.value, b.derivative)};
}
Dual operator+(const Dual& a, const Dual& b) { return {a.value + b.value, a.derivative + b.derivative}; }
Dual scaled(double k, const Dual& a) { return {k * a.value, k * a.derivative}; }

// 1 - e^{-T s} and its derivative T e^{-T s}: the regeneration factor of one delay chain.
Dual regeneration_factor(double period_s, Complex s) {
  double magnitude = std::exp(-period_s * s.real());
  double phase = period_s * s.imag();
  Complex delayed(magnitude * std::cos(phase), -magnitude * std::sin(phase));
  return {1.0 - delayed, period_s * delayed};
}

}  // namespace

PlungeCharacteristic::PlungeCharacteristic(const PlungeRegenerativeParameters& p)
    : wheel_period_s_(60.0 / p.wheel_speed_rpm),
      work_period_s_(60.0 / p.work_speed_rpm),
      wheel_on_(p.wheel_regeneration),
      work_on_(p.work_regeneration),
      contact_stiffness_(p.contact_stiffness_n_per_m),
      alpha_(p.wheel_regeneration ? p.contact_stiffness_n_per_m / p.wheel_wear_stiffness_n_per_m : 0.0),
      beta_(p.work_regeneration ? p.contact_stiffness_n_per_m / p.work_removal_stiffness_n_per_m : 0.0) {
  for (const StructuralMode& m : p.modes) {
    double omega = kTwoPi * m.frequency_hz;
    double ratio = p.contact_stiffness_n_per_m / m.stiffness_n_per_m;
    // Two modes with the same w and zeta share the denominator P: multiplying E by P twice would
    // add a spurious zero at the structural pole, so their compliances are merged first.
    auto same = std::find_if(modes_.begin(), modes_.end(), [&](const Mode& q) {
      return q.omega == omega && q.zeta == m.damping_ratio;
    });
    if (same != modes_.end()) {
      same->contact_ratio += ratio;
      continue;
    }
    modes_.push_back({1.0 / (omega * omega), 2.0 * m.damping_ratio / omega, ratio, omega,
                      m.damping_ratio});
  }
}

CharacteristicValue PlungeCharacteristic::evaluate(Complex s) const { return evaluate_with_work_factor(s).e; }

CharacteristicValue PlungeCharacteristic::newton_form(Complex s) const {
  const auto [e, work] = evaluate_with_work_factor(s);
  if (!work_on_) return e;
  // F = E/G with G = B + beta, G' = B': F' = (E' - F G')/G.
  const Complex g = work.value + beta_;
  const Complex f = e.value / g;
  return {f, (e.derivative - f * work.derivative) / g};
}

PlungeCharacteristic::Evaluation PlungeCharacteristic::evaluate_with_work_factor(Complex s) const {
  // Modal product Pi = prod P_i and Q = sum_i (kc/k_i) prod_{j != i} P_j, built incrementally
  // (Q_new = Q P + (kc/k) Pi_old), so a zero of one P_i never has to be divided by.
  Dual product{1.0, 0.0}, coupled{0.0, 0.0};
  const Complex s_squared = times(s, s), two_s = 2.0 * s;
  for (const Mode& m : modes_) {
    Dual denominator{s_squared * m.inverse_omega_squared + s * m.two_zeta_over_omega + 1.0,
                     two_s * m.inverse_omega_squared + m.two_zeta_over_omega};
    coupled = coupled * denominator + scaled(m.contact_ratio, product);
    product = product * denominator;
  }
  const Dual one{1.0, 0.0};
  Dual wheel = wheel_on_ ? regeneration_factor(wheel_period_s_, s) : one;
  Dual work = work_on_ ? regeneration_factor(work_period_s_, s) : one;
  Dual both = wheel * work;
  // E = Pi (A B + alpha B + beta A) + A B Q
  Dual e = product * (both + scaled(alpha_, work) + scaled(beta_, wheel)) + both * coupled;
  return {{e.value, e.derivative}, {work.value, work.derivative}};
}

Complex PlungeCharacteristic::structural_compliance(Complex s) const {
  Complex h = 0.0;
  for (const Mode& m : modes_)
    h += m.contact_ratio / (s * s * m.inverse_omega_squared + s * m.two_zeta_over_omega + 1.0);
  return h / contact_stiffness_;
}

std::vector<Complex> PlungeCharacteristic::neutral_roots(double max_angular_frequency) const {
  std::vector<Complex> roots;
  if (!(wheel_on_ && work_on_)) return roots;  // one chain alone has no zero at s = 0
  // s = 0: A = B = 0 makes every term of E vanish (a uniform change of wheel wear against work
  // removal leaves the force unchanged: cumulative removal, MODELS.md G1 note).
  roots.push_back(0.0);
  // The same holds at every common point of the two lattices 2 pi n/Tg = 2 pi m/Tw, which exist
  // when the speed ratio is rational (e.g. 1450/55 = 290/11: every 265.8 Hz). A wave pattern
  // periodic in both revolutions, worn into the wheel and ground into the work with opposite
  // signs, leaves the force unchanged for ever: the same neutral exchange as s = 0, not chatter.
  // Lattice points that only nearly coincide give genuine roots at Re s ~ -C |delta|^2 < 0 (or > 0
  // where the structure crosses the process line of eq 2-21), which are reported.
  const double ratio = work_period_s_ / wheel_period_s_;
  for (long n = 1; kTwoPi * static_cast<double>(n) / wheel_period_s_ <= max_angular_frequency; ++n) {
    double m_exact = static_cast<double>(n) * ratio;
    double m = std::round(m_exact);
    if (m < 1.0 || std::abs(m_exact - m) > 1e-9 * m_exact) continue;
    double wheel_point = kTwoPi * static_cast<double>(n) / wheel_period_s_;
    double work_point = kTwoPi * m / work_period_s_;
    // Rounding-level offset: the zero of E sits at the alpha/beta-weighted mean (local linear
    // balance alpha Tw (u - delta) + beta Tg u = 0).
    double weight = alpha_ * work_period_s_ / (alpha_ * work_period_s_ + beta_ * wheel_period_s_);
    roots.emplace_back(0.0, wheel_point + weight * (work_point - wheel_point));
  }
  return roots;
}

void PlungeCharacteristic::initial_guesses(double max_angular_frequency,
                                           std::vector<Complex>& guesses) const {
  // One root per lattice point of each active delay chain (the quasi-polynomial is of neutral
  // type: every root lies in a vertical strip and the chains fill it at the lattice density),
  // plus the structural roots. Newton's first step from a lattice point 2 pi n j/T is the
  // chain's first-order shift, so the raw lattice point is a good guess, except where a wheel
  // and a work lattice point nearly coincide: there two roots share a neighbourhood and the
  // local quadratic below separates them.
  const double tg = wheel_period_s_, tw = work_period_s_;
  const long wheel_points = wheel_on_ ? static_cast<long>(max_angular_frequency * tg / kTwoPi) + 2 : 0;
  const long work_points = work_on_ ? static_cast<long>(max_angular_frequency * tw / kTwoPi) + 2 : 0;
  std::vector<bool> work_point_paired(static_cast<std::size_t>(std::max(work_points, 0L)), false);
  guesses.reserve(guesses.size() + static_cast<std::size_t>(wheel_points + work_points) + 2 * modes_.size() + 2);

  for (long n = 0; n < wheel_points; ++n) {
    const Complex wheel_point(0.0, kTwoPi * static_cast<double>(n) / tg);
    long m = std::lround(static_cast<double>(n) * tw / tg);
    Complex delta = Complex(0.0, kTwoPi * static_cast<double>(m) / tw) - wheel_point;
    if (!work_on_ || m >= work_points || std::abs(delta) * tw > 0.5) {
      guesses.push_back(wheel_point);
      continue;
    }
    // A ~ Tg u, B ~ Tw (u - delta) near the pair (u = s - wheel_point); E/Pi = K A B + alpha B +
    // beta A = 0 with K = 1 + kc H becomes a quadratic in u.
    work_point_paired[static_cast<std::size_t>(m)] = true;
    Complex k = 1.0 + contact_stiffness_ * structural_compliance(wheel_point);
    Complex a2 = k * tg * tw;
    Complex a1 = alpha_ * tw + beta_ * tg - a2 * delta;
    Complex a0 = -alpha_ * tw * delta;
    Complex root_disc = std::sqrt(a1 * a1 - 4.0 * a2 * a0);
    if ((std::conj(a1) * root_disc).real() < 0.0) root_disc = -root_disc;
    Complex q = -0.5 * (a1 + root_disc);  // the larger-magnitude root without cancellation
    if (std::abs(a2) > 0.0) guesses.push_back(wheel_point + q / a2);
    if (std::abs(q) > 0.0) guesses.push_back(wheel_point + a0 / q);
  }
  for (long m = 0; m < work_points; ++m) {
    if (work_point_paired[static_cast<std::size_t>(m)]) continue;
    if (m == 0 && wheel_on_) continue;  // s = 0 is neutral; the n = 0 pair covers its neighbour
    guesses.emplace_back(0.0, kTwoPi * static_cast<double>(m) / tw);
  }
  // Structural roots: the open-loop pole and the pole stiffened by the contact and the averaged
  // regeneration terms (the mean of 1/(1 - e^{-Ts}) over a lattice period is 1).
  const double mean_process = 1.0 + alpha_ + beta_;
  for (const Mode& m : modes_) {
    double z = std::min(m.zeta, 0.999);
    guesses.emplace_back(-z * m.omega, m.omega * std::sqrt(1.0 - z * z));
    double stiffened = 1.0 + m.contact_ratio / mean_process;
    guesses.emplace_back(-z * m.omega, m.omega * std::sqrt(std::max(stiffened - z * z, 0.0)));
  }
}

double PlungeCharacteristic::real_part_bound() const {
  // For Re s = sigma > 0: Re 1/(1 - e^{-Ts}) > 1/2 (the map 1/(1 - z) sends |z| < 1 into
  // Re > 1/2), so Re D > nu - kc |H| with nu = 1 + alpha/2 + beta/2; and |P_i(s)| >= sigma^2/w_i^2
  // (both poles have Re <= 0), so kc |H| <= sum (kc/k_i) w_i^2 / sigma^2. Hence D != 0 (and E =
  // D A B Pi != 0: A, B, Pi have no zeros with Re s > 0) once sigma^2 >= sum (kc/k_i) w_i^2 / nu.
  const double nu = 1.0 + 0.5 * alpha_ + 0.5 * beta_;
  double sum = 0.0;
  for (const Mode& m : modes_) sum += m.contact_ratio * m.omega * m.omega;
  return 1.001 * std::sqrt(sum / nu) + 1e-9;
}

double PlungeCharacteristic::natural_frequency_scale_hz() const {
  double highest = 0.0;
  for (const Mode& m : modes_) highest = std::max(highest, m.omega / kTwoPi);
  return highest;
}

}  // namespace chatterlab
