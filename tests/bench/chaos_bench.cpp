// Speed of the nonlinear analyses (MODELS.md N) on 100,000-sample series against TISEAN 3.0.1.
//
// Kantz's method against TISEAN's lyap_k, side by side, on every signal of the validation suite
// (tests/validation/): `BM_LyapKProcess/<signal>` runs this program as a separate process on the
// signal written to a file (`chaos_bench --lyap-k FILE OUT`: read the file, Kantz curves with
// lyap_k's parameters, write them; start-up included) and, when TISEAN_BIN names TISEAN's bin
// directory, `lyap_k -m 2 -M 4` on the same file right after it; the counters give TISEAN's time
// and the ratio. lyap_k's defaults (read from its usage text and source): dimensions m..M,
// delay 1, 5 radii from 1/1000 to 1/100 of the data range (geometric), every point a reference,
// 50 iterations (S(k), k = 0..50), Theiler window 0, all neighbours within eps.
//
// The other benchmarks time the analyses in process: lyap_spec's work (m = 2, delay 1,
// 30 neighbours, every point a reference: BM_LyapSpec*), d2's (sampled references, and every
// pair within 2 % / 20 % of the range: BM_D2Henon*), and the Kantz scan alone (BM_LyapK*).
// Run single-threaded (OMP_NUM_THREADS=1) and with 2 threads; docs/performance.md records the
// figures and the commands.
#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <spawn.h>
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
#include "analysis/nonlinear_common/test_signals.hpp"
#include "chatterlab/signal_io.hpp"

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

// `chaos_bench --lyap-k FILE OUT`: our side of the side-by-side run, as lyap_k does it: read
// the series, compute, write S(k) per dimension and radius.
int lyap_k_process(const char* file, const char* out) {
  const auto x = read_data_table(file).columns.at(0);
  const auto scan = lyap_k_scan(x);
  std::FILE* f = std::fopen(out, "w");
  if (!f) return 1;
  for (std::size_t r = 0; r < scan.radii.size(); ++r)
    for (int m = scan.min_dimension; m <= scan.max_dimension; ++m) {
      std::fprintf(f, "#m= %d epsilon= %g\n", m, scan.radii[r]);
      const auto curve = scan.curve(r, m);
      for (std::size_t k = 0; k < curve.size(); ++k) std::fprintf(f, "%zu %.8g\n", k, curve[k]);
      std::fprintf(f, "\n\n");
    }
  return std::fclose(f) == 0 ? 0 : 1;
}

// Wall time of a child process (seconds), or a negative value if it failed.
double run_process(const std::vector<std::string>& args) {
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
  if (spawned != 0) return -1;
  int status = 0;
  waitpid(pid, &status, 0);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? seconds : -1;
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

void BM_LyapKProcess(benchmark::State& state, const std::string& name,
                     const std::function<std::vector<double>()>& make) {
  const std::string file = signal_file(name, make());
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const std::string ours_out = file + ".ours", tisean_out = file + ".lyap";
  const char* tisean = std::getenv("TISEAN_BIN");
  double tisean_total = 0, ours_total = 0;
  std::size_t runs = 0;
  for (auto _ : state) {
    const double ours = run_process({self, "--lyap-k", file, ours_out});
    if (ours < 0) {
      state.SkipWithError("chaos_bench --lyap-k failed");
      break;
    }
    state.SetIterationTime(ours);
    ours_total += ours;
    if (tisean) {
      const double t = run_process({std::string(tisean) + "/lyap_k", "-m", "2", "-M", "4", "-V",
                                    "0", "-o", tisean_out, file});
      if (t < 0) {
        state.SkipWithError("TISEAN lyap_k failed (TISEAN_BIN)");
        break;
      }
      tisean_total += t;
    }
    ++runs;
  }
  if (tisean && runs > 0) {
    state.counters["tisean_s"] = tisean_total / double(runs);
    state.counters["ratio"] = tisean_total / ours_total;
  }
}

[[maybe_unused]] const bool registered = [] {
  for (const auto& [name, make] : signals())
    benchmark::RegisterBenchmark(("BM_LyapKProcess/" + name).c_str(), BM_LyapKProcess, name, make)
        ->Unit(benchmark::kMillisecond)
        ->UseManualTime()
        ->Iterations(1);
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
  if (argc == 4 && std::string(argv[1]) == "--lyap-k") return lyap_k_process(argv[2], argv[3]);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
