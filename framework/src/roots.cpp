// Rightmost characteristic root in a band, certified by the argument principle (roots.hpp).
//
// How the search copes with the hard cases of MODELS.md G1 (eq 2-16):
//
// (a) Long work delays, many roots. At a work speed of 55 rpm (Tw = 1.09 s) every 2 pi / Tw =
//     5.8 rad/s of the band holds a root of the work-regeneration chain, so a 1 kHz band holds
//     about 1100 roots in the upper half plane (and one per wheel revolution frequency, 24 Hz,
//     from the wheel chain). The model seeds Newton with one guess per lattice point 2 pi n / T,
//     so the cost is linear in the number of roots; and since only the rightmost root matters,
//     guesses that can no longer beat the best root found after one or two Newton steps are
//     dropped (locate_from_guesses). The certificate's left edge runs past all of the roots at a
//     small distance; the adaptive phase tracking (roots/contour.hpp) spends 4..10 evaluations
//     per root passed, independent of how close it passes, because each step is sized from a
//     one-zero model of E fitted at the step's ends. Only the upper half of the rectangle is
//     tracked (conjugate symmetry), so the count costs one pass along [0, band].
// (b) Roots very close to Re s = 0. The wheel-wear chain's roots sit at
//     Re s ~ -ln(1 + kc/kg ...)/Tg, a few 1e-2 /s for a hard wheel, and near-coincident wheel and
//     work lattice points give roots at Re s ~ -C |delta|^2. The rightmost root is then one of
//     hundreds of roots with nearly the same small real part. The contour's left edge is put at
//     sigma_c = Re s* + gap with a gap of 1e-4 |Re s*| (never more than half of |Re s*| when
//     Re s* < 0, so a stable verdict stays provable), i.e. it passes 1e-6 /s from such roots; the
//     tracking resolves that (E is accurate to rounding there because the model evaluates the
//     factored form), and if a root the guesses missed lies between s* and sigma_c the count is
//     nonzero and the repair step finds it.
// (c) The neutral root s = 0 (and, for commensurate speeds, the other common points of the two
//     delay lattices, see plunge_regenerative.hpp). The model declares them; Newton results that
//     land on them are dropped (counted in neutral_roots_excluded) and the contour count
//     subtracts those inside the rectangle. When Re s* < 0 the rectangle contains s = 0, so the
//     count is "1 neutral zero, 0 unknown"; when Re s* > 0 it does not.
#include "chatterlab/roots.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include <fmt/format.h>

#include "chatterlab/errors.hpp"
#include "roots/contour.hpp"
#include "roots/newton.hpp"

namespace chatterlab {

namespace {

using roots_detail::Box;
using roots_detail::BoxCount;
using roots_detail::BudgetExhausted;
using roots_detail::ContourSettings;
using roots_detail::ContourTracker;
using roots_detail::Evaluator;
using roots_detail::NewtonSettings;
using roots_detail::RootSet;

// Guesses and declared neutral roots cover a little more than the band, so roots near the top
// edge of the certificate rectangle are known before the count (they are subtracted, not hunted).
constexpr double kGuessBandFactor = 1.05;
// Relative distance under which two Newton results are the same root (Newton stops at 1e-13).
constexpr double kSameRootTolerance = 1e-8;
// Relative gap between the rightmost root and the certificate's left edge (see (b) above).
constexpr double kRelativeGap = 1e-4;
constexpr double kGapFloor = 1e-9;  // times max(|s*|, length scale)
constexpr int kCertificateAttempts = 4;
// Newton on the guesses: pruning stages (one Newton step each) before the survivors are finished,
// and the margin (in last-step lengths) a candidate keeps for moving right.
constexpr int kPruningStages = 2;
constexpr double kPruningMargin = 3.0;
constexpr int kMaxSubdivisionDepth = 60;

std::string show(Complex s) { return fmt::format("{:.6g}{:+.6g}i", s.real(), s.imag()); }

class RootSearch {
 public:
  RootSearch(const CharacteristicFunction& function, const RootSearchOptions& options,
             const std::vector<Complex>* guesses)
      : function_(function),
        guesses_(guesses),
        options_(options),
        evaluate_(function, options.max_function_evaluations),
        tracker_(evaluate_, ContourSettings{}),
        band_(2.0 * std::numbers::pi * options.max_frequency_hz),
        length_scale_(1e-3 * band_),
        roots_(kSameRootTolerance, length_scale_) {}

  RightmostRoot run();

 private:
  void locate_from_guesses();
  bool add_root(Complex s);
  bool try_newton(Complex guess);
  std::optional<Complex> rightmost_in_band() const;
  int known_in(const Box& box) const;
  Complex known_sum(const Box& box) const;
  Complex known_square_sum(const Box& box) const;
  bool is_neutral(Complex s) const;
  // Distance from the rightmost root s* to the certificate's left edge (see (b) above).
  double certificate_gap(Complex rightmost) const;
  bool locate(const Box& box, const BoxCount& count, int depth);
  bool locate_real(const Box& box);
  RightmostRoot finish(Complex rightmost, bool certified, double sigma_c, int unknown,
                       std::string certificate) const;

  const CharacteristicFunction& function_;
  const std::vector<Complex>* guesses_;  // warm start; nullptr: the model's own guesses
  RootSearchOptions options_;
  Evaluator evaluate_;
  ContourTracker tracker_;
  double band_;          // Omega = 2 pi max_frequency_hz [rad/s]
  double length_scale_;  // absolute floor for relative tolerances [rad/s]
  double real_bound_ = 0.0;
  NewtonSettings newton_;
  RootSet roots_;  // every located root, Im >= 0, in or beyond the band; never neutral ones
  std::vector<Complex> neutral_;
  int neutral_hits_ = 0;
  int repaired_ = 0;
  bool repairing_ = false;
  std::vector<Complex> dropped_;  // where candidates dropped by the pruning stood (Im >= 0)
};

double RootSearch::certificate_gap(Complex rightmost) const {
  const double sigma = rightmost.real();
  const double floor = kGapFloor * std::max(std::abs(rightmost), length_scale_);
  const double gap = std::max(kRelativeGap * std::abs(sigma), floor);
  return sigma < 0.0 ? std::max(std::min(gap, 0.5 * std::abs(sigma)), floor) : gap;
}

bool RootSearch::is_neutral(Complex s) const {
  for (Complex n : neutral_)
    if (roots_detail::magnitude(s - n) <= roots_.tolerance(n)) return true;
  return false;
}

bool RootSearch::add_root(Complex s) {
  if (is_neutral(s)) {
    ++neutral_hits_;
    return false;
  }
  bool added = roots_.insert(s);
  if (added && repairing_) ++repaired_;
  return added;
}

bool RootSearch::try_newton(Complex guess) {
  std::optional<Complex> root = roots_detail::newton(evaluate_, guess, newton_);
  return root && add_root(*root);
}

void RootSearch::locate_from_guesses() {
  using roots_detail::NewtonIterate;
  using Status = NewtonIterate::Status;
  std::vector<Complex> own_guesses;
  if (!guesses_) function_.initial_guesses(kGuessBandFactor * band_, own_guesses);
  const std::vector<Complex>& guesses = guesses_ ? *guesses_ : own_guesses;
  // Only the rightmost root is needed. Every guess gets one Newton step; then, in stages, the
  // most promising candidate is finished (a reference root), the candidates that can no longer
  // beat the best root found are dropped, and the rest take another step. Whatever a wrongly
  // dropped candidate would have found, the certificate's count catches and the repair finds.
  std::vector<NewtonIterate> candidates;
  candidates.reserve(guesses.size());
  std::optional<Complex> best;
  auto record = [&](const NewtonIterate& it) {
    if (it.status != Status::converged || !add_root(it.s)) return;
    if (it.s.imag() <= band_ && (!best || it.s.real() > best->real())) best = it.s;
  };
  for (Complex guess : guesses) {
    if (!roots_detail::is_finite(guess)) continue;
    NewtonIterate it;
    it.s = guess.imag() < 0.0 ? std::conj(guess) : guess;
    roots_detail::newton_steps(evaluate_, it, 1, newton_);
    if (it.status == Status::running) candidates.push_back(it);
    else record(it);
  }
  // How far right a candidate may still move: a few times its last step (quadratic convergence
  // makes the true remaining distance much smaller once steps shrink).
  auto reach = [](const NewtonIterate& it) { return it.s.real() + kPruningMargin * it.last_step; };
  auto by_reach = [&](const NewtonIterate& a, const NewtonIterate& b) {
    // Deterministic order (ties broken by the iterate itself), independent of the guess order.
    if (reach(a) != reach(b)) return reach(a) > reach(b);
    if (a.s.imag() != b.s.imag()) return a.s.imag() < b.s.imag();
    return a.s.real() < b.s.real();
  };
  auto finish = [&](NewtonIterate& it) {
    roots_detail::newton_steps(evaluate_, it, newton_.max_iterations, newton_);
    record(it);
  };
  for (int stage = 1;; ++stage) {
    std::sort(candidates.begin(), candidates.end(), by_reach);
    if (!best && !candidates.empty()) {
      finish(candidates.front());
      candidates.erase(candidates.begin());
    }
    if (best)
      std::erase_if(candidates, [&](const NewtonIterate& it) {
        if (reach(it) >= best->real()) return false;
        if (options_.keep_approximate_roots) dropped_.push_back(it.s);
        return true;
      });
    if (stage == kPruningStages || candidates.empty()) break;
    for (NewtonIterate& it : candidates) {
      roots_detail::newton_steps(evaluate_, it, 1, newton_);
      if (it.status != Status::running) record(it);
    }
    std::erase_if(candidates, [](const NewtonIterate& it) { return it.status != Status::running; });
  }
  for (NewtonIterate& it : candidates) {  // still sorted by reach
    if (best && reach(it) < best->real()) {
      if (options_.keep_approximate_roots) dropped_.push_back(it.s);
      continue;
    }
    finish(it);
  }
}

std::optional<Complex> RootSearch::rightmost_in_band() const {
  std::optional<Complex> best;
  for (Complex r : roots_.roots()) {
    if (r.imag() > band_) break;  // sorted by Im
    // Ties (equal Re) go to the lower frequency: the result must not depend on insertion order.
    if (!best || r.real() > best->real() || (r.real() == best->real() && r.imag() < best->imag()))
      best = r;
  }
  return best;
}

int RootSearch::known_in(const Box& box) const {
  int n = 0;
  for (Complex r : roots_.roots()) n += box.multiplicity(r);
  for (Complex r : neutral_) n += box.multiplicity(r);
  return n;
}

Complex RootSearch::known_sum(const Box& box) const {
  Complex sum = 0.0;
  auto add = [&](Complex r) {
    int m = box.multiplicity(r);
    if (m == 0) return;
    // In a mirrored box a complex root brings its conjugate: the pair sums to 2 Re.
    sum += box.symmetric() ? Complex(m == 2 ? 2.0 * r.real() : r.real(), 0.0) : r;
  };
  for (Complex r : roots_.roots()) add(r);
  for (Complex r : neutral_) add(r);
  return sum;
}

Complex RootSearch::known_square_sum(const Box& box) const {
  Complex sum = 0.0;
  auto add = [&](Complex r) {
    int m = box.multiplicity(r);
    if (m == 0) return;
    const Complex square = r * r;
    // In a mirrored box a complex root brings its conjugate: r^2 + conj(r)^2 = 2 Re r^2.
    sum += box.symmetric() ? Complex(m == 2 ? 2.0 * square.real() : square.real(), 0.0) : square;
  };
  for (Complex r : roots_.roots()) add(r);
  for (Complex r : neutral_) add(r);
  return sum;
}

// A mirrored box holding exactly one zero, and it is unknown: E is real on the real axis and
// changes sign across that zero, so bisection brackets it before Newton polishes it.
bool RootSearch::locate_real(const Box& box) {
  auto real_value = [&](double x) { return evaluate_(Complex(x, 0.0)).value.real(); };
  double lo = box.re_min, hi = box.re_max;
  double f_lo = real_value(lo), f_hi = real_value(hi);
  if (!(f_lo * f_hi < 0.0)) return false;
  for (int i = 0; i < 200 && hi - lo > roots_.tolerance(Complex(hi, 0.0)); ++i) {
    double mid = 0.5 * (lo + hi);
    double f_mid = real_value(mid);
    if (f_mid == 0.0) return add_root(Complex(mid, 0.0));
    if ((f_mid < 0.0) == (f_lo < 0.0)) {
      lo = mid;
      f_lo = f_mid;
    } else {
      hi = mid;
    }
  }
  return try_newton(Complex(0.5 * (lo + hi), 0.0)) || add_root(Complex(0.5 * (lo + hi), 0.0));
}

// Finds the zeros in `box` that the count says exist but no guess found: isolate by bisecting the
// box (each child counted by its own contour), then Newton from the contour's root-sum estimate.
bool RootSearch::locate(const Box& box, const BoxCount& count, int depth) {
  int unknown = count.zeros - known_in(box);
  if (unknown == 0) return true;
  if (unknown < 0 || depth > kMaxSubdivisionDepth) return false;

  if (unknown == 1) {
    // One unknown zero: the contour's root sum minus the known zeros' sum is its location.
    Complex estimate = count.root_sum - known_sum(box);
    Complex centre(0.5 * (box.re_min + box.re_max), 0.5 * (box.im_min + box.im_max));
    if (box.symmetric()) {
      if (count.zeros == 1 && locate_real(box)) return true;
      estimate = Complex(estimate.real(), 0.0);
      centre = Complex(centre.real(), 0.0);
    }
    for (Complex guess : {estimate, centre}) {
      if (!box.symmetric() && !box.contains(guess)) continue;
      try_newton(guess);
      if (count.zeros - known_in(box) == 0) return true;
    }
  }

  if (unknown == 2) {
    // Two unknown zeros (in a mirrored box typically a conjugate pair): their sum p and the sum of
    // their squares q make them the roots of z^2 - p z + (p^2 - q) / 2. Newton from both; only
    // if that fails is the box subdivided.
    const Complex p = count.root_sum - known_sum(box), q = count.root_square_sum - known_square_sum(box);
    const Complex disc = roots_detail::square_root(2.0 * q - p * p);
    for (Complex guess : {0.5 * (p + disc), 0.5 * (p - disc)}) {
      if (!roots_detail::is_finite(guess)) continue;
      try_newton(guess);
      if (count.zeros - known_in(box) == 0) return true;
    }
  }

  const double width = box.re_max - box.re_min, height = box.im_max - box.im_min;
  const bool split_real = width >= height;
  for (int attempt = 0; attempt < 4; ++attempt) {
    // A split line that passes through a zero cannot be tracked; move it a little and retry.
    double fraction = 0.5 + 0.0137 * attempt;
    Box first = box, second = box;
    if (split_real) {
      double cut = box.re_min + fraction * width;
      first.re_max = cut;
      second.re_min = cut;
    } else {
      double cut = box.im_min + fraction * height;
      first.im_max = cut;
      second.im_min = cut;  // the upper child of a mirrored box is an ordinary box
    }
    BoxCount count_first = tracker_.count(first);
    if (!count_first.ok) continue;
    BoxCount count_second = tracker_.count(second);
    // The upper child of a mirrored box is ordinary: its zeros appear twice in the parent.
    const int second_weight = box.symmetric() && !second.symmetric() ? 2 : 1;
    if (!count_second.ok || count_first.zeros + second_weight * count_second.zeros != count.zeros)
      continue;
    bool ok_first = locate(first, count_first, depth + 1);
    bool ok_second = locate(second, count_second, depth + 1);
    return ok_first && ok_second;
  }
  return false;
}

RightmostRoot RootSearch::finish(Complex rightmost, bool certified, double sigma_c, int unknown,
                                 std::string certificate) const {
  RightmostRoot result;
  result.root = rightmost;
  for (Complex r : roots_.roots())
    if (r.imag() <= band_) ++result.roots_found;
  result.certified = certified;
  result.certified_real_part = sigma_c;
  result.zeros_right_of_contour = unknown;
  result.function_evaluations = static_cast<int>(std::min<long>(evaluate_.count(), 2147483647L));
  result.certificate = std::move(certificate);
  if (std::string note = function_.certificate_note(sigma_c, band_); !note.empty())
    result.certificate += "; " + note;
  result.repaired_roots = repaired_;
  result.neutral_roots_excluded = neutral_hits_;
  result.warm_started = guesses_ != nullptr;
  if (options_.keep_approximate_roots) {
    result.approximate_roots = roots_.roots();
    for (Complex s : dropped_)
      if (!roots_.contains(s)) result.approximate_roots.push_back(s);
    std::sort(result.approximate_roots.begin(), result.approximate_roots.end(), [](Complex a, Complex b) {
      return a.imag() != b.imag() ? a.imag() < b.imag() : a.real() < b.real();
    });
  }
  return result;
}

RightmostRoot RootSearch::run() {
  if (!(options_.max_frequency_hz > 0.0) || !std::isfinite(options_.max_frequency_hz))
    throw PointFailure(fmt::format("root search: max_frequency_hz = {} must be finite and > 0",
                                   options_.max_frequency_hz));
  real_bound_ = function_.real_part_bound();
  if (!std::isfinite(real_bound_))
    throw PointFailure("root search: the model's bound on Re s is not finite");

  newton_.relative_tolerance = options_.newton_relative_tolerance;
  newton_.max_iterations = options_.max_newton_iterations;
  newton_.length_scale = length_scale_;
  // Iterates are abandoned well outside the region holding the zeros that matter.
  newton_.max_real_part = std::max(real_bound_, 0.0) + band_;
  newton_.max_imag_part = 2.0 * band_;

  for (Complex n : function_.neutral_roots(kGuessBandFactor * band_))
    neutral_.push_back(n.imag() < 0.0 ? std::conj(n) : n);

  std::optional<Complex> rightmost;
  double sigma_c = 0.0;
  try {
    locate_from_guesses();
    for (int round = 0;; ++round) {
      rightmost = rightmost_in_band();
      if (!rightmost)
        throw PointFailure(fmt::format(
            "root search: no characteristic root found with |Im s| <= {:.6g} rad/s "
            "({} evaluations)", band_, evaluate_.count()));
      const double sigma = rightmost->real();
      double gap = certificate_gap(*rightmost);
      double top = band_;

      BoxCount count;
      Box box;
      for (int attempt = 0; attempt < kCertificateAttempts; ++attempt) {
        sigma_c = sigma + gap;
        // No zero has Re s >= real_bound_, so any right edge at or beyond it is valid.
        double right = std::max(real_bound_, sigma_c + std::max(1.0, std::abs(sigma_c)));
        box = Box{sigma_c, right, 0.0, top};
        count = tracker_.count(box);
        if (count.ok) break;
        // A zero on (or within rounding of) an edge: move the edge that failed.
        if (std::abs(count.failure_point.imag() - top) <= 1e-6 * top)
          top *= 1.0 + 1e-6 * std::pow(10.0, attempt);
        else
          gap *= 30.0;
      }
      if (!count.ok)
        return finish(*rightmost, false, sigma_c, -1,
                      fmt::format("uncertified: the phase of E could not be resolved near s = {} "
                                  "(a zero on the contour; tried {} contours)",
                                  show(count.failure_point), kCertificateAttempts));

      const int known = known_in(box);

      const int unknown = count.zeros - known;
      if (unknown == 0)
        return finish(*rightmost, true, sigma_c, 0,
                      fmt::format("ok: argument principle on Re s in [{:.6g}, {:.6g}], |Im s| <= "
                                  "{:.6g}: {} zeros, all known ({} neutral or beyond the band); "
                                  "no root right of Re s = {:.6g}",
                                  box.re_min, box.re_max, box.im_max, count.zeros, known, sigma_c));
      if (unknown < 0)
        return finish(*rightmost, false, sigma_c, unknown,
                      fmt::format("uncertified: the contour counts {} zeros right of Re s = {:.6g} "
                                  "but {} known zeros lie there (inconsistent count)",
                                  count.zeros, sigma_c, known));
      if (round >= options_.max_repair_rounds)
        return finish(*rightmost, false, sigma_c, unknown,
                      fmt::format("uncertified: {} zero(s) right of Re s = {:.6g} were not located "
                                  "({} repair rounds)", unknown, sigma_c, round));
      repairing_ = true;
      int before = repaired_;
      locate(box, count, 0);
      repairing_ = false;
      if (repaired_ > before && count.zeros - known_in(box) == 0) {
        // Every zero this count saw right of sigma_c is now known, so the new rightmost root is
        // among them and nothing unknown lies right of sigma_c: the same contour certifies it (a
        // second contour round the new root would only recount what is known).
        const Complex located = *rightmost_in_band();
        const double certified = located.real() + certificate_gap(located);
        return finish(located, true, certified, 0,
                      fmt::format("ok: argument principle on Re s in [{:.6g}, {:.6g}], |Im s| <= "
                                  "{:.6g}: {} zeros, all known ({} located by the repair, {} neutral or "
                                  "beyond the band); no root right of Re s = {:.6g}",
                                  box.re_min, box.re_max, box.im_max, count.zeros, repaired_ - before, known,
                                  certified));
      }
      if (repaired_ == before)
        return finish(*rightmost, false, sigma_c, unknown,
                      fmt::format("uncertified: {} zero(s) right of Re s = {:.6g} could not be "
                                  "located by subdividing the contour", unknown, sigma_c));
    }
  } catch (const BudgetExhausted&) {
    if (!rightmost) rightmost = rightmost_in_band();
    if (!rightmost)
      throw PointFailure(fmt::format("root search: evaluation budget ({}) exhausted before any "
                                     "root was found", options_.max_function_evaluations));
    return finish(*rightmost, false, sigma_c, -1,
                  fmt::format("uncertified: evaluation budget ({}) exhausted",
                              options_.max_function_evaluations));
  }
}

}  // namespace

RightmostRoot find_rightmost_root(const CharacteristicFunction& characteristic,
                                  const RootSearchOptions& options) {
  // The runner calls this from OpenMP threads: only PointFailure may leave, and all state is
  // local to this call (determinism: same inputs, same operations, same result on any thread).
  try {
    if (options.warm_start && !options.warm_start->empty()) {
      try {
        RightmostRoot warm = RootSearch(characteristic, options, options.warm_start).run();
        if (warm.certified) return warm;
      } catch (const PointFailure&) {
        // no root from the warm guesses: the model's own guesses below
      }
    }
    return RootSearch(characteristic, options, nullptr).run();
  } catch (const PointFailure&) {
    throw;
  } catch (const std::exception& e) {
    throw PointFailure(std::string("root search failed: ") + e.what());
  } catch (...) {
    throw PointFailure("root search failed: " + describe_current_exception());
  }
}

}  // namespace chatterlab
