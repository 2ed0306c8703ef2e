#include "runner/progress.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>

namespace chatterlab::runner {

namespace {
constexpr int bar_width = 30;
constexpr auto redraw_interval = std::chrono::milliseconds(200);

std::string duration_text(double seconds) {
  if (!std::isfinite(seconds)) return "?";
  auto s = static_cast<long long>(std::llround(seconds));
  if (s < 60) return fmt::format("{} s", s);
  if (s < 3600) return fmt::format("{}:{:02} min", s / 60, s % 60);
  return fmt::format("{}:{:02}:{:02} h", s / 3600, (s / 60) % 60, s % 60);
}
}  // namespace

bool stderr_is_terminal() { return ::isatty(STDERR_FILENO) == 1; }

ProgressBar::ProgressBar(bool enabled, std::size_t total)
    : enabled_(enabled && total > 0),
      total_(total),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

std::string ProgressBar::format(std::size_t done, std::size_t total, double elapsed_s) {
  double fraction = total == 0 ? 1.0 : static_cast<double>(done) / static_cast<double>(total);
  int filled = static_cast<int>(fraction * bar_width);
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.resize(bar_width, '.');
  // ETA from the mean rate so far: grid points of one study cost about the same on average.
  std::string eta = done == 0 ? "?"
                              : duration_text(elapsed_s / static_cast<double>(done) *
                                              static_cast<double>(total - done));
  return fmt::format("[{}] {:3.0f}%  {}/{} points  {} elapsed  ETA {}", bar, 100.0 * fraction, done,
                     total, duration_text(elapsed_s), eta);
}

void ProgressBar::draw(std::size_t done, double elapsed_s) {
  std::fprintf(stderr, "\r%s", format(done, total_, elapsed_s).c_str());
  std::fflush(stderr);
}

void ProgressBar::point_done() { points_done(1); }

void ProgressBar::points_done(std::size_t n) {
  if (!enabled_) return;
  std::lock_guard lock(mutex_);
  done_ += n;
  auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < redraw_interval && done_ != total_) return;
  last_draw_ = now;
  draw(done_, std::chrono::duration<double>(now - start_).count());
}

void ProgressBar::finish() {
  if (!enabled_) return;
  std::lock_guard lock(mutex_);
  draw(done_, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
  std::fputc('\n', stderr);
  std::fflush(stderr);
}

}  // namespace chatterlab::runner
