#pragma once
// Discrete Fourier transforms of real signals through FFTW, shared by every analysis that needs
// one (spectra of simulations, IAAFT surrogates, Gaussian filters of closed profiles, error
// separation). FFTW's planner is not thread-safe, its plan execution is: a RealFft plans in its
// constructor under a process-wide lock and then transforms without locking. Use one object per
// thread (the object owns its work buffers).
#include <complex>
#include <cstddef>
#include <span>
#include <vector>

namespace chatterlab {

class RealFft {
 public:
  // Transform length n >= 1 (any n; FFTW is fast for every size, fastest for 2^a 3^b 5^c 7^d).
  explicit RealFft(std::size_t n);
  ~RealFft();
  RealFft(const RealFft&) = delete;
  RealFft& operator=(const RealFft&) = delete;
  RealFft(RealFft&& other) noexcept;
  RealFft& operator=(RealFft&& other) noexcept;

  std::size_t size() const { return n_; }
  std::size_t spectrum_size() const { return n_ / 2 + 1; }

  // X[k] = sum_{j<n} x[j] exp(-2 pi i k j / n), k = 0..n/2 (unnormalised, FFTW's convention).
  // x.size() must be n, spectrum.size() n/2 + 1 (std::invalid_argument otherwise).
  void forward(std::span<const double> x, std::span<std::complex<double>> spectrum);
  std::vector<std::complex<double>> forward(std::span<const double> x);

  // x[j] = (1/n) sum_k X[k] exp(+2 pi i k j / n) over the full Hermitian spectrum: normalised, so
  // inverse(forward(x)) == x. The imaginary parts of X[0] (and X[n/2] for even n) are ignored.
  void inverse(std::span<const std::complex<double>> spectrum, std::span<double> x);
  std::vector<double> inverse(std::span<const std::complex<double>> spectrum);

 private:
  void release() noexcept;
  std::size_t n_ = 0;
  double* real_ = nullptr;            // fftw_malloc'd, n
  std::complex<double>* complex_ = nullptr;  // fftw_malloc'd, n/2 + 1
  void* forward_plan_ = nullptr;      // fftw_plan
  void* inverse_plan_ = nullptr;
};

// One real signal transformed in place, in one buffer of 2 (n/2 + 1) doubles (FFTW's padded
// in-place layout): for signals so long that the copies matter. RealFft holds 16 bytes per sample
// of its own buffers and returns fresh arrays; this holds 8 (a whole-revolution filter of a
// 10^7-sample closed profile, issue 23). Same conventions as RealFft: forward unnormalised,
// inverse normalised. Plans are made per transform under RealFft's planner lock (FFTW_ESTIMATE:
// microseconds, negligible beside a transform of a long signal).
class InPlaceRealFft {
 public:
  // The n samples, copied into the padded buffer (n >= 1).
  explicit InPlaceRealFft(std::span<const double> samples);

  std::size_t size() const { return n_; }
  // The n samples: valid before forward() and after inverse().
  std::span<double> samples() { return {buffer_.data(), n_}; }
  // The n/2 + 1 bins X[k]: valid after forward() (and until inverse()).
  std::span<std::complex<double>> spectrum() {
    return {reinterpret_cast<std::complex<double>*>(buffer_.data()), n_ / 2 + 1};
  }
  void forward();
  void inverse();
  // The samples as a vector of n (the buffer itself, no copy: capacity 2 (n/2 + 1)); the object
  // is empty afterwards.
  std::vector<double> take_samples();

 private:
  std::size_t n_;
  std::vector<double> buffer_;
};

}  // namespace chatterlab
