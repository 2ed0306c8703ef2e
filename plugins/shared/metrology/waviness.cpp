#include "shared/metrology/waviness.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <stdexcept>

#include "chatterlab/fft.hpp"

namespace chatterlab::surface {
namespace {

enum class Phase { none, peak, valley };

struct PhaseExtreme {
  Phase kind;
  double extreme;
  bool started_by_transition;
  std::size_t first, last;  // first and last sample beyond the height discrimination
  double up_crossing;       // peaks: the mean-line up-crossing that starts them (-1: none)
};

struct AmplitudeMoments {
  double Wa = 0, Wq = 0, Wp = 0, Wv = 0, Wsk = 0, Wku = 0;
};

AmplitudeMoments amplitude_moments(const double* w, std::size_t n) {
  AmplitudeMoments m;
  double s1 = 0, s2 = 0, s3 = 0, s4 = 0, hi = w[0], lo = w[0];
  for (std::size_t i = 0; i < n; ++i) {
    const double v = w[i], v2 = v * v;
    s1 += std::abs(v);
    s2 += v2;
    s3 += v2 * v;
    s4 += v2 * v2;
    hi = std::max(hi, v);
    lo = std::min(lo, v);
  }
  const double count = static_cast<double>(n);
  m.Wa = s1 / count;
  m.Wq = std::sqrt(s2 / count);
  m.Wp = hi;
  m.Wv = -lo;
  if (m.Wq > 0) {
    m.Wsk = s3 / count / (m.Wq * m.Wq * m.Wq);
    m.Wku = s4 / count / (m.Wq * m.Wq * m.Wq * m.Wq);
  }
  return m;
}

}  // namespace

namespace {

// The profile elements from the phases in order (each complete: its extreme and extent final),
// with the width discrimination applied as they arrive: a peak or valley narrower than the limit,
// between two others, is no element of its own: its neighbours (of the other kind) join across
// it. Only the phases that a later join could still change are held (a noisy band-limited
// profile of 10^7 samples has millions of phases): every phase before the last one that can no
// longer be removed (started by a transition, or at least as wide as the limit) is final.
class ElementJoiner {
 public:
  ElementJoiner(double width_discrimination, ProfileElements& out)
      : width_discrimination_(width_discrimination), out_(out) {}

  void add(const PhaseExtreme& p) {
    if (kept_.size() >= 2 && removable(kept_.back())) {
      kept_.pop_back();
      PhaseExtreme& joined = kept_.back();
      joined.extreme = p.kind == Phase::peak ? std::max(joined.extreme, p.extreme)
                                             : std::min(joined.extreme, p.extreme);
      joined.last = p.last;
      if (!removable(joined)) last_fixed_ = kept_.size() - 1;
    } else {
      kept_.push_back(p);
      if (!removable(p)) last_fixed_ = kept_.size() - 1;
    }
    // Phases before the last fixed one are final, and so is the wave height of each but the
    // last of them (it needs the next phase's extreme): emit those, keep the rest.
    if (kept_.size() > 64 && last_fixed_ >= 2) {
      const std::size_t done = last_fixed_ - 1;
      for (std::size_t k = 0; k < done; ++k) emit(k);
      kept_.erase(kept_.begin(), kept_.begin() + static_cast<std::ptrdiff_t>(done));
      last_fixed_ -= done;
    }
  }

  void finish() {
    for (std::size_t k = 0; k < kept_.size(); ++k) emit(k);
    kept_.clear();
  }

 private:
  bool removable(const PhaseExtreme& p) const {
    return p.started_by_transition &&
           static_cast<double>(p.last - p.first + 1) < width_discrimination_;
  }
  void emit(std::size_t k) {
    if (kept_[k].kind == Phase::peak && kept_[k].up_crossing >= 0)
      out_.up_crossings.push_back(kept_[k].up_crossing);
    if (k + 1 < kept_.size() && kept_[k].kind == Phase::peak && kept_[k].started_by_transition)
      out_.wave_heights.push_back(kept_[k].extreme - kept_[k + 1].extreme);
  }

  double width_discrimination_;
  ProfileElements& out_;
  std::vector<PhaseExtreme> kept_;
  std::size_t last_fixed_ = 0;  // index in kept_ of the last phase no join can remove
};

}  // namespace

ProfileElements profile_elements(std::span<const double> w, double height_discrimination,
                                 bool closed, double width_discrimination) {
  ProfileElements out;
  if (w.size() < 3) return out;
  // A closed profile is read from its deepest valley round to that valley again (every phase is
  // then complete): y(i) = w[(start + i) mod N], i = 0..N, by index instead of a rotated copy.
  const std::size_t n = w.size();
  const std::size_t start =
      closed ? static_cast<std::size_t>(std::min_element(w.begin(), w.end()) - w.begin()) : 0;
  const std::size_t length = closed ? n + 1 : n;
  auto y = [&](std::size_t i) {
    const std::size_t k = i + start;
    return w[k >= n ? k - n : k];
  };
  const double h = height_discrimination;
  ElementJoiner joiner(width_discrimination, out);
  bool started = false;
  PhaseExtreme current{};  // the phase being read
  std::size_t last_significant = 0;
  for (std::size_t i = 0; i < length; ++i) {
    const double yi = y(i);
    const Phase cls = yi > h ? Phase::peak : (yi < -h ? Phase::valley : Phase::none);
    if (cls == Phase::none) continue;
    if (!started) {
      current = {cls, yi, false, i, i, -1.0};
      started = true;
    } else if (current.kind == cls) {
      current.extreme = cls == Phase::peak ? std::max(current.extreme, yi) : std::min(current.extreme, yi);
      current.last = i;
    } else {
      double crossing = -1.0;
      if (cls == Phase::peak) {
        // The mean-line up-crossing closest to this peak phase.
        for (std::size_t j = i; j > last_significant; --j) {
          if (y(j - 1) < 0 && y(j) >= 0) {
            crossing = static_cast<double>(j - 1) + y(j - 1) / (y(j - 1) - y(j));
            break;
          }
        }
      }
      joiner.add(current);
      current = {cls, yi, true, i, i, crossing};
    }
    last_significant = i;
  }
  if (started) joiner.add(current);
  joiner.finish();
  return out;
}

double mean_of_five_largest(std::vector<double> heights) {
  if (heights.empty()) return 0.0;
  const std::size_t count = std::min<std::size_t>(5, heights.size());
  std::partial_sort(heights.begin(), heights.begin() + static_cast<std::ptrdiff_t>(count),
                    heights.end(), std::greater<>());
  double sum = 0;
  for (std::size_t i = 0; i < count; ++i) sum += heights[i];
  return sum / static_cast<double>(count);
}

WavinessParameters waviness_parameters(std::span<const double> w, double spacing, bool closed,
                                       int sampling_lengths, double width_discrimination) {
  if (w.size() < 4) throw std::invalid_argument("waviness_parameters: fewer than 4 samples");
  WavinessParameters p;
  const std::size_t n = w.size();
  const std::size_t parts = std::clamp<std::size_t>(static_cast<std::size_t>(std::max(1, sampling_lengths)), 1, n / 4);
  for (std::size_t k = 0; k < parts; ++k) {
    const std::size_t from = k * n / parts, to = (k + 1) * n / parts;
    const AmplitudeMoments m = amplitude_moments(w.data() + from, to - from);
    p.Wa += m.Wa;
    p.Wq += m.Wq;
    p.Wp += m.Wp;
    p.Wv += m.Wv;
    p.Wz += m.Wp + m.Wv;
    p.Wsk += m.Wsk;
    p.Wku += m.Wku;
  }
  const double count = static_cast<double>(parts);
  for (double* v : {&p.Wa, &p.Wq, &p.Wp, &p.Wv, &p.Wz, &p.Wsk, &p.Wku}) *v /= count;
  const auto [lo, hi] = std::minmax_element(w.begin(), w.end());
  p.Wt = *hi - *lo;

  const ProfileElements elements = profile_elements(w, 0.1 * p.Wz, closed, width_discrimination);
  const auto& up = elements.up_crossings;
  if (closed && !up.empty()) {
    p.WSm = static_cast<double>(n) * spacing / static_cast<double>(up.size());
  } else if (up.size() >= 2) {
    p.WSm = (up.back() - up.front()) / static_cast<double>(up.size() - 1) * spacing;
  }
  p.wave_count = elements.wave_heights.size();
  p.Wz_five = mean_of_five_largest(elements.wave_heights);
  return p;
}

std::pair<UprBand, UprBand> default_bands(double wheel_speed_rpm, double work_speed_rpm,
                                          std::size_t samples_per_rev) {
  const double z = wheel_speed_rpm / work_speed_rpm;
  const double nyquist = std::floor(static_cast<double>(samples_per_rev) / 2);
  UprBand low{std::max(2.0, std::round(z / 2)), std::min(nyquist, std::round(1.5 * z))};
  UprBand high{low.to_upr + 1, nyquist};
  return {low, high};
}

namespace {

// Zeroes the bins outside [max(2, from_upr), to_upr].
void keep_band(std::span<std::complex<double>> spectrum, UprBand band) {
  for (std::size_t k = 0; k < spectrum.size(); ++k) {
    const double upr = static_cast<double>(k);
    if (upr < std::max(2.0, band.from_upr) || upr > band.to_upr) spectrum[k] = 0.0;
  }
}

}  // namespace

std::vector<double> band_limited(std::span<const double> closed_profile, UprBand band) {
  InPlaceRealFft fft(closed_profile);
  fft.forward();
  keep_band(fft.spectrum(), band);
  fft.inverse();
  return fft.take_samples();
}

BandWaviness band_waviness(std::span<const double> closed_profile, UprBand band,
                           double work_speed_rpm) {
  const std::size_t n = closed_profile.size();
  BandWaviness out;
  out.band = {std::max(2.0, band.from_upr),
              std::min(band.to_upr, std::floor(static_cast<double>(n) / 2))};
  // One buffer (in place: 8 bytes per sample beside the profile) holds the band's spectrum, then
  // the band-limited profile.
  InPlaceRealFft fft(closed_profile);
  fft.forward();
  keep_band(fft.spectrum(), out.band);
  // Dominant bin of the band's own spectrum: amplitude of a cosine of k lobes is 2 |X_k| / N
  // (|X_k| / N at Nyquist); bins outside the band are zero.
  const std::span<const std::complex<double>> spectrum = fft.spectrum();
  for (std::size_t k = 0; k < spectrum.size(); ++k) {
    const double scale = (2 * k == n ? 1.0 : 2.0) / static_cast<double>(n);
    const double amplitude = scale * std::abs(spectrum[k]);
    if (amplitude > out.dominant_amplitude) {
      out.dominant_amplitude = amplitude;
      out.dominant_upr = static_cast<double>(k);
    }
  }
  out.dominant_frequency_hz = out.dominant_upr * work_speed_rpm / 60.0;
  fft.inverse();
  const std::span<const double> limited = fft.samples();
  // Elements of the band-limited profile: 10 % of its peak-to-valley height as discrimination.
  const auto [lo, hi] = std::minmax_element(limited.begin(), limited.end());
  const ProfileElements elements = profile_elements(limited, 0.1 * (*hi - *lo), true);
  out.wave_count = elements.wave_heights.size();
  out.Wz = mean_of_five_largest(elements.wave_heights);
  return out;
}

}  // namespace chatterlab::surface
