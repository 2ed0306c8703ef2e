#include "chatterlab/fft.hpp"

#include <fftw3.h>
#include <fmt/format.h>

#include <algorithm>
#include <functional>
#include <mutex>
#include <new>
#include <stdexcept>
#include <utility>

namespace chatterlab {

namespace {
// FFTW's planner (and plan destruction) touch global state: one lock for the whole process.
std::mutex& planner_mutex() {
  static std::mutex mutex;
  return mutex;
}
}  // namespace

RealFft::RealFft(std::size_t n) : n_(n) {
  if (n == 0) throw std::invalid_argument("RealFft: length must be at least 1");
  const std::lock_guard lock(planner_mutex());
  real_ = fftw_alloc_real(n);
  complex_ = reinterpret_cast<std::complex<double>*>(fftw_alloc_complex(n / 2 + 1));
  if (real_ == nullptr || complex_ == nullptr) {
    fftw_free(real_);
    fftw_free(complex_);
    throw std::bad_alloc();
  }
  const int length = static_cast<int>(n);
  // FFTW_ESTIMATE: planning costs microseconds and never overwrites the buffers; MEASURE would
  // pay off only for thousands of transforms of one size, which no caller does.
  forward_plan_ = fftw_plan_dft_r2c_1d(length, real_, reinterpret_cast<fftw_complex*>(complex_),
                                       FFTW_ESTIMATE);
  inverse_plan_ = fftw_plan_dft_c2r_1d(length, reinterpret_cast<fftw_complex*>(complex_), real_,
                                       FFTW_ESTIMATE);
  if (forward_plan_ == nullptr || inverse_plan_ == nullptr) {
    if (forward_plan_) fftw_destroy_plan(static_cast<fftw_plan>(forward_plan_));
    if (inverse_plan_) fftw_destroy_plan(static_cast<fftw_plan>(inverse_plan_));
    fftw_free(real_);
    fftw_free(complex_);
    throw std::runtime_error(fmt::format("FFTW could not plan a transform of length {}", n));
  }
}

void RealFft::release() noexcept {
  if (n_ == 0 && real_ == nullptr) return;
  const std::lock_guard lock(planner_mutex());
  if (forward_plan_) fftw_destroy_plan(static_cast<fftw_plan>(forward_plan_));
  if (inverse_plan_) fftw_destroy_plan(static_cast<fftw_plan>(inverse_plan_));
  fftw_free(real_);
  fftw_free(complex_);
  forward_plan_ = inverse_plan_ = nullptr;
  real_ = nullptr;
  complex_ = nullptr;
  n_ = 0;
}

RealFft::~RealFft() { release(); }

RealFft::RealFft(RealFft&& other) noexcept
    : n_(std::exchange(other.n_, 0)),
      real_(std::exchange(other.real_, nullptr)),
      complex_(std::exchange(other.complex_, nullptr)),
      forward_plan_(std::exchange(other.forward_plan_, nullptr)),
      inverse_plan_(std::exchange(other.inverse_plan_, nullptr)) {}

RealFft& RealFft::operator=(RealFft&& other) noexcept {
  if (this != &other) {
    release();
    n_ = std::exchange(other.n_, 0);
    real_ = std::exchange(other.real_, nullptr);
    complex_ = std::exchange(other.complex_, nullptr);
    forward_plan_ = std::exchange(other.forward_plan_, nullptr);
    inverse_plan_ = std::exchange(other.inverse_plan_, nullptr);
  }
  return *this;
}

void RealFft::forward(std::span<const double> x, std::span<std::complex<double>> spectrum) {
  if (x.size() != n_ || spectrum.size() != spectrum_size())
    throw std::invalid_argument(fmt::format(
        "RealFft::forward: length {} needs {} samples and {} spectrum bins, got {} and {}", n_,
        n_, spectrum_size(), x.size(), spectrum.size()));
  std::copy(x.begin(), x.end(), real_);
  fftw_execute(static_cast<fftw_plan>(forward_plan_));
  std::copy(complex_, complex_ + spectrum_size(), spectrum.begin());
}

std::vector<std::complex<double>> RealFft::forward(std::span<const double> x) {
  std::vector<std::complex<double>> spectrum(spectrum_size());
  forward(x, spectrum);
  return spectrum;
}

void RealFft::inverse(std::span<const std::complex<double>> spectrum, std::span<double> x) {
  if (x.size() != n_ || spectrum.size() != spectrum_size())
    throw std::invalid_argument(fmt::format(
        "RealFft::inverse: length {} needs {} spectrum bins and {} samples, got {} and {}", n_,
        spectrum_size(), n_, spectrum.size(), x.size()));
  // c2r destroys its input: it works on the object's own buffer, never on the caller's.
  std::copy(spectrum.begin(), spectrum.end(), complex_);
  fftw_execute(static_cast<fftw_plan>(inverse_plan_));
  const double scale = 1.0 / static_cast<double>(n_);
  std::transform(real_, real_ + n_, x.begin(), [scale](double v) { return v * scale; });
}

std::vector<double> RealFft::inverse(std::span<const std::complex<double>> spectrum) {
  std::vector<double> x(n_);
  inverse(spectrum, x);
  return x;
}

InPlaceRealFft::InPlaceRealFft(std::span<const double> samples)
    : n_(samples.size()), buffer_(2 * (samples.size() / 2 + 1), 0.0) {
  if (n_ == 0) throw std::invalid_argument("InPlaceRealFft: length must be at least 1");
  std::copy(samples.begin(), samples.end(), buffer_.begin());
}

namespace {
// Plans under the lock (FFTW_ESTIMATE never touches the buffer), executes outside it.
void execute_once(const std::function<fftw_plan()>& plan_maker, std::size_t n) {
  fftw_plan plan = nullptr;
  {
    const std::lock_guard lock(planner_mutex());
    plan = plan_maker();
  }
  if (plan == nullptr)
    throw std::runtime_error(fmt::format("FFTW could not plan an in-place transform of length {}", n));
  fftw_execute(plan);
  const std::lock_guard lock(planner_mutex());
  fftw_destroy_plan(plan);
}
}  // namespace

void InPlaceRealFft::forward() {
  auto* real = buffer_.data();
  auto* complex = reinterpret_cast<fftw_complex*>(buffer_.data());
  execute_once([&] { return fftw_plan_dft_r2c_1d(static_cast<int>(n_), real, complex, FFTW_ESTIMATE); },
               n_);
}

void InPlaceRealFft::inverse() {
  auto* real = buffer_.data();
  auto* complex = reinterpret_cast<fftw_complex*>(buffer_.data());
  execute_once([&] { return fftw_plan_dft_c2r_1d(static_cast<int>(n_), complex, real, FFTW_ESTIMATE); },
               n_);
  const double scale = 1.0 / static_cast<double>(n_);
  for (std::size_t j = 0; j < n_; ++j) buffer_[j] *= scale;
}

std::vector<double> InPlaceRealFft::take_samples() {
  std::vector<double> out = std::move(buffer_);
  out.resize(n_);
  n_ = 0;
  buffer_.clear();
  return out;
}

}  // namespace chatterlab
