// Stability lobes by bracketing, polishing and continuation (lobe_tracer.hpp has the method).
#include "study_kinds/stability_lobes/lobe_tracer.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <exception>
#include <mutex>
#include <numbers>

#include "chatterlab/errors.hpp"
#include "chatterlab/nyquist.hpp"
#include "chatterlab/roots.hpp"

namespace chatterlab::lobes {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kParameterStep = 1e-7;  // relative step of the difference dG/dp

// A model seen on the imaginary axis through one route: G(w) and dG/dw.
class Axis {
 public:
  Axis(const Model& model, Route route) {
    if (route == Route::roots) {
      e_ = model.characteristic();
      if (!e_) throw PointFailure("the model has no characteristic function here");
    } else {
      f_ = model.return_difference();
      if (!f_) throw PointFailure("the model has no return difference (Nyquist route) here");
    }
  }
  CharacteristicValue at(double w) const {
    if (e_) {
      const CharacteristicValue v = e_->evaluate(Complex(0.0, w));
      return {v.value, Complex(0.0, 1.0) * v.derivative};  // dE(j w)/dw = j E'
    }
    return f_->at(w);
  }
  // Where G turns fast: the roots route's starting guesses (delay lattices, structural poles), the
  // Nyquist route's fast frequencies.
  std::vector<double> marks(double max_rad_s) const {
    std::vector<double> out;
    if (e_) {
      std::vector<Complex> guesses;
      e_->initial_guesses(max_rad_s, guesses);
      for (const Complex& g : guesses)
        if (g.imag() > 0.0 && g.imag() <= max_rad_s) out.push_back(g.imag());
    } else {
      f_->fast_frequencies(max_rad_s, out);
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }
  // Frequencies where G vanishes for every p (declared neutral roots): never crossings.
  std::vector<double> neutral(double max_rad_s) const {
    std::vector<double> out;
    if (e_)
      for (const Complex& r : e_->neutral_roots(max_rad_s)) out.push_back(r.imag());
    return out;
  }

 private:
  std::unique_ptr<CharacteristicFunction> e_;
  std::unique_ptr<ReturnDifference> f_;
};

double typical_spacing(const std::vector<double>& marks, double band_rad_s) {
  std::vector<double> gaps;
  for (std::size_t i = 1; i < marks.size(); ++i)
    if (marks[i] > marks[i - 1]) gaps.push_back(marks[i] - marks[i - 1]);
  if (gaps.empty()) return band_rad_s / 200.0;
  std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2), gaps.end());
  return std::min(gaps[gaps.size() / 2], band_rad_s / 200.0);
}

bool in_range(double p, const TraceSettings& s) { return p >= s.parameter_min && p <= s.parameter_max; }

// ---------------------------------------------------------------- the crossings at one speed

// The value at x of the Moebius map sending xs[k] to ys[k] (cross ratios are invariant).
Complex moebius(Complex x, const std::array<Complex, 3>& xs, const std::array<Complex, 3>& ys) {
  const Complex c = ((x - xs[1]) * (xs[0] - xs[2])) / ((x - xs[2]) * (xs[0] - xs[1]));
  return (ys[1] * (ys[0] - ys[2]) - c * ys[2] * (ys[0] - ys[1])) / ((ys[0] - ys[2]) - c * (ys[0] - ys[1]));
}

bool near_neutral(const std::vector<double>& neutral, double w, double spacing) {
  return std::any_of(neutral.begin(), neutral.end(), [&](double n) { return std::abs(n - w) <= 1e-6 * spacing; });
}

// Sample frequencies of a scan over (0, band): a uniform grid of an eighth of the typical spacing,
// plus geometric offsets on both sides of every mark.
std::vector<double> scan_grid(const std::vector<double>& marks, double spacing, double band) {
  std::vector<double> w;
  const double step = spacing / 8.0;
  for (double x = step; x < band; x += step) w.push_back(x);
  for (double m : marks)
    for (double f : {1e-9, 1e-7, 1e-5, 1e-3, 1e-2, 0.05}) {
      w.push_back(m - f * spacing);
      w.push_back(m + f * spacing);
    }
  std::sort(w.begin(), w.end());
  w.erase(std::remove_if(w.begin(), w.end(), [&](double x) { return !(x > 0.0 && x < band); }), w.end());
  w.erase(std::unique(w.begin(), w.end()), w.end());
  return w;
}

// The crossings at one speed: all of them in the range (scan) or the one near a guess (near).
class View {
 public:
  View(double speed, const TraceSettings& s) : speed_(speed), s_(s) {}
  virtual ~View() = default;
  virtual std::vector<Crossing> scan() const = 0;
  virtual std::optional<Crossing> near(const Crossing& guess) const = 0;
  double spacing() const { return spacing_; }

 protected:
  double speed_;
  const TraceSettings& s_;
  double spacing_ = 0.0;
};

// For a parameter entering G as a Moebius map (affine included: every stiffness of G1, in E and in
// F): three models at p0, p1, p2 give, at any w, the one p that makes G vanish there,
// p*(w) = M^{-1}(0); it is real exactly at a crossing. So the crossings are the zeros of
// Im p*(w), bracketed on the scan grid and polished by the Illinois method, without building
// another model.
class MoebiusView final : public View {
 public:
  MoebiusView(const ModelAt& model_at, double speed, const TraceSettings& s, std::array<double, 3> p)
      : View(speed, s),
        p_(p),
        m0_(model_at(p[0], speed)), m1_(model_at(p[1], speed)), m2_(model_at(p[2], speed)),
        axes_{Axis(*m0_, s.route), Axis(*m1_, s.route), Axis(*m2_, s.route)} {
    const double band = kTwoPi * s.max_frequency_hz;
    marks_ = axes_[0].marks(band);
    neutral_ = axes_[0].neutral(band);
    spacing_ = typical_spacing(marks_, band);
  }

  std::vector<Crossing> scan() const override {
    std::vector<Crossing> found;
    const std::vector<double> w = scan_grid(marks_, spacing_, kTwoPi * s_.max_frequency_hz);
    Complex previous = parameter_at(w.front());
    for (std::size_t i = 1; i < w.size(); ++i) {
      const Complex current = parameter_at(w[i]);
      if (const auto c = bracketed(w[i - 1], previous, w[i], current))
        if (std::none_of(found.begin(), found.end(), [&](const Crossing& k) { return same_frequency(k, *c); }))
          found.push_back(*c);
      previous = current;
    }
    return found;
  }

  std::optional<Crossing> near(const Crossing& guess) const override {
    // Sign changes within half a spacing of the guess; the one closest to it.
    constexpr int n = 16;
    std::optional<Crossing> best;
    double x0 = guess.omega_rad_s - 0.5 * spacing_;
    Complex v0 = parameter_at(x0);
    for (int k = 1; k <= 2 * n; ++k) {
      const double x1 = guess.omega_rad_s + (k - n) * spacing_ / (2.0 * n);
      const Complex v1 = parameter_at(x1);
      if (const auto c = bracketed(x0, v0, x1, v1))
        if (!best || std::abs(c->omega_rad_s - guess.omega_rad_s) < std::abs(best->omega_rad_s - guess.omega_rad_s))
          best = c;
      x0 = x1, v0 = v1;
    }
    if (best && std::abs(best->omega_rad_s - guess.omega_rad_s) < spacing_ / 3.0) return best;
    return std::nullopt;
  }

 private:
  Complex parameter_at(double w) const {
    if (!(w > 0.0)) return NAN;
    const std::array<Complex, 3> g{axes_[0].at(w).value, axes_[1].at(w).value, axes_[2].at(w).value};
    if (g[0] == g[1] || g[1] == g[2] || g[0] == g[2]) return NAN;  // G does not depend on p here
    return moebius(0.0, g, {p_[0], p_[1], p_[2]});
  }

  bool same_frequency(const Crossing& a, const Crossing& b) const {
    return std::abs(a.omega_rad_s - b.omega_rad_s) <= 1e-9 * a.omega_rad_s;
  }

  // The crossing between a and b when Im p* changes sign there (and p* is not passing a pole).
  std::optional<Crossing> bracketed(double a, Complex pa, double b, Complex pb) const {
    if (!std::isfinite(pa.imag()) || !std::isfinite(pb.imag()) || std::signbit(pa.imag()) == std::signbit(pb.imag()))
      return std::nullopt;
    // A pole of p* also flips the sign of Im p*: there p* is far outside the range.
    const auto plausible = [&](Complex p) {
      return p.real() > 0.0 && p.real() < 100.0 * s_.parameter_max && p.real() > 0.01 * s_.parameter_min;
    };
    if (!plausible(pa) && !plausible(pb)) return std::nullopt;
    double fa = pa.imag(), fb = pb.imag();
    int side = 0;
    double x = a;
    Complex px = pa;
    for (int i = 0; i < 100 && b - a > 1e-14 * b; ++i) {
      x = (a * fb - b * fa) / (fb - fa);
      px = parameter_at(x);
      if (!std::isfinite(px.imag())) return std::nullopt;
      if (px.imag() == 0.0) break;
      if (std::signbit(px.imag()) == std::signbit(fa)) {
        a = x, fa = px.imag();
        if (side == -1) fb *= 0.5;
        side = -1;
      } else {
        b = x, fb = px.imag();
        if (side == 1) fa *= 0.5;
        side = 1;
      }
    }
    if (!(std::abs(px.imag()) <= 1e-6 * std::abs(px)) || !in_range(px.real(), s_) || near_neutral(neutral_, x, spacing_))
      return std::nullopt;
    return Crossing{speed_, px.real(), x};
  }

  std::array<double, 3> p_;
  std::unique_ptr<Model> m0_, m1_, m2_;
  std::array<Axis, 3> axes_;
  std::vector<double> marks_, neutral_;
};

// For any other parameter: sign changes of Im(G conj dG/dp) at a reference p seed a Newton
// iteration on (w, p) with a model built at every step.
class NewtonView final : public View {
 public:
  NewtonView(const ModelAt& model_at, double speed, const TraceSettings& s) : View(speed, s), model_at_(model_at) {
    const auto m = model_at(std::sqrt(s.parameter_min * s.parameter_max), speed);
    const Axis axis(*m, s.route);
    const double band = kTwoPi * s.max_frequency_hz;
    marks_ = axis.marks(band);
    neutral_ = axis.neutral(band);
    spacing_ = typical_spacing(marks_, band);
  }

  std::vector<Crossing> scan() const override {
    const double p_ref = std::sqrt(s_.parameter_min * s_.parameter_max), dp = kParameterStep * p_ref;
    const auto m0 = model_at_(p_ref, speed_), m1 = model_at_(p_ref + dp, speed_);
    const Axis a0(*m0, s_.route), a1(*m1, s_.route);
    struct Sample {
      double psi, p_est;
    };
    auto sample = [&](double x) {
      const Complex g = a0.at(x).value, gp = (a1.at(x).value - g) / dp;
      return Sample{(g * std::conj(gp)).imag(), gp == 0.0 ? NAN : p_ref - (g / gp).real()};
    };
    std::vector<Crossing> found;
    const std::vector<double> w = scan_grid(marks_, spacing_, kTwoPi * s_.max_frequency_hz);
    Sample previous = sample(w.front());
    for (std::size_t i = 1; i < w.size(); ++i) {
      const Sample current = sample(w[i]);
      if (std::signbit(previous.psi) != std::signbit(current.psi) && previous.psi != 0.0) {
        const double x = w[i - 1] + previous.psi / (previous.psi - current.psi) * (w[i] - w[i - 1]);
        const Sample at = sample(x);
        if (!near_neutral(neutral_, x, spacing_) && at.p_est > 0.25 * s_.parameter_min && at.p_est < 4.0 * s_.parameter_max)
          if (const auto c = correct(model_at_, Crossing{speed_, at.p_est, x}, s_.route, spacing_); c && in_range(c->parameter, s_))
            if (std::none_of(found.begin(), found.end(), [&](const Crossing& k) {
                  return std::abs(k.omega_rad_s - c->omega_rad_s) <= 1e-7 * c->omega_rad_s;
                }))
              found.push_back(*c);
      }
      previous = current;
    }
    return found;
  }

  std::optional<Crossing> near(const Crossing& guess) const override {
    const auto c = correct(model_at_, Crossing{speed_, guess.parameter, guess.omega_rad_s}, s_.route, spacing_);
    if (c && in_range(c->parameter, s_) && std::abs(c->omega_rad_s - guess.omega_rad_s) < spacing_ / 3.0) return c;
    return std::nullopt;
  }

 private:
  const ModelAt& model_at_;
  std::vector<double> marks_, neutral_;
};

// Whether p enters G as a Moebius map: a fourth model must agree with the map through three, at
// frequencies spread over the band (checked once, at the first speed).
bool moebius_in_parameter(const ModelAt& model_at, double speed, const TraceSettings& s, const std::array<double, 3>& p) {
  const double p3 = 3.7 * p[1];
  std::array<std::unique_ptr<Model>, 4> models{model_at(p[0], speed), model_at(p[1], speed), model_at(p[2], speed),
                                               model_at(p3, speed)};
  std::vector<Axis> axes;
  for (const auto& m : models) axes.emplace_back(*m, s.route);
  for (int k = 0; k < 24; ++k) {
    const double w = kTwoPi * s.max_frequency_hz * (k + 0.3819) / 24.0;
    const std::array<Complex, 3> g{axes[0].at(w).value, axes[1].at(w).value, axes[2].at(w).value};
    const Complex g3 = axes[3].at(w).value;
    const double scale = std::max({std::abs(g[0]), std::abs(g[1]), std::abs(g[2]), std::abs(g3)});
    if (g[0] == g[1] || g[1] == g[2]) continue;
    const Complex predicted = moebius(p3, {p[0], p[1], p[2]}, g);
    if (!(std::abs(predicted - g3) <= 1e-7 * scale)) return false;
  }
  return true;
}

// ---------------------------------------------------------------- continuation along a lobe

// The boundary's direction at a crossing when the speed changes: G_w dw + G_p dp + G_v dv = 0.
Crossing tangent_predict(const ModelAt& model_at, const Crossing& c, double speed, Route route) {
  const BoundaryDerivatives d = boundary_derivatives(model_at, c, route);
  const double dv = 1e-6 * c.speed;
  const Complex g0 = axis_value(*model_at(c.parameter, c.speed), c.omega_rad_s, route);
  const Complex g_v = (axis_value(*model_at(c.parameter, c.speed + dv), c.omega_rad_s, route) - g0) / dv;
  const double det = d.g_omega.real() * d.g_parameter.imag() - d.g_omega.imag() * d.g_parameter.real();
  const double step = speed - c.speed;
  const double d_omega = -(g_v.real() * d.g_parameter.imag() - g_v.imag() * d.g_parameter.real()) / det * step;
  const double d_p = -(d.g_omega.real() * g_v.imag() - d.g_omega.imag() * g_v.real()) / det * step;
  Crossing p{speed, c.parameter + d_p, c.omega_rad_s + d_omega};
  if (!(p.parameter > 0.0) || !std::isfinite(p.parameter) || !std::isfinite(p.omega_rad_s)) return {speed, c.parameter, c.omega_rad_s};
  return p;
}

Crossing predict(const ModelAt& model_at, const Lobe& lobe, double speed, bool forward, Route route) {
  const auto& pts = lobe.points;
  const Crossing& last = forward ? pts.back() : pts.front();
  if (pts.size() < 2) {
    try {
      return tangent_predict(model_at, last, speed, route);
    } catch (const std::exception&) {
      return {speed, last.parameter, last.omega_rad_s};
    }
  }
  const Crossing& before = forward ? pts[pts.size() - 2] : pts[1];
  const double t = (speed - last.speed) / (last.speed - before.speed);
  Crossing c{speed, last.parameter + t * (last.parameter - before.parameter),
             last.omega_rad_s + t * (last.omega_rad_s - before.omega_rad_s)};
  if (!(c.parameter > 0.0)) c.parameter = last.parameter;
  return c;
}

struct Tracer {
  const ModelAt& model_at;
  const TraceSettings& s;
  bool moebius = false;
  std::array<double, 3> p{};
  std::atomic<int> corrections{0};
  static constexpr int max_halvings = 4;

  std::unique_ptr<View> view(double speed) const {
    if (moebius) return std::make_unique<MoebiusView>(model_at, speed, s, p);
    return std::make_unique<NewtonView>(model_at, speed, s);
  }

  // The lobe's point at `speed` (a view there given), from its end (forward: its last point),
  // with points added at halved speed steps when the direct step finds no crossing near the
  // prediction (the lobe turns faster than the step resolves).
  std::vector<Crossing> step(const Lobe& lobe, const View& at, double speed, bool forward, int depth = 0) {
    ++corrections;
    if (const auto c = at.near(predict(model_at, lobe, speed, forward, s.route))) return {*c};
    if (depth == max_halvings) return {};
    const double from = forward ? lobe.points.back().speed : lobe.points.front().speed;
    const double middle = 0.5 * (from + speed);
    std::unique_ptr<View> mid;
    try {
      mid = view(middle);
    } catch (const std::exception&) {
      return {};
    }
    std::vector<Crossing> first = step(lobe, *mid, middle, forward, depth + 1);
    if (first.empty()) return {};
    Lobe probe;
    probe.points = forward ? std::vector<Crossing>{lobe.points.back(), first.back()}
                           : std::vector<Crossing>{first.back(), lobe.points.front()};
    std::vector<Crossing> second = step(probe, at, speed, forward, depth + 1);
    if (second.empty()) return {};
    first.insert(first.end(), second.begin(), second.end());
    return first;
  }
};

bool same_crossing(const Crossing& a, const Crossing& b) {
  return std::abs(a.omega_rad_s - b.omega_rad_s) <= 1e-6 * std::max(a.omega_rad_s, 1.0) &&
         std::abs(a.parameter - b.parameter) <= 1e-6 * a.parameter;
}

// ---------------------------------------------------------------- the envelope

// Where lobes a and b (a lowest at speed v0, b lowest at v1) intersect: regula falsi (Illinois)
// on p_a(v) - p_b(v), each p from a view at that speed.
std::optional<Crossing> intersection(Tracer& t, const Lobe& a, const Lobe& b, double v0, double v1) {
  auto point_at = [&](const Lobe& lobe, const View& view, double v) -> std::optional<Crossing> {
    Lobe part;
    for (const Crossing& c : lobe.points)
      if (c.speed <= v) part.points.push_back(c);
    if (part.points.empty()) return std::nullopt;
    return view.near(predict(t.model_at, part, v, true, t.s.route));
  };
  auto difference = [&](double v) -> std::optional<std::pair<double, Crossing>> {
    const auto view = t.view(v);
    const auto pa = point_at(a, *view, v), pb = point_at(b, *view, v);
    if (!pa || !pb) return std::nullopt;
    return std::pair{pa->parameter - pb->parameter, pa->parameter <= pb->parameter ? *pa : *pb};
  };
  std::optional<std::pair<double, Crossing>> d0, d1;
  try {
    d0 = difference(v0), d1 = difference(v1);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (!d0 || !d1 || !(d0->first < 0.0) || !(d1->first > 0.0)) return std::nullopt;
  double lo = v0, hi = v1, f_lo = d0->first, f_hi = d1->first;
  Crossing best = d0->second;
  int side = 0;
  for (int i = 0; i < 40 && hi - lo > 1e-12 * std::abs(hi); ++i) {
    const double v = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
    std::optional<std::pair<double, Crossing>> d;
    try {
      d = difference(v);
    } catch (const std::exception&) {
      return std::nullopt;
    }
    if (!d) return std::nullopt;
    best = d->second;
    if (d->first == 0.0) break;
    if ((d->first < 0.0) == (f_lo < 0.0)) {
      lo = v, f_lo = d->first;
      if (side == -1) f_hi *= 0.5;
      side = -1;
    } else {
      hi = v, f_hi = d->first;
      if (side == 1) f_lo *= 0.5;
      side = 1;
    }
    if (std::abs(d->first) <= 1e-10 * best.parameter) break;
  }
  return best;
}

// The point of the envelope at the speed of `candidate` (a crossing between speeds v0 and v1):
// `candidate`, or a lower crossing of a lobe present at both speeds.
Crossing lowest_at(Tracer& t, const std::vector<Lobe>& lobes, double v0, double v1, const Crossing& candidate) {
  Crossing lowest = candidate;
  std::unique_ptr<View> view;
  try {
    view = t.view(candidate.speed);
  } catch (const std::exception&) {
    return lowest;
  }
  for (const Lobe& lobe : lobes) {
    Lobe part;
    bool after = false;
    for (const Crossing& c : lobe.points) {
      if (c.speed <= candidate.speed && c.speed >= v0) part.points.push_back(c);
      after = after || (c.speed >= candidate.speed && c.speed <= v1);
    }
    if (part.points.empty() || !after) continue;
    if (const auto c = view->near(predict(t.model_at, part, candidate.speed, true, t.s.route)))
      if (c->parameter < lowest.parameter) lowest = *c;
  }
  return lowest;
}

}  // namespace

// ---------------------------------------------------------------- public functions

void for_each_index(std::size_t n, const std::function<void(std::size_t)>& fn) {
  std::exception_ptr error;
  std::mutex mutex;
  auto guarded = [&](std::size_t i) {
    try {
      fn(i);
    } catch (...) {
      std::lock_guard lock(mutex);
      if (!error) error = std::current_exception();
    }
  };
  const auto count = static_cast<long>(n);
  if (omp_in_parallel()) {
#pragma omp taskloop grainsize(1)
    for (long i = 0; i < count; ++i) guarded(static_cast<std::size_t>(i));
  } else {
#pragma omp parallel
#pragma omp single
#pragma omp taskloop grainsize(1)
    for (long i = 0; i < count; ++i) guarded(static_cast<std::size_t>(i));
  }
  if (error) std::rethrow_exception(error);
}

Complex axis_value(const Model& model, double omega_rad_s, Route route) {
  return Axis(model, route).at(omega_rad_s).value;
}

BoundaryDerivatives boundary_derivatives(const ModelAt& model_at, const Crossing& c, Route route) {
  const double dp = kParameterStep * c.parameter;
  const auto m0 = model_at(c.parameter, c.speed), m1 = model_at(c.parameter + dp, c.speed);
  const CharacteristicValue g = Axis(*m0, route).at(c.omega_rad_s);
  return {g.derivative, (Axis(*m1, route).at(c.omega_rad_s).value - g.value) / dp};
}

double parameter_derivative(const BoundaryDerivatives& d, Complex g_q) {
  // [Re g_w  Re g_p] [dw]     [Re g_q]
  // [Im g_w  Im g_p] [dp] = - [Im g_q]   (Cramer's rule for dp)
  const double det = d.g_omega.real() * d.g_parameter.imag() - d.g_omega.imag() * d.g_parameter.real();
  return -(d.g_omega.real() * g_q.imag() - d.g_omega.imag() * g_q.real()) / det;
}

std::optional<Crossing> correct(const ModelAt& model_at, const Crossing& guess, Route route, double spacing) {
  Crossing c = guess;
  if (!(c.parameter > 0.0) || !(c.omega_rad_s > 0.0)) return std::nullopt;
  try {
    for (int iteration = 0; iteration < 40; ++iteration) {
      const double dp = kParameterStep * c.parameter;
      const auto m0 = model_at(c.parameter, c.speed), m1 = model_at(c.parameter + dp, c.speed);
      const CharacteristicValue g = Axis(*m0, route).at(c.omega_rad_s);
      const Complex g_p = (Axis(*m1, route).at(c.omega_rad_s).value - g.value) / dp;
      const double det = g.derivative.real() * g_p.imag() - g.derivative.imag() * g_p.real();
      if (!(std::abs(det) > 0.0) || !std::isfinite(det)) return std::nullopt;
      double d_omega = -(g.value.real() * g_p.imag() - g.value.imag() * g_p.real()) / det;
      double d_p = -(g.derivative.real() * g.value.imag() - g.derivative.imag() * g.value.real()) / det;
      // Damped: never more than a quarter lattice spacing (the next lobe) or half the parameter.
      const double shrink = std::max({1.0, std::abs(d_omega) / (0.25 * spacing), std::abs(d_p) / (0.5 * c.parameter)});
      d_omega /= shrink;
      d_p /= shrink;
      c.omega_rad_s += d_omega;
      c.parameter += d_p;
      if (!(c.parameter > 0.0) || !(c.omega_rad_s > 0.0) || !std::isfinite(c.parameter)) return std::nullopt;
      if (shrink == 1.0 && std::abs(d_omega) <= 1e-12 * c.omega_rad_s && std::abs(d_p) <= 1e-11 * c.parameter)
        return c;
    }
  } catch (const PointFailure&) {
    return std::nullopt;  // a model that cannot be built or evaluated here
  } catch (const InputError&) {
    return std::nullopt;  // e.g. a parameter value the model refuses
  }
  return std::nullopt;
}

StabilityCheck check_stability(const Model& model, Route route, double band_hz) {
  StabilityCheck out;
  if (route == Route::roots) {
    auto e = model.characteristic();
    RootSearchOptions options;
    options.max_frequency_hz = band_hz;
    const RightmostRoot r = find_rightmost_root(*e, options);
    out.growth_rate_per_s = r.root.real();
    if (r.certified || r.root.real() > 0.0) out.stable = r.root.real() < 0.0;
    else out.reason = r.certificate;
    return out;
  }
  const NyquistCount n = count_unstable_roots(*model.return_difference());
  if (n.reliable) out.stable = n.unstable_roots == 0;
  else out.reason = n.note;
  return out;
}

namespace {

// Links the crossings found at speed index i to the living lobes: each lobe takes the crossing
// nearest its prediction (within a third of a spacing, never one another lobe took), else tries
// halved steps; seeds nobody took start new lobes, which are also followed backwards.
void continue_lobes(Tracer& tracer, const std::vector<double>& speeds, std::size_t i,
                    const std::vector<std::unique_ptr<View>>& views, std::vector<std::vector<Crossing>>& scans,
                    std::vector<Lobe>& lobes, std::vector<bool>& alive) {
  std::vector<bool> taken(scans[i].size(), false);
  std::vector<std::vector<Crossing>> steps(lobes.size());
  if (i > 0) {
    // The direct matches first (cheap, sequential: the order decides conflicts deterministically).
    std::vector<std::size_t> unmatched;
    for (std::size_t k = 0; k < lobes.size(); ++k) {
      if (!alive[k]) continue;
      const Crossing guess = predict(tracer.model_at, lobes[k], speeds[i], true, tracer.s.route);
      std::optional<std::size_t> best;
      for (std::size_t j = 0; j < scans[i].size(); ++j)
        if (!taken[j] && std::abs(scans[i][j].omega_rad_s - guess.omega_rad_s) < views[i]->spacing() / 3.0 &&
            (!best || std::abs(scans[i][j].omega_rad_s - guess.omega_rad_s) <
                          std::abs(scans[i][*best].omega_rad_s - guess.omega_rad_s)))
          best = j;
      if (best) {
        taken[*best] = true;
        steps[k] = {scans[i][*best]};
      } else {
        unmatched.push_back(k);
      }
    }
    // The rest by halved steps, in parallel.
    for_each_index(unmatched.size(), [&](std::size_t u) {
      const std::size_t k = unmatched[u];
      steps[k] = tracer.step(lobes[k], *views[i], speeds[i], true);
    });
    for (std::size_t k = 0; k < lobes.size(); ++k) {
      if (!alive[k]) continue;
      if (steps[k].empty()) {
        alive[k] = false;
        continue;
      }
      // A halved-step result may be a crossing the scan found too: take it off the seeds.
      for (std::size_t j = 0; j < scans[i].size(); ++j)
        if (!taken[j] && same_crossing(scans[i][j], steps[k].back())) taken[j] = true;
      lobes[k].points.insert(lobes[k].points.end(), steps[k].begin(), steps[k].end());
    }
  }
  for (std::size_t j = 0; j < scans[i].size(); ++j) {
    if (taken[j]) continue;
    Lobe lobe;
    lobe.id = static_cast<int>(lobes.size()) + 1;
    lobe.points.push_back(scans[i][j]);
    for (std::size_t b = i; b-- > 0;) {
      std::vector<Crossing> back = tracer.step(lobe, *views[b], speeds[b], false);
      if (back.empty() || std::any_of(lobes.begin(), lobes.end(), [&](const Lobe& other) {
            return std::any_of(other.points.begin(), other.points.end(), [&](const Crossing& c) {
              return c.speed == back.back().speed && same_crossing(c, back.back());
            });
          }))
        break;
      lobe.points.insert(lobe.points.begin(), back.rbegin(), back.rend());
    }
    lobes.push_back(std::move(lobe));
    alive.push_back(true);
  }
}

// The limit at each speed: the lowest crossing when the range's lower end is stable, the highest
// when only its upper end is.
void limits(LobeDiagram& d, const std::vector<StabilityCheck>& lower, const std::vector<StabilityCheck>& upper) {
  for (std::size_t i = 0; i < d.speeds.size(); ++i) {
    SpeedResult& r = d.at[i];
    if (!lower[i].stable) {
      r.note = "no stability verdict at the lower end of parameter_range" +
               (lower[i].reason.empty() ? std::string() : ": " + lower[i].reason);
      continue;
    }
    if (!*lower[i].stable) {
      if (!upper[i].stable) {
        r.note = "unstable at the lower end of parameter_range, no verdict at the upper end" +
                 (upper[i].reason.empty() ? std::string() : ": " + upper[i].reason);
        continue;
      }
      if (!*upper[i].stable) {
        r.note = "unstable over the whole range";
        continue;
      }
      r.stable_below = false;
    }
    for (const Lobe& lobe : d.lobes)
      for (const Crossing& c : lobe.points)
        if (c.speed == d.speeds[i] &&
            (!r.limit || (r.stable_below ? c.parameter < r.limit->parameter : c.parameter > r.limit->parameter))) {
          r.limit = c;
          r.lobe = lobe.id;
        }
    if (!r.limit) r.note = "no crossing in parameter_range: stable over the whole range";
  }
}

}  // namespace

LobeDiagram trace_lobes(const ModelAt& model_at, const std::vector<double>& speeds, const TraceSettings& s) {
  LobeDiagram d;
  d.speeds = speeds;
  d.at.resize(speeds.size());
  Tracer tracer{model_at, s};
  const double p_ref = std::sqrt(s.parameter_min * s.parameter_max);
  tracer.p = {0.5 * p_ref, p_ref, 2.0 * p_ref};
  tracer.moebius = moebius_in_parameter(model_at, speeds.front(), s, tracer.p);
  d.parameter_enters_as_moebius_map = tracer.moebius;
  // Every speed's crossings and the check at the range's lower end, independently.
  std::vector<std::unique_ptr<View>> views(speeds.size());
  std::vector<std::vector<Crossing>> scans(speeds.size());
  std::vector<StabilityCheck> lower(speeds.size()), upper(speeds.size());
  for_each_index(speeds.size(), [&](std::size_t i) {
    try {
      views[i] = tracer.view(speeds[i]);
      scans[i] = views[i]->scan();
      lower[i] = check_stability(*model_at(s.parameter_min, speeds[i]), s.route, s.max_frequency_hz);
      if (lower[i].stable == false)
        upper[i] = check_stability(*model_at(s.parameter_max, speeds[i]), s.route, s.max_frequency_hz);
    } catch (const std::exception& e) {
      lower[i].stable.reset();
      lower[i].reason = e.what();
    }
  });
  std::vector<bool> alive;
  for (std::size_t i = 0; i < speeds.size(); ++i) {
    d.seeds += static_cast<int>(scans[i].size());
    if (!views[i]) continue;  // nothing computable at this speed: its lobes end here
    continue_lobes(tracer, speeds, i, views, scans, d.lobes, alive);
  }
  d.corrections = tracer.corrections;
  limits(d, lower, upper);
  // Envelope: the limits plus, where the lowest lobe changes between two speeds, the two lobes'
  // intersection, unless a third lobe present at both speeds lies lower there (the speed step was
  // too coarse to show that lobe as the lowest).
  std::vector<std::optional<Crossing>> cusps(speeds.size());
  for_each_index(speeds.size(), [&](std::size_t i) {
    if (i == 0 || !d.at[i].limit || !d.at[i - 1].limit || d.at[i - 1].lobe == d.at[i].lobe ||
        !d.at[i].stable_below || !d.at[i - 1].stable_below)
      return;
    const Lobe& a = d.lobes[static_cast<std::size_t>(d.at[i - 1].lobe - 1)];
    const Lobe& b = d.lobes[static_cast<std::size_t>(d.at[i].lobe - 1)];
    cusps[i] = intersection(tracer, a, b, speeds[i - 1], speeds[i]);
    if (cusps[i]) cusps[i] = lowest_at(tracer, d.lobes, speeds[i - 1], speeds[i], *cusps[i]);
  });
  for (std::size_t i = 0; i < speeds.size(); ++i) {
    if (!d.at[i].limit) continue;
    if (cusps[i]) d.envelope.push_back(*cusps[i]);
    d.envelope.push_back(*d.at[i].limit);
  }
  return d;
}

}  // namespace chatterlab::lobes
