#pragma once
// Waviness parameters (MODELS.md W1, W2; docs/analysis/surface.md):
//   ISO 4287 definitions applied to the waviness profile w (form already removed, so its mean line
//   is w = 0): Wa = mean |w|, Wq = rms w, Wp = max w, Wv = -min w (a depth, >= 0), Wz = Wp + Wv,
//   Wsk = mean w^3 / Wq^3, Wku = mean w^4 / Wq^4 -- each over a sampling length and averaged over
//   the `sampling_lengths` equal sampling lengths of the evaluation length; Wt = max - min over
//   the whole evaluation length; WSm = mean width of the profile elements (height discrimination
//   10 % of Wz: an element is a peak above +0.1 Wz and the following valley below -0.1 Wz,
//   delimited by the mean-line up-crossings between them; peaks or valleys narrower than the
//   width discrimination join their neighbours -- the surface evaluation uses 1 % of the
//   cut-off, ISO's 1 % of the (roughness) sampling length lr = lc: with the sampling length
//   = the evaluation length, 1 % of it would swallow real waves of profiles with > 50 of them).
//   The book's Wz (W1, JB/Z168-81): mean of the five largest wave heights, a wave height being
//   the difference between a peak and the adjacent (following) valley of the same elements.
//   Frequency-resolved Wz|f (W2): the closed profile split into DFT bands of undulations per
//   revolution (UPR); the book's Wz of each band-limited profile with its dominant UPR and the
//   frequency that UPR had during grinding, f = UPR * n_w / 60.
#include <cstddef>
#include <span>
#include <optional>
#include <string>
#include <vector>

namespace chatterlab::surface {

struct WavinessParameters {
  double Wa = 0, Wq = 0, Wp = 0, Wv = 0, Wz = 0, Wt = 0, Wsk = 0, Wku = 0;
  std::optional<double> WSm;       // in the spacing's unit; none with fewer than 2 crossings
  double Wz_five = 0;              // book W1: mean of the five largest wave heights
  std::size_t wave_count = 0;      // waves found (Wz_five averages min(5, wave_count) heights)
};

// `w`: waviness profile with form removed; `spacing`: sample spacing (mm or deg); closed: one
// revolution, the profile wraps. sampling_lengths >= 1 (clamped to the sample count / 4);
// width_discrimination in samples (0: none).
WavinessParameters waviness_parameters(std::span<const double> w, double spacing, bool closed,
                                       int sampling_lengths = 1,
                                       double width_discrimination = 0.0);

// Profile elements of a profile about its mean line w = 0 with height discrimination h (> 0)
// and width discrimination (in samples: a peak or valley spanning fewer samples beyond +-h is
// joined into its neighbours): the positions (in samples) of the mean-line up-crossings that
// start elements and the heights peak - following valley of the waves.
struct ProfileElements {
  std::vector<double> up_crossings;  // fractional sample index (closed: of the rotated profile)
  std::vector<double> wave_heights;
};
ProfileElements profile_elements(std::span<const double> w, double height_discrimination,
                                 bool closed, double width_discrimination = 0.0);

// Mean of the five largest heights (all of them if fewer); 0 for none.
double mean_of_five_largest(std::vector<double> heights);

struct UprBand {
  double from_upr = 0, to_upr = 0;  // inclusive bin range
};

struct BandWaviness {
  UprBand band;
  double Wz = 0;               // book W1 on the band-limited profile
  std::size_t wave_count = 0;
  double dominant_upr = 0;     // bin with the largest amplitude in the band
  double dominant_amplitude = 0;
  double dominant_frequency_hz = 0;  // dominant_upr * work_speed_rpm / 60
};

// Default bands from the speeds (W2): Z = wheel_speed_rpm / work_speed_rpm wheel revolutions per
// work revolution, i.e. the forced (wheel-unbalance) lobes. Low band [max(2, round(Z/2)),
// round(3Z/2)] around Z; high band (chatter) above it up to the last DFT bin.
std::pair<UprBand, UprBand> default_bands(double wheel_speed_rpm, double work_speed_rpm,
                                          std::size_t samples_per_rev);

// Wz|f of one band of a closed profile (UPR 0 and 1 -- radius and eccentricity -- are never in a
// band: ranges are clipped to [2, N/2]).
BandWaviness band_waviness(std::span<const double> closed_profile, UprBand band,
                           double work_speed_rpm);

// The profile keeping only DFT bins in [from_upr, to_upr] (closed profiles).
std::vector<double> band_limited(std::span<const double> closed_profile, UprBand band);

}  // namespace chatterlab::surface
