// Speed of the nonlinear analyses (MODELS.md N) on 100,000-sample series against TISEAN 3.0.1.
//
// Side by side with TISEAN, as processes on the same file (start-up, reading and writing
// included): `BM_Process/<tool>/<signal>` writes the signal to a file once, then per iteration
// runs this program (`chaos_bench --run TOOL FILE OUT`: read the file, compute, write the result)
// and, when TISEAN_BIN names TISEAN's bin directory, the TISEAN program on the same file right
// after it. The time is the process's CPU time (user + system: steadier than the wall time on
// a shared machine; the wall times are counters); the counters give TISEAN's times and the
// CPU-time ratio. Tools:
//  - lyap_k (Kantz's method) on every signal of the validation suite (tests/validation/):
//    `lyap_k -m 2 -M 4`, i.e. dimensions 2..4, delay 1, 5 radii from 1/1000 to 1/100 of the data
//    range (geometric), every point a reference, 50 iterations (S(k), k = 0..50), Theiler
//    window 0, all neighbours within eps (its defaults, read from its usage text and source);
//  - d2 (Henon, Lorenz): `d2 -d 1 -M 1,10 -t 0 -N 0 -R <2 % of the range>`, every pair closer
//    than 2 % of the range in dimensions 1..10;
//  - lyap_spec (Henon, Lorenz): `lyap_spec -m 1,2 -k 30`, local Jacobians from 30 neighbours at
//    every point, dimension 2, delay 1.
//
// The other benchmarks time the analyses in process: lyap_spec's work (BM_LyapSpec*), d2's
// (sampled references, and every pair within 2 % / 20 % of the range: BM_D2Henon*), and the
// Kantz scan alone (BM_LyapK*). Run single-threaded (OMP_NUM_THREADS=1) and with 2 threads;
// docs/performance.md records the figures and the commands.
#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>

#include "analysis/correlation_dimension/correlation_dimension.hpp"
#include "analysis/lyapunov/lyapunov.hpp"
#include "analysis/lyapunov_spectrum/lyapunov_spectrum.hpp"
#include "shared/nonlinear/test_signals.hpp"
#include "chatterlab/signal_io.hpp"

#include <fmt/format.h>

extern char** environ;

namespace {

using namespace chatterlab;
namespace ts = test_signals;
namespace fs = std::filesystem;

constexpr std::size_t samples = 100000;

const std::vector<double>& henon() {
  static const auto x = ts::henon(samples);
  return x;
}
const std::vector<double>& lorenz() {
  static const auto x = ts::lorenz(samples);
  return x;
}

// The validation suite's signals at 100,000 samples.
const std::vector<std::pair<std::string, std::function<std::vector<double>()>>>& signals() {
  static const std::vector<std::pair<std::string, std::function<std::vector<double>()>>> list{
      {"henon", [] { return ts::henon(samples); }},
      {"ikeda", [] { return ts::ikeda(samples); }},
      {"lorenz", [] { return ts::lorenz(samples); }},
      {"roessler", [] { return ts::roessler(samples); }},
      {"mackey_glass", [] { return ts::mackey_glass(samples); }},
      {"torus", [] { return ts::torus(samples); }},
      {"ar2", [] { return ts::ar2(samples, 5); }},
      {"ar1_tanh", [] { return ts::saturated(ts::ar2(samples, 8, 0.95, 0.0)); }},
      {"power_law_noise", [] { return ts::power_law_noise(samples, 1.5, 7); }},
      {"white_noise", [] { return ts::white_noise(samples, 3); }},
      {"henon_noise_5", [] { return ts::with_noise(ts::henon(samples), 0.05, 9); }},
      {"henon_noise_20", [] { return ts::with_noise(ts::henon(samples), 0.2, 9); }},
      {"lorenz_noise_10", [] { return ts::with_noise(ts::lorenz(samples), 0.1, 9); }},
  };
  return list;
}

// lyap_k's default radii: 5, geometric, 1/1000 to 1/100 of the data range.
std::vector<double> lyap_k_radii(const std::vector<double>& x) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  std::vector<double> radii;
  for (int r = 0; r < 5; ++r) radii.push_back((*hi - *lo) * 1e-3 * std::pow(10.0, r / 4.0));
  return radii;
}

// lyap_k's work: -m 2 -M 4, every point a reference, 50 iterations, Theiler window 0.
KantzScan lyap_k_scan(const std::vector<double>& x) {
  return kantz_scan(x, 2, 4, 1, 0, 51, 0, lyap_k_radii(x));
}

double data_range(const std::vector<double>& x) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  return *hi - *lo;
}

// A TISEAN program and our side of the same work, run as processes on the same file. Our side
// (`chaos_bench --run TOOL FILE OUT`) reads the series, computes and writes the result as the
// TISEAN program does (start-up, reading and writing included).
struct Tool {
  const char* name;
  void (*ours)(const std::vector<double>& x, std::FILE* out);
  // TISEAN's command line (after the program) for the file, output and data.
  std::vector<std::string> (*tisean_args)(const std::string& file, const std::string& out,
                                          const std::vector<double>& x);
};

// lyap_k -m 2 -M 4: S(k) per dimension and radius.
void lyap_k_ours(const std::vector<double>& x, std::FILE* f) {
  const auto scan = lyap_k_scan(x);
  for (std::size_t r = 0; r < scan.radii.size(); ++r)
    for (int m = scan.min_dimension; m <= scan.max_dimension; ++m) {
      std::fprintf(f, "#m= %d epsilon= %g\n", m, scan.radii[r]);
      const auto curve = scan.curve(r, m);
      for (std::size_t k = 0; k < curve.size(); ++k) std::fprintf(f, "%zu %.8g\n", k, curve[k]);
      std::fprintf(f, "\n\n");
    }
}
std::vector<std::string> lyap_k_tisean(const std::string& file, const std::string& out,
                                       const std::vector<double>&) {
  return {"-m", "2", "-M", "4", "-V", "0", "-o", out, file};
}

// d2 -d 1 -M 1,10 -t 0 -N 0 -R (2 % of the range): every pair closer than 2 % of the range in
// dimensions 1..10; C(r) per dimension.
constexpr double d2_cut = 0.02;
void d2_ours(const std::vector<double>& x, std::FILE* f) {
  const auto sums = correlation_sums_within(x, 10, 1, 0, d2_cut);
  const auto log_r = sums.log_radii();
  for (int d = 1; d <= 10; ++d) {
    std::fprintf(f, "#dim= %d\n", d);
    const auto log_c = sums.log_correlation(d);
    for (std::size_t k = 0; k < log_c.size(); ++k)
      if (std::isfinite(log_c[k])) std::fprintf(f, "%.8g %.8g\n", std::exp(log_r[k]), std::exp(log_c[k]));
    std::fprintf(f, "\n\n");
  }
}
std::vector<std::string> d2_tisean(const std::string& file, const std::string& out,
                                   const std::vector<double>& x) {
  return {"-d", "1", "-M", "1,10", "-t", "0", "-N", "0",
          "-R", fmt::format("{:.17g}", d2_cut * data_range(x)), "-V", "0", "-o", out, file};
}

// lyap_spec -m 1,2 -k 30 (delay 1, one-step Jacobians, every point a reference).
void lyap_spec_ours(const std::vector<double>& x, std::FILE* f) {
  const auto s = lyapunov_spectrum(x, 2, 1, 0, 1, 30, x.size());
  for (double v : s.exponents) std::fprintf(f, "%.8g ", v);
  std::fprintf(f, "\n");
}
std::vector<std::string> lyap_spec_tisean(const std::string& file, const std::string& out,
                                          const std::vector<double>&) {
  return {"-m", "1,2", "-k", "30", "-V", "0", "-o", out, file};
}

const Tool tools[] = {{"lyap_k", lyap_k_ours, lyap_k_tisean},
                      {"d2", d2_ours, d2_tisean},
                      {"lyap_spec", lyap_spec_ours, lyap_spec_tisean}};

const Tool* find_tool(const std::string& name) {
  for (const auto& t : tools)
    if (name == t.name) return &t;
  return nullptr;
}

int run_tool(const char* tool, const char* file, const char* out) {
  const Tool* t = find_tool(tool);
  if (!t) return 2;
  const auto x = read_data_table(file).columns.at(0);
  std::FILE* f = std::fopen(out, "w");
  if (!f) return 1;
  t->ours(x, f);
  return std::fclose(f) == 0 ? 0 : 1;
}

// Wall and CPU time (user + system) of a child process, in seconds; negative if it failed. On
// a shared machine the CPU time is the steadier measure (the wall time includes waiting for a
// core); both include start-up, reading and writing.
struct ProcessTime {
  double wall = -1, cpu = -1;
  bool ok() const { return wall >= 0; }
};
ProcessTime run_process(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  const auto start = std::chrono::steady_clock::now();
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) return {};
  int status = 0;
  rusage usage{};
  wait4(pid, &status, 0, &usage);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) return {};
  auto seconds = [](const timeval& t) { return double(t.tv_sec) + 1e-6 * double(t.tv_usec); };
  return {wall, seconds(usage.ru_utime) + seconds(usage.ru_stime)};
}

// The signal written once to a file both programs read (one value per line, full precision).
std::string signal_file(const std::string& name, const std::vector<double>& x) {
  const fs::path file = fs::temp_directory_path() / ("chaos_bench_" + name + ".dat");
  if (!fs::exists(file)) {
    std::ofstream out(file);
    out.precision(17);
    for (double v : x) out << v << '\n';
  }
  return file.string();
}

// Per iteration: our process, then TISEAN's (when TISEAN_BIN names its bin directory) on the
// same file. The manual time is our CPU time; counters: our wall time, TISEAN's CPU and wall
// times (means over the iterations) and the CPU-time ratio TISEAN / ours.
void BM_Process(benchmark::State& state, const Tool* tool, const std::string& name,
                const std::function<std::vector<double>()>& make) {
  const auto x = make();
  const std::string file = signal_file(name, x);
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const std::string ours_out = file + ".ours", tisean_out = file + "." + tool->name;
  const char* tisean = std::getenv("TISEAN_BIN");
  ProcessTime ours_total{0, 0}, tisean_total{0, 0};
  std::size_t runs = 0;
  for (auto _ : state) {
    const ProcessTime ours = run_process({self, "--run", tool->name, file, ours_out});
    if (!ours.ok()) {
      state.SkipWithError("chaos_bench --run failed");
      break;
    }
    state.SetIterationTime(ours.cpu);
    ours_total.wall += ours.wall;
    ours_total.cpu += ours.cpu;
    if (tisean) {
      std::vector<std::string> args{std::string(tisean) + "/" + tool->name};
      for (auto& a : tool->tisean_args(file, tisean_out, x)) args.push_back(a);
      const ProcessTime t = run_process(args);
      if (!t.ok()) {
        state.SkipWithError("the TISEAN program failed (TISEAN_BIN)");
        break;
      }
      tisean_total.wall += t.wall;
      tisean_total.cpu += t.cpu;
    }
    ++runs;
  }
  if (runs == 0) return;
  state.counters["wall_s"] = ours_total.wall / double(runs);
  if (tisean) {
    state.counters["tisean_cpu_s"] = tisean_total.cpu / double(runs);
    state.counters["tisean_wall_s"] = tisean_total.wall / double(runs);
    state.counters["ratio"] = tisean_total.cpu / ours_total.cpu;
  }
}

// lyap_k on every validation signal; d2 and lyap_spec on the Henon map and the Lorenz flow.
[[maybe_unused]] const bool registered = [] {
  for (const auto& [name, make] : signals())
    for (const auto& tool : tools) {
      if (std::string(tool.name) != "lyap_k" && name != "henon" && name != "lorenz") continue;
      benchmark::RegisterBenchmark(fmt::format("BM_Process/{}/{}", tool.name, name).c_str(),
                                   BM_Process, &tool, name, make)
          ->Unit(benchmark::kMillisecond)
          ->UseManualTime()
          ->Iterations(1);
    }
  return true;
}();

void BM_LyapSpecHenon(benchmark::State& state) {
  for (auto _ : state) {
    auto s = lyapunov_spectrum(henon(), 2, 1, 0, 1, 30, 100000);
    benchmark::DoNotOptimize(s.exponents);
    state.counters["lambda1"] = s.exponents[0];
  }
}
BENCHMARK(BM_LyapSpecHenon)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_LyapSpecLorenz(benchmark::State& state) {
  for (auto _ : state) {
    auto s = lyapunov_spectrum(lorenz(), 2, 1, 0, 1, 30, 100000);
    benchmark::DoNotOptimize(s.exponents);
  }
}
BENCHMARK(BM_LyapSpecLorenz)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_D2Henon(benchmark::State& state) {
  for (auto _ : state) {
    auto sums = correlation_sums(henon(), 10, 1, 0, std::size_t(state.range(0)));
    benchmark::DoNotOptimize(sums.counts);
  }
}
BENCHMARK(BM_D2Henon)->Arg(2000)->Arg(10000)->Unit(benchmark::kMillisecond)->UseRealTime();

// TISEAN d2's work with all pairs (-N 0): dimensions 1..10, every pair closer than 2 % (arg 20) or
// 20 % (arg 200) of the range, counted exactly (sorted strips), radii binned 8 per octave.
void BM_D2HenonAllPairs(benchmark::State& state) {
  const double cut = double(state.range(0)) / 1000.0;
  for (auto _ : state) {
    auto sums = correlation_sums_within(henon(), 10, 1, 0, cut);
    benchmark::DoNotOptimize(sums.counts);
    // Ordered pairs closer than the cut in dimensions 2 and 10 (each pair counts for both of its
    // vectors): the work that grows with the cut.
    for (const int d : {2, 10}) {
      double pairs = 0;
      for (std::size_t b = 0; b < CorrelationSums::blocks; ++b)
        for (std::size_t k = 0; CorrelationSums::edge(k) <= cut; ++k)
          pairs += double(sums.counts[(b * 10 + std::size_t(d - 1)) * CorrelationSums::bins + k]);
      state.counters[d == 2 ? "pairs_m2" : "pairs_m10"] = pairs;
    }
  }
}
BENCHMARK(BM_D2HenonAllPairs)->Arg(20)->Arg(200)->Unit(benchmark::kMillisecond)->UseRealTime();

// The Kantz scan of lyap_k's work in process (no file, no start-up): for profiling.
void lyap_k_in_process(benchmark::State& state, const std::vector<double>& x) {
  for (auto _ : state) {
    auto scan = lyap_k_scan(x);
    benchmark::DoNotOptimize(scan.sum);
    const auto curve = scan.curve(2, 2);
    state.counters["slope_m2_eps3"] = (curve[10] - curve[2]) / 8.0;
  }
}
void BM_LyapKHenon(benchmark::State& state) { lyap_k_in_process(state, henon()); }
void BM_LyapKLorenz(benchmark::State& state) { lyap_k_in_process(state, lorenz()); }
BENCHMARK(BM_LyapKHenon)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_LyapKLorenz)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  if (argc == 5 && std::string(argv[1]) == "--run") return run_tool(argv[2], argv[3], argv[4]);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
