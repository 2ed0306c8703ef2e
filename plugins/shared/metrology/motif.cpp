#include "shared/metrology/motif.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <queue>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace chatterlab::surface {

namespace {

// combine_motifs on n points given by y(i) and x(i). Per local peak it keeps about 50 bytes
// (32-bit indices and links, 16-byte queue entries): on a noisy profile of N samples, with about
// N / 3 peaks, some 16 bytes per sample.
template <class Height, class Position>
Motifs combine(std::size_t n, const Height& y, const Position& x, double limit) {
  Motifs out;
  if (n < 2) return out;
  if (n >= std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("MOTIF: profiles of 2^32 or more samples are not supported");
  // Initial boundaries: end points and local peaks.
  std::vector<std::uint32_t> peak{0};
  for (std::size_t i = 1; i + 1 < n; ++i)
    if (y(i) >= y(i - 1) && y(i) > y(i + 1)) peak.push_back(static_cast<std::uint32_t>(i));
  peak.push_back(static_cast<std::uint32_t>(n - 1));
  const std::size_t m = peak.size();
  // valley[k]: lowest point of the motif starting at boundary k (inclusive of its ends).
  std::vector<double> valley(m, 0.0);
  for (std::size_t k = 0; k + 1 < m; ++k) {
    double lowest = y(peak[k]);
    for (std::size_t i = peak[k] + 1; i <= peak[k + 1]; ++i) lowest = std::min(lowest, y(i));
    valley[k] = lowest;
  }
  std::vector<std::uint32_t> prev(m), next(m);
  for (std::size_t k = 0; k < m; ++k) {
    prev[k] = static_cast<std::uint32_t>(k == 0 ? m : k - 1);
    next[k] = static_cast<std::uint32_t>(k + 1);
  }
  std::vector<char> alive(m, 1);
  std::vector<unsigned> version(m, 0);
  // Heights of the boundaries side by side (not looked up through peak[] in the profile): the
  // merge loop touches them in heap order, and on million-sample profiles the scattered reads
  // were most of MOTIF's time. Positions come from peak[] (x is i * spacing on a profile).
  std::vector<double> top(m);
  for (std::size_t k = 0; k < m; ++k) top[k] = y(peak[k]);
  auto height = [&](std::size_t k) { return top[k]; };
  auto at = [&](std::size_t k) { return x(peak[k]); };

  // Admissibility of removing interior boundary b (joining its two motifs); key = min(T1, T2).
  auto admissible = [&](std::size_t b, double& key) {
    if (prev[b] == m || next[b] >= m) return false;
    const std::size_t p1 = prev[b], p3 = next[b];
    const double y1 = height(p1), y2 = height(b), y3 = height(p3);
    const double t1 = std::min(y1, y2) - valley[p1], t2 = std::min(y2, y3) - valley[b];
    const double joined = std::min(y1, y3) - std::min(valley[p1], valley[b]);
    key = std::min(t1, t2);
    return y2 <= std::max(y1, y3)                       // C1 envelope
           && at(p3) - at(p1) <= limit                  // C2 width
           && joined >= std::max(t1, t2)                // C3 enlargement
           && key < 0.6 * joined;                       // C4 relative depth
  };
  using Candidate = std::tuple<double, std::uint32_t, unsigned>;
  std::vector<Candidate> storage;
  storage.reserve(m);
  std::priority_queue<Candidate, std::vector<Candidate>, std::greater<>> queue(std::greater<>{},
                                                                               std::move(storage));
  auto consider = [&](std::size_t b) {
    double key;
    if (b < m && admissible(b, key)) queue.emplace(key, static_cast<std::uint32_t>(b), version[b]);
  };
  for (std::size_t b = 1; b + 1 < m; ++b) consider(b);
  while (!queue.empty()) {
    const auto [key, b32, v] = queue.top();
    const std::size_t b = b32;
    queue.pop();
    if (!alive[b] || v != version[b]) continue;
    const std::size_t p1 = prev[b], p3 = next[b];
    valley[p1] = std::min(valley[p1], valley[b]);
    alive[b] = 0;
    next[p1] = static_cast<std::uint32_t>(p3);
    prev[p3] = static_cast<std::uint32_t>(p1);
    ++version[p1];
    ++version[p3];
    consider(p1);
    consider(p3);
  }
  for (std::size_t k = 0; k < m; k = next[k]) {
    out.boundaries.push_back(peak[k]);
    if (next[k] >= m) break;
    out.depths.push_back(height(k) - valley[k]);
    out.depths.push_back(height(next[k]) - valley[k]);
    out.lengths.push_back(at(next[k]) - at(k));
  }
  return out;
}

void summarise(const Motifs& motifs, double& mean_depth, double& mean_length, double& max_depth) {
  mean_depth = mean_length = max_depth = 0;
  if (motifs.lengths.empty()) return;
  for (double d : motifs.depths) {
    mean_depth += d;
    max_depth = std::max(max_depth, d);
  }
  mean_depth /= static_cast<double>(motifs.depths.size());
  for (double l : motifs.lengths) mean_length += l;
  mean_length /= static_cast<double>(motifs.lengths.size());
}

template <class Height>
MotifParameters parameters_of(std::size_t n, const Height& y, double spacing, double a_mm,
                              double b_mm) {
  if (n < 3) throw std::invalid_argument("motif_parameters: fewer than 3 samples");
  auto x = [spacing](std::size_t i) { return static_cast<double>(i) * spacing; };
  MotifParameters p;
  const Motifs roughness = combine(n, y, x, a_mm);
  summarise(roughness, p.R, p.AR, p.Rx);
  p.roughness_motifs = roughness.lengths.size();
  // Upper envelope through the delimiting peaks.
  std::vector<double> ex, ey;
  for (std::size_t i : roughness.boundaries) {
    ex.push_back(x(i));
    ey.push_back(y(i));
  }
  const Motifs waviness = combine_motifs(ex, ey, b_mm);
  summarise(waviness, p.W, p.AW, p.Wx);
  p.waviness_motifs = waviness.lengths.size();
  const auto [lo, hi] = std::minmax_element(ey.begin(), ey.end());
  p.Wte = *hi - *lo;
  return p;
}

}  // namespace

Motifs combine_motifs(const std::vector<double>& x, const std::vector<double>& y, double limit) {
  return combine(
      y.size(), [&](std::size_t i) { return y[i]; }, [&](std::size_t i) { return x[i]; }, limit);
}

MotifParameters motif_parameters(std::span<const double> y, double spacing, double a_mm,
                                 double b_mm) {
  return parameters_of(y.size(), [&](std::size_t i) { return y[i]; }, spacing, a_mm, b_mm);
}

MotifParameters motif_parameters(std::span<const double> y, double intercept, double slope,
                                 double spacing, double a_mm, double b_mm) {
  // The expression of surface.cpp's without_line, so both routes give the same doubles.
  return parameters_of(
      y.size(), [&](std::size_t i) { return y[i] - intercept - slope * static_cast<double>(i); },
      spacing, a_mm, b_mm);
}

}  // namespace chatterlab::surface
