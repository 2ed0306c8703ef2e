#pragma once
// Roundness by multi-probe error separation (MODELS.md E1-E5; book ch. 6). docs/analysis/
// error_separation.md states the equations; this header is the numerical core shared by the
// `error_separation` study kind, the cylindricity reconstruction (E6) and the tests.
//
// Conventions. One revolution holds N samples, theta_i = 2 pi i / N. Probe q sits at angle phi_q
// (rad) and reads, at sample i,
//     Y_q(i) = r(theta_i + phi_q) + dx(i) cos phi_q + dy(i) sin phi_q
// (r: the part's form, dx/dy: the spindle's radial error motion). Weights c_q with
// sum c_q cos phi_q = sum c_q sin phi_q = 0 cancel the spindle: S(i) = sum c_q Y_q(i) depends on
// r alone, and in the DFT (FFTW sign: X(l) = sum x(i) e^{-j 2 pi l i/N}) S(l) = G(l) R(l) with
//     G(l) = sum_q c_q e^{j l phi_q}                                          (E2)
// (e^{j 2 pi l p_q / N} for integer probe offsets p_q = N phi_q / 2 pi). G(1) = 0 always: the
// first harmonic (eccentricity) is lost and is reported inside the spindle motion.
#include <complex>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace chatterlab::error_separation {

// Probe angles and the weights that combine their signals.
struct ProbeLayout {
  std::vector<double> angles_rad;  // phi_q
  std::vector<double> weights;     // c_q
};

// E1/E2 three-probe weights c0 = 1, c1 = -sin(phi2 - phi0)/sin(phi2 - phi1),
// c2 = sin(phi1 - phi0)/sin(phi2 - phi1). Throws std::invalid_argument when the probes are
// collinear through the centre (sin(phi2 - phi1) ~ 0, or two probes at one angle).
std::vector<double> three_point_weights(std::span<const double> angles_rad);

// E5 n-point weights (n >= 3): the spindle-cancelling weights whose G(l) is as flat as possible
// over l = 2..max_harmonic, i.e. minimise sum_l |G(l) - 1|^2 subject to
// sum c cos phi = sum c sin phi = 0 (equality-constrained least squares on the null space of the
// constraints). Scaled so that c0 = 1 (Q(l) and R = S/G do not depend on the scale). For three
// probes this is the three-point weight vector.
std::vector<double> balanced_weights(std::span<const double> angles_rad, int max_harmonic);

// max(|sum c cos phi|, |sum c sin phi|) / sum |c|: zero for weights that cancel spindle motion.
double spindle_residual(const ProbeLayout& layout);

// G(l) for l = 0..max_harmonic (E2).
std::vector<std::complex<double>> weight_function(const ProbeLayout& layout, int max_harmonic);

// Amplitude and error transfer (E2): W(l) = 1/|G(l)|, Q(l) = sqrt(sum c^2)/|G(l)|
// (infinite where G(l) = 0).
struct Transfer {
  std::vector<int> harmonic;  // 0..max_harmonic
  std::vector<double> g_abs, w, q;
};
Transfer transfer(const ProbeLayout& layout, int max_harmonic);

// Harmonics l in [2, max_harmonic] with |G(l)| <= tolerance * sum |c|: the probe layout cannot
// see them (set to zero in the separated profile). For integer offsets a zero is exact to
// rounding; gcd(p1 - p0, p2 - p0, N) = d > 1 suppresses l = k N/d +/- 1.
std::vector<int> suppressed_harmonics(const ProbeLayout& layout, int max_harmonic,
                                      double tolerance);

// The worst (largest) error transfer Q(l) over the band l = min_harmonic..max_harmonic: infinite
// when the layout suppresses a harmonic of the band (|G(l)| <= suppression_tolerance sum |c|:
// noise there is amplified without bound and the form there is not measured at all); the worst
// over the harmonics the layout sees is reported beside it.
struct WorstTransfer {
  double q = 0.0;             // +inf when a harmonic of the band is lost
  int harmonic = 0;           // where (the first lost harmonic when infinite)
  double seen_q = 0.0;        // over the harmonics the layout sees
  int seen_harmonic = 0;
  std::size_t lost = 0;       // lost harmonics in the band
};
WorstTransfer worst_q(const ProbeLayout& layout, int max_harmonic, double suppression_tolerance = 1e-6,
                      int min_harmonic = 2);

// What a layout loses of the measured signals: the probe signals' amplitude per harmonic (mean
// over the probes, l = 0..max_harmonic) and the share of their power in the band
// min_harmonic..max_harmonic that lies at the lost harmonics. The form there cannot be told from
// spindle motion; this share is what the separated profile may miss (an upper estimate of the
// form's share when the spindle moves little).
struct LostSpectrum {
  std::vector<int> harmonics;      // lost harmonics in the band
  std::vector<double> amplitude;   // mean probe amplitude per harmonic 0..max_harmonic
  double lost_share = 0.0;         // lost power / band power (0..1)
};
LostSpectrum lost_spectrum(std::span<const std::vector<double>> probes, const std::vector<int>& lost,
                           int min_harmonic, int max_harmonic);

// Zero-phase FIR low-pass (E3): a Hamming-windowed sinc, symmetric h(-k) = h(k) (real response:
// no phase shift), cut off half-way between passband_upr and stopband_upr. Length: the smallest odd
// L >= 3.3 N / (stopband - passband) (the Hamming window's transition width), giving a passband
// gain within 0.3 % of 1 (DC included) and >= 50 dB stopband attenuation (0.28 % and 51.8 dB for
// 32/64 UPR at N = 1024). Applied circularly to a closed profile.
struct FirDesign {
  double passband_upr = 0.0;
  double stopband_upr = 0.0;
  std::vector<double> taps;  // h(-K..K), size 2K + 1
};
FirDesign design_zero_phase_lowpass(double passband_upr, double stopband_upr,
                                    std::size_t samples_per_rev);
// Real frequency response H(l), l = 0..N/2, of the taps applied circularly over N samples.
std::vector<double> fir_response(const FirDesign& fir, std::size_t samples_per_rev);

// Ensemble average of M = values.size() / N revolutions (E3: noise variance / M).
// values.size() must be a positive multiple of n.
std::vector<double> average_revolutions(std::span<const double> values, std::size_t n);

// Options shared by every separation method.
struct SeparationOptions {
  int max_harmonic = -1;                // harmonics above it are set to zero; < 0: N/2 (all)
  double suppression_tolerance = 1e-6;  // see suppressed_harmonics
  double validity_fraction = 0.05;      // first-harmonic check limit, fraction of the S range
  std::optional<FirDesign> fir;         // zero-phase smoothing of the profile
  int max_recursion_passes = 20;        // time recursion (E4)
};

// The first-harmonic validity check (E2): the combined signal S has no first harmonic in
// theory (G(1) = 0); a measured amplitude |S_1| above validity_fraction * (max S - min S) means
// the data do not fit the probe layout (angles wrong, signals not synchronised, drift).
struct FirstHarmonicCheck {
  double amplitude = 0.0;  // amplitude of the once-per-revolution component of S
  double limit = 0.0;
  bool valid = true;
};

struct Separation {
  std::vector<double> profile;    // r(theta_i) minus its mean, first harmonic removed
  double mean_radius = 0.0;       // R(0)/G(0): the mean of r relative to the probes' zero
  bool mean_radius_known = true;  // false when G(0) = 0
  std::vector<double> dx, dy;     // spindle motion (with the part's eccentricity), per sample
  std::vector<int> suppressed;    // harmonics set to zero (see suppressed_harmonics)
  FirstHarmonicCheck first_harmonic;
  int recursion_passes = 0;  // time recursion only
  double roundness() const;  // peak-to-valley of `profile` (about the least-squares centre)
};

// S(i) = sum_q c_q Y_q(i).
std::vector<double> combine(std::span<const std::vector<double>> probes,
                            std::span<const double> weights);

// E1/E2 (3 probes) and E5 (n probes): frequency-domain separation R(l) = S(l)/G(l) where
// G(l) != 0 (R(0) = mean radius, R(1) = 0), then the spindle motion by least squares over all
// probes: Y_q(i) - r(theta_i + phi_q) = dx cos phi_q + dy sin phi_q. probes[q] has N samples;
// exact for any profile when the offsets are whole samples, for profiles band-limited below N/2
// otherwise.
Separation separate_frequency(std::span<const std::vector<double>> probes,
                              const ProbeLayout& layout, const SeparationOptions& options);

// E4 time-domain recursion: probes at phi0, phi0 + phi, phi0 + 2 phi with phi = 2 pi p / N,
// gcd(p, N) = 1 (std::invalid_argument otherwise), offsets whole samples. Weights
// (1, -2 cos phi, 1); r(k + 2p) = S(k) + 2 cos phi r(k + p) - r(k) walks the chain 0, p, 2p, ...
// through every sample. Its homogeneous solutions are exactly the first harmonic, so the unknown
// starting values only add an eccentricity, removed afterwards with the least-squares centre.
// Passes repeat from the values the previous pass ended with until they close (change
// <= 1e-12 of the signal range).
Separation separate_time_recursion(std::span<const std::vector<double>> probes,
                                   const ProbeLayout& layout, const SeparationOptions& options);

// E5 two-point approximation: probes A at phi0 and C at phi0 + pi - 2 pi/N of the three-point
// layout (phi0, phi0 + pi/2, phi0 + pi - 2 pi/N) whose middle weight b = -tan(2 pi/N) is
// dropped: S^ = A + c C, R^ = S^/G with the three-point G. The error is
// Delta R(l)/R(l) = b e^{j l pi/2}/G(l) (book 6-54): about pi/N for even harmonics, larger for
// odd ones. `probes` holds A and C.
Separation separate_two_point(std::span<const std::vector<double>> probes, double phi0_rad,
                              const SeparationOptions& options);
// The three-point layout behind the two-point approximation (weights exact).
ProbeLayout two_point_layout(double phi0_rad, std::size_t samples_per_rev);

// Least-squares centre of a closed profile (E4): the first Fourier coefficients
// a = (2/N) sum r cos theta, b = (2/N) sum r sin theta; returns r - a cos - b sin.
std::vector<double> remove_first_harmonic(std::span<const double> profile);

// Probe-angle optimisation (E2): over probe angles on a grid of `step` samples (phi0 = 0,
// 0 < phi1 < phi2 <= max_span), the three-point layout with no suppressed harmonic in the band
// min_harmonic..max_harmonic and the smallest worst Q(l) there.
struct AngleOptimum {
  bool found = false;
  std::vector<double> angles_rad;
  WorstTransfer worst;
  std::size_t layouts_checked = 0;
};
AngleOptimum optimise_three_point_angles(std::size_t samples_per_rev, int max_harmonic,
                                         double max_span_rad, double suppression_tolerance,
                                         int min_harmonic = 2);

// |G(l)| / sum|c| of the three-point layout (0, phi1, phi2) for a row of phi2 values and
// l = 2..max_harmonic: the harmonic-suppression map (row-major, phi2 slowest). NaN where the
// layout has no weights (phi2 = phi1 or phi2 = phi1 + pi).
std::vector<double> suppression_map(double phi1_rad, std::span<const double> phi2_rad,
                                    int max_harmonic);

}  // namespace chatterlab::error_separation
