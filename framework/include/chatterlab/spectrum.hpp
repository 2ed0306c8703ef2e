#pragma once
// One-sided amplitude spectra of uniformly sampled signals and their peaks: the spectrum of a
// simulated vibration (chatter frequency, G7 sidebands), of a measured signal, or of a profile
// (undulations per revolution). Built on RealFft.
#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace chatterlab {

enum class SpectralWindow { rectangular, hann };

struct Spectrum {
  std::vector<double> frequency_hz;  // k * resolution_hz, k = 0..n/2
  std::vector<double> amplitude;     // same unit as the samples: a sine of amplitude A reads A
  double resolution_hz = 0.0;        // sample_rate_hz / n
};

// The mean is removed first (a DC offset would leak into the low bins through the window). The
// window's coherent gain is divided out, so the peak of a sine on a bin centre equals its
// amplitude (Hann: 1.5 bins wide main lobe, sidelobes < -31 dB). Needs >= 4 samples and a
// positive finite sample rate (std::invalid_argument).
Spectrum amplitude_spectrum(std::span<const double> samples, double sample_rate_hz,
                            SpectralWindow window = SpectralWindow::hann);

struct SpectralPeak {
  double frequency_hz = 0.0;  // refined between bins (parabola through log amplitudes)
  double amplitude = 0.0;     // refined peak height
  std::size_t bin = 0;        // the local-maximum bin
};

// Local maxima (strictly above both neighbours, DC excluded), largest first, each at least
// min_separation_hz from every larger peak kept, and at least relative_threshold times the
// largest. At most max_peaks. The parabolic refinement on log amplitude locates a Hann-windowed
// sine to about 1 % of a bin.
std::vector<SpectralPeak> find_peaks(const Spectrum& spectrum, std::size_t max_peaks,
                                     double min_separation_hz = 0.0,
                                     double relative_threshold = 1e-3);

std::string to_string(SpectralWindow window);

}  // namespace chatterlab
