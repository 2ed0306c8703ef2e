#include "runner/point_compute.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <stdexcept>

#include "chatterlab/errors.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/plugin_api.hpp"
#include "runner/output_dir.hpp"

namespace chatterlab::runner {

std::string with_plugin_context(const std::string& what, const Json& point_document,
                                const std::string& study_file) {
  const std::string plugins = out_of_tree_plugins_in(point_document);
  if (plugins.empty()) return what;
  return fmt::format("{} (out-of-tree plugins of this point: {}; study {})", what, plugins,
                     study_file);
}

ComputedPoint compute_point(const StudyKind& kind, const Study& study, std::size_t point,
                            const std::vector<std::string>& columns,
                            const std::filesystem::path& out_dir, bool plots) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  const std::size_t writes_failed_before = failed_output_writes_on_this_thread();
  ComputedPoint computed;
  PointResult& result = computed.result;
  result.done = true;
  Json document;
  try {
    document = study.point_document(point);
    PointContext context;
    context.index = point;
    context.point_count = study.point_count();
    context.artifact_dir = point_artifact_dir(out_dir, point, context.point_count);
    context.plots = plots;
    std::vector<Json> outputs = kind.run_point(document, context);
    if (outputs.size() != columns.size())
      throw std::logic_error(fmt::format("study kind {} returned {} outputs for {} columns",
                                         study.kind, outputs.size(), columns.size()));
    // A non-finite number is no result (and JSON, hence the journal, cannot carry it).
    for (std::size_t c = 0; c < columns.size(); ++c)
      if (outputs[c].is_number_float() && !std::isfinite(outputs[c].get<double>()))
        throw PointFailure(
            fmt::format("{} is not finite ({})", columns[c], outputs[c].get<double>()));
    result.outputs = std::move(outputs);
    result.status = "ok";
  } catch (...) {
    result.outputs.assign(columns.size(), Json());
    result.status = failure_status(
        with_plugin_context(describe_current_exception(), document, study.file.string()));
  }
  computed.compute_s = std::chrono::duration<double>(Clock::now() - start).count();
  computed.output_failed = failed_output_writes_on_this_thread() != writes_failed_before;
  // A grid point whose files could not all be written keeps none: they would be an incomplete
  // set, and they hold the room results.csv and meta.json still need (--retry-failed rewrites it).
  // A write error a kind caught (e.g. as a plot error) still fails the point: its files are not all there.
  if (computed.output_failed && result.status == "ok") {
    result.outputs.assign(columns.size(), Json());
    result.status = failure_status("a file of this point could not be written (disk full or I/O error; meta.json "
                                   "output_error): run again with --resume --retry-failed");
  }
  if (computed.output_failed && study.point_count() > 1) {
    std::error_code ignored;
    std::filesystem::remove_all(point_artifact_dir(out_dir, point, study.point_count()), ignored);
  }
  return computed;
}

// ------------------------------------------------------------------ InProcessGuard
namespace {

constexpr std::array<int, 5> fatal_signals = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
constexpr int max_watched_threads = 1024;

// One active guard per process (a run computes in one place at a time). Plain atomics: the
// signal handler reads them.
std::atomic<bool> guard_active{false};
std::atomic<int> watched_threads{0};
std::array<std::atomic<long long>, max_watched_threads> running_point;  // -1: idle
std::array<struct sigaction, fatal_signals.size()> previous_actions;
std::function<void(const std::string&)>* exit_callback = nullptr;
void (*last_words)(void*) = nullptr;
void* last_words_context = nullptr;

// Async-signal-safe: fixed buffer, no allocation.
struct SignalText {
  char text[512];
  std::size_t size = 0;
  void add(const char* s) {
    while (*s != '\0' && size + 1 < sizeof text) text[size++] = *s++;
  }
  void add(long long v) {
    char digits[24];
    int n = 0;
    if (v == 0) digits[n++] = '0';
    while (v > 0 && n < 24) digits[n++] = static_cast<char>('0' + v % 10), v /= 10;
    while (n > 0 && size + 1 < sizeof text) text[size++] = digits[--n];
  }
};

void add_running_points(SignalText& out) {
  bool any = false;
  const int threads = watched_threads.load();
  for (int t = 0; t < threads; ++t) {
    long long p = running_point[static_cast<std::size_t>(t)].load();
    if (p < 0) continue;
    out.add(any ? ", " : "");
    out.add(p);
    any = true;
  }
  if (!any) out.add("(none)");
}

void on_fatal_signal(int signal) {
  if (last_words != nullptr) last_words(last_words_context);
  SignalText message;
  message.add("\nchatterlab: fatal: signal ");
  message.add(static_cast<long long>(signal));
  message.add(" (");
  message.add(sigabbrev_np(signal) != nullptr ? sigabbrev_np(signal) : "?");
  message.add(") while computing grid point(s) ");
  add_running_points(message);
  message.add(
      " in this process. The journal keeps the points finished before it: run again with "
      "--resume --isolate to record such a point as failed and go on.\n");
  ssize_t ignored = ::write(STDERR_FILENO, message.text, message.size);
  (void)ignored;
  // Die as the process would have: the previous action (default, or a sanitizer's report) gets
  // the signal again (raised here: a signal sent with raise() would not repeat by itself).
  for (std::size_t i = 0; i < fatal_signals.size(); ++i)
    if (fatal_signals[i] == signal) sigaction(signal, &previous_actions[i], nullptr);
  raise(signal);
}

void on_exit() {
  if (!guard_active.load()) return;
  std::string points;
  const int threads = watched_threads.load();
  for (int t = 0; t < threads; ++t)
    if (long long p = running_point[static_cast<std::size_t>(t)].load(); p >= 0)
      points += (points.empty() ? "" : ", ") + std::to_string(p);
  if (points.empty()) return;  // a normal exit between points
  const std::string message = fmt::format(
      "a plugin ended the process (exit()) while grid point(s) {} were computed: the run is "
      "incomplete and its results were not written. The journal keeps the points finished "
      "before it: run again with --resume --isolate to record such a point as failed and go on",
      points);
  try {
    if (exit_callback != nullptr) (*exit_callback)(message);
  } catch (...) {  // meta.json could not be written either; the message below still says it
  }
  const std::string line = "chatterlab: error: " + message + "\n";
  ssize_t ignored = ::write(STDERR_FILENO, line.data(), line.size());
  (void)ignored;
  std::_Exit(3);
}

}  // namespace

InProcessGuard::InProcessGuard(int threads,
                               std::function<void(const std::string&)> on_exit_during_point,
                               void (*before_dying)(void*), void* context) {
  last_words = before_dying;
  last_words_context = context;
  static const bool registered = std::atexit(on_exit) == 0;
  (void)registered;
  watched_threads = std::min(threads, max_watched_threads);
  for (auto& slot : running_point) slot = -1;
  exit_callback = new std::function<void(const std::string&)>(std::move(on_exit_during_point));
  struct sigaction action {};
  action.sa_handler = on_fatal_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND | SA_NODEFER;
  for (std::size_t i = 0; i < fatal_signals.size(); ++i)
    sigaction(fatal_signals[i], &action, &previous_actions[i]);
  guard_active = true;
}

InProcessGuard::~InProcessGuard() {
  guard_active = false;
  for (std::size_t i = 0; i < fatal_signals.size(); ++i)
    sigaction(fatal_signals[i], &previous_actions[i], nullptr);
  delete exit_callback;
  exit_callback = nullptr;
  last_words = nullptr;
}

void InProcessGuard::started(int thread, std::size_t point) {
  if (thread >= 0 && thread < max_watched_threads)
    running_point[static_cast<std::size_t>(thread)] = static_cast<long long>(point);
}

void InProcessGuard::finished(int thread) {
  if (thread >= 0 && thread < max_watched_threads)
    running_point[static_cast<std::size_t>(thread)] = -1;
}

}  // namespace chatterlab::runner
