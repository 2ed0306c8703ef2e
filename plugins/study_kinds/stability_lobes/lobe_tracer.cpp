// Stability lobes by bracketing, polishing and continuation (lobe_tracer.hpp has the method).
#include "study_kinds/stability_lobes/lobe_tracer.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
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

// ---------------------------------------------------------------- bracketing: the seeds at one speed

struct Scan {
  std::vector<Crossing> crossings;
  double spacing = 0.0;
};

Scan scan_speed(const ModelAt& model_at, double speed, const TraceSettings& s) {
  const double band = kTwoPi * s.max_frequency_hz;
  const double p_ref = std::sqrt(s.parameter_min * s.parameter_max);
  const double dp = kParameterStep * p_ref;
  const auto m0 = model_at(p_ref, speed), m1 = model_at(p_ref + dp, speed);
  const Axis a0(*m0, s.route), a1(*m1, s.route);
  const std::vector<double> marks = a0.marks(band), neutral = a0.neutral(band);
  Scan scan;
  scan.spacing = typical_spacing(marks, band);
  // Samples: a uniform grid of an eighth of the typical spacing, plus geometric offsets on both
  // sides of every mark.
  std::vector<double> w;
  const double step = scan.spacing / 8.0;
  for (double x = step; x < band; x += step) w.push_back(x);
  for (double m : marks)
    for (double f : {1e-9, 1e-7, 1e-5, 1e-3, 1e-2, 0.05}) {
      w.push_back(m - f * scan.spacing);
      w.push_back(m + f * scan.spacing);
    }
  std::sort(w.begin(), w.end());
  w.erase(std::remove_if(w.begin(), w.end(), [&](double x) { return !(x > 0.0 && x < band); }), w.end());
  w.erase(std::unique(w.begin(), w.end()), w.end());
  // psi = Im(G conj dG/dp) vanishes where G/(dG/dp) is real, i.e. where G + (p - p_ref) dG/dp = 0
  // for a real p: the estimate p_est = p_ref - Re(G/(dG/dp)).
  struct Sample {
    double psi, p_est;
  };
  auto sample = [&](double x) {
    const Complex g = a0.at(x).value, gp = (a1.at(x).value - g) / dp;
    return Sample{(g * std::conj(gp)).imag(), gp == 0.0 ? NAN : p_ref - (g / gp).real()};
  };
  Sample previous = sample(w.front());
  for (std::size_t i = 1; i < w.size(); ++i) {
    const Sample current = sample(w[i]);
    if (std::signbit(previous.psi) != std::signbit(current.psi) && previous.psi != 0.0) {
      const double t = previous.psi / (previous.psi - current.psi);
      const double x = w[i - 1] + t * (w[i] - w[i - 1]);
      const Sample at = sample(x);
      const bool neutral_here = std::any_of(neutral.begin(), neutral.end(), [&](double n) {
        return std::abs(n - x) <= 1e-6 * scan.spacing;
      });
      if (!neutral_here && at.p_est > 0.25 * s.parameter_min && at.p_est < 4.0 * s.parameter_max) {
        if (const auto c = correct(model_at, Crossing{speed, at.p_est, x}, s.route, scan.spacing);
            c && in_range(c->parameter, s)) {
          const bool known = std::any_of(scan.crossings.begin(), scan.crossings.end(), [&](const Crossing& k) {
            return std::abs(k.omega_rad_s - c->omega_rad_s) <= 1e-7 * c->omega_rad_s;
          });
          if (!known) scan.crossings.push_back(*c);
        }
      }
    }
    previous = current;
  }
  std::sort(scan.crossings.begin(), scan.crossings.end(),
            [](const Crossing& a, const Crossing& b) { return a.omega_rad_s < b.omega_rad_s; });
  return scan;
}

// ---------------------------------------------------------------- continuation along a lobe

Crossing predict(const Lobe& lobe, double speed, bool forward) {
  const auto& pts = lobe.points;
  const Crossing& last = forward ? pts.back() : pts.front();
  if (pts.size() < 2) return {speed, last.parameter, last.omega_rad_s};
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
  double spacing;
  int corrections = 0;
  static constexpr int max_halvings = 5;

  // The lobe's point at `speed`, from its current end (forward: its last point). Halves the speed
  // step up to max_halvings times (keeping the intermediate points) when Newton fails, lands more
  // than a third of a lattice spacing from the prediction (another lobe), or leaves the range.
  std::vector<Crossing> step(const Lobe& lobe, double speed, bool forward, int depth = 0) {
    Lobe probe = lobe;
    const Crossing guess = predict(probe, speed, forward);
    ++corrections;
    const auto c = correct(model_at, guess, s.route, spacing);
    if (c && in_range(c->parameter, s) && std::abs(c->omega_rad_s - guess.omega_rad_s) < spacing / 3.0) return {*c};
    if (depth == max_halvings) return {};
    const double from = forward ? lobe.points.back().speed : lobe.points.front().speed;
    const double middle = 0.5 * (from + speed);
    std::vector<Crossing> first = step(lobe, middle, forward, depth + 1);
    if (first.empty()) return {};
    for (const Crossing& x : first) forward ? probe.points.push_back(x) : (void)probe.points.insert(probe.points.begin(), x);
    std::vector<Crossing> second = step(probe, speed, forward, depth + 1);
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
// on p_a(v) - p_b(v), each p from Newton at that speed.
std::optional<Crossing> intersection(Tracer& t, const Lobe& a, const Lobe& b, double v0, double v1) {
  auto point_at = [&](const Lobe& lobe, double v) -> std::optional<Crossing> {
    Lobe part;
    for (const Crossing& c : lobe.points)
      if (c.speed <= v) part.points.push_back(c);
    if (part.points.empty()) return std::nullopt;
    return correct(t.model_at, predict(part, v, true), t.s.route, t.spacing);
  };
  auto difference = [&](double v) -> std::optional<std::pair<double, Crossing>> {
    const auto pa = point_at(a, v), pb = point_at(b, v);
    if (!pa || !pb) return std::nullopt;
    return std::pair{pa->parameter - pb->parameter, pa->parameter <= pb->parameter ? *pa : *pb};
  };
  auto d0 = difference(v0), d1 = difference(v1);
  if (!d0 || !d1 || !(d0->first < 0.0) || !(d1->first > 0.0)) return std::nullopt;
  double lo = v0, hi = v1, f_lo = d0->first, f_hi = d1->first;
  Crossing best = d0->second;
  int side = 0;
  for (int i = 0; i < 40 && hi - lo > 1e-12 * std::abs(hi); ++i) {
    const double v = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
    const auto d = difference(v);
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

LobeDiagram trace_lobes(const ModelAt& model_at, const std::vector<double>& speeds, const TraceSettings& s) {
  LobeDiagram d;
  d.speeds = speeds;
  d.at.resize(speeds.size());
  // Seeds and the check at the range's lower end, every speed independently.
  std::vector<Scan> scans(speeds.size());
  std::vector<StabilityCheck> lower(speeds.size());
  for_each_index(speeds.size(), [&](std::size_t i) {
    try {
      scans[i] = scan_speed(model_at, speeds[i], s);
      lower[i] = check_stability(*model_at(s.parameter_min, speeds[i]), s.route, s.max_frequency_hz);
    } catch (const PointFailure& e) {
      lower[i].reason = e.what();
    }
  });
  double spacing = INFINITY;
  for (const Scan& scan : scans)
    if (scan.spacing > 0.0) spacing = std::min(spacing, scan.spacing);
  if (!std::isfinite(spacing)) spacing = kTwoPi * s.max_frequency_hz / 200.0;
  Tracer tracer{model_at, s, spacing};

  // Continuation, speed by speed: every living lobe steps (in parallel), then unclaimed seeds start
  // new lobes that are also followed backwards.
  std::vector<Lobe> lobes;
  std::vector<bool> alive;
  for (std::size_t i = 0; i < speeds.size(); ++i) {
    d.seeds += static_cast<int>(scans[i].crossings.size());
    std::vector<std::vector<Crossing>> steps(lobes.size());
    if (i > 0)
      for_each_index(lobes.size(), [&](std::size_t k) {
        if (alive[k]) steps[k] = tracer.step(lobes[k], speeds[i], true);
      });
    std::vector<Crossing> here;
    for (std::size_t k = 0; k < lobes.size(); ++k) {
      if (!alive[k]) continue;
      const bool duplicate = !steps[k].empty() && std::any_of(here.begin(), here.end(), [&](const Crossing& c) {
        return same_crossing(c, steps[k].back());
      });
      if (steps[k].empty() || duplicate) {
        alive[k] = false;
        continue;
      }
      lobes[k].points.insert(lobes[k].points.end(), steps[k].begin(), steps[k].end());
      here.push_back(steps[k].back());
    }
    for (const Crossing& seed : scans[i].crossings) {
      if (std::any_of(here.begin(), here.end(), [&](const Crossing& c) { return same_crossing(c, seed); })) continue;
      Lobe lobe;
      lobe.id = static_cast<int>(lobes.size()) + 1;
      lobe.points.push_back(seed);
      for (std::size_t j = i; j-- > 0;) {
        std::vector<Crossing> back = tracer.step(lobe, speeds[j], false);
        if (back.empty()) break;
        lobe.points.insert(lobe.points.begin(), back.rbegin(), back.rend());
      }
      here.push_back(seed);
      lobes.push_back(std::move(lobe));
      alive.push_back(true);
    }
  }
  d.corrections = tracer.corrections;

  // The limit at each speed: the lowest crossing, when the range's lower end is stable.
  for (std::size_t i = 0; i < speeds.size(); ++i) {
    SpeedResult& r = d.at[i];
    if (!lower[i].stable) {
      r.note = lower[i].reason.empty() ? "no stability verdict at the lower end of parameter_range"
                                       : "no stability verdict at the lower end of parameter_range: " + lower[i].reason;
      continue;
    }
    if (!*lower[i].stable) {
      r.note = "unstable already at the lower end of parameter_range";
      continue;
    }
    for (const Lobe& lobe : lobes)
      for (const Crossing& c : lobe.points)
        if (c.speed == speeds[i] && (!r.limit || c.parameter < r.limit->parameter)) {
          r.limit = c;
          r.lobe = lobe.id;
        }
    if (!r.limit) r.note = "no crossing in parameter_range: stable over the whole range";
  }
  // Envelope: the limits plus the intersections where the lowest lobe changes.
  for (std::size_t i = 0; i < speeds.size(); ++i) {
    if (!d.at[i].limit) continue;
    if (!d.envelope.empty() && i > 0 && d.at[i - 1].limit && d.at[i - 1].lobe != d.at[i].lobe) {
      const Lobe& a = lobes[static_cast<std::size_t>(d.at[i - 1].lobe - 1)];
      const Lobe& b = lobes[static_cast<std::size_t>(d.at[i].lobe - 1)];
      if (const auto x = intersection(tracer, a, b, speeds[i - 1], speeds[i])) d.envelope.push_back(*x);
    }
    d.envelope.push_back(*d.at[i].limit);
  }
  d.lobes = std::move(lobes);
  return d;
}

}  // namespace chatterlab::lobes
