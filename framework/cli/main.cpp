// The `chatterlab` command: list, describe, validate, run; the SDK commands (new-plugin,
// check-plugin, init, completion) are in sdk_commands.cpp.
//
// Exit codes (docs/studies.md, "Exit codes"), one meaning each: 0 every grid point ok, 1 some
// points failed or timed out (each recorded in results.csv and meta.json), 2 rejected: bad input,
// a usage error, an unusable or busy output directory, a refused --resume (nothing run, nothing
// written), or an input file that changed during the run (stopped, results.csv not written),
// 3 an output could not be written (disk full, I/O error; meta.json says which). Errors go to
// stderr as "chatterlab: error: <message>", never as a stack trace. Under mpirun every rank
// loads the same study and the runner makes its errors collective, so only rank 0 prints.
#include <algorithm>
#include <exception>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "chatterlab/catalog.hpp"
#include "chatterlab/plugin_api.hpp"
#include "chatterlab/detail/mpi_env.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/input_files.hpp"
#include "chatterlab/runner.hpp"
#include "chatterlab/shards.hpp"
#include "chatterlab/study.hpp"
#include "sdk_commands.hpp"

namespace {

using chatterlab::Json;

constexpr int exit_bad_input = 2;
constexpr int exit_output_failed = 3;

// MPI_Init only under a launcher; MPI_Finalize on every way out of main.
struct MpiSession {
  MpiSession(int& argc, char**& argv) { chatterlab::mpi_init_if_launched(argc, argv); }
  ~MpiSession() { chatterlab::mpi_finalize(); }
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
};

bool is_root() { return chatterlab::mpi_rank() == 0; }

int report_error(const std::string& message) {
  if (is_root()) std::cerr << "chatterlab: error: " << message << '\n';
  return exit_bad_input;
}

// Numbers in shortest form (1450, not 1450.0), anything else as JSON.
std::string show(const Json& value) {
  return value.is_number_float() ? fmt::format("{}", value.get<double>()) : value.dump();
}

// 1.2 GiB, 340 MiB, 12 KiB, 800 bytes.
std::string bytes_text(std::uint64_t bytes) {
  const double b = static_cast<double>(bytes);
  if (b >= 1 << 30) return fmt::format("{:.1f} GiB", b / (1 << 30));
  if (b >= 1 << 20) return fmt::format("{:.0f} MiB", b / (1 << 20));
  if (b >= 1 << 10) return fmt::format("{:.0f} KiB", b / (1 << 10));
  return fmt::format("{} bytes", bytes);
}

// One line per axis for `validate`: "wheel_speed_rpm  21 values from 1000 to 2000".
std::string describe_axis(const chatterlab::GridAxis& axis) {
  const auto& v = axis.values;
  std::string values;
  if (v.size() == 1) {
    values = "1 value: " + show(v.front());
  } else if (v.size() <= 6) {
    values = fmt::format("{} values: ", v.size());
    for (std::size_t i = 0; i < v.size(); ++i) values += (i ? ", " : "") + show(v[i]);
  } else {
    values = fmt::format("{} values from {} to {}", v.size(), show(v.front()), show(v.back()));
  }
  std::string path = axis.path == axis.key ? "" : fmt::format("  ({})", axis.path);
  return fmt::format("{}  {}{}", axis.key, values, path);
}

void print_summary(const chatterlab::Study& study) {
  std::ostringstream out;
  out << study.file.string() << ": valid\n";
  out << fmt::format("  kind        {} (name \"{}\")\n", study.kind,
                     study.document["study"].value("name", ""));
  for (const auto& [key, value] : study.document.items()) {
    if (key == "study" || key == "grid" || key == "plugins" || !value.is_object()) continue;
    std::string type = value.contains("type") ? value["type"].get<std::string>() : "(settings)";
    out << fmt::format("  {:<11} {}\n", key, type);
  }
  for (const auto& library : study.plugin_libraries) out << "  plugin      " << library << '\n';
  std::string shape;
  for (std::size_t a = 0; a < study.grid.size(); ++a) {
    out << (a == 0 ? "  grid        " : "              ") << describe_axis(study.grid[a]) << '\n';
    shape += (a ? " x " : "") + std::to_string(study.grid[a].values.size());
  }
  if (study.grid.empty()) out << "  grid        (none: a single point)\n";
  out << fmt::format("  points      {}{}\n", study.point_count(),
                     study.grid.size() > 1 ? " (" + shape + ", last key varies fastest)" : "");
  const chatterlab::GridCost cost =
      chatterlab::grid_cost(study.point_count(), study.grid.size(), study.output_columns.size());
  out << fmt::format(
      "  estimate    memory {} at rank 0, disk {} for the journal, results.csv and grid plots\n"
      "              (memory: {} fixed, {} held rows x {} bytes, {} points x {} bytes;\n"
      "              disk: {} points x {} bytes; a kind's own working set and files come on top)\n"
      "              limit on this machine: {} points (half of {} of memory){}\n",
      bytes_text(cost.memory_bytes()), bytes_text(cost.disk_bytes()),
      bytes_text(chatterlab::GridCost::fixed_memory_bytes), cost.held_rows,
      chatterlab::GridCost::memory_bytes_per_cell * cost.cells_per_point, cost.points,
      chatterlab::GridCost::bookkeeping_bytes_per_point, cost.points, cost.disk_bytes_per_point,
      cost.default_max_points, bytes_text(2 * cost.memory_budget_bytes),
      cost.points > cost.default_max_points ? "; this grid needs --allow-large" : "");
  if (study.inputs)
    for (const auto& file : study.inputs->files())
      out << fmt::format("  input       {} ({}, {} bytes, sha256 {})\n", file.path.string(),
                         chatterlab::input_role_name(file.role), file.bytes, file.sha256);
  std::cout << out.str();
}

struct Arguments {
  std::string name;
  std::filesystem::path study_file;
  std::filesystem::path out_dir;
  int threads = 0;
  bool resume = false;
  bool retry_failed = false;
  bool isolate = false;
  std::optional<double> point_timeout_s;
  bool allow_large = false;
  bool progress = false;
  bool no_progress = false;
  std::string shard;                          // run --shard I/N
  std::vector<std::filesystem::path> shard_dirs;  // merge OUT SHARD_DIRS...
  std::vector<std::string> plugin_libraries;  // list/describe: out-of-tree libraries to include
};

// What a run (or a merge) says on stdout, from rank 0.
void print_run_summary(const chatterlab::RunSummary& summary, const chatterlab::RunOptions& options) {
  if (is_root()) {
    std::cout << fmt::format("{} points: {} ok, {} failed", summary.points,
                             summary.points - summary.failed, summary.failed);
    if (summary.timed_out > 0) std::cout << fmt::format(" ({} of them timed out)", summary.timed_out);
    if (summary.resumed > 0) std::cout << fmt::format(" ({} taken over from the earlier run)", summary.resumed);
    if (summary.output_error.empty() && options.shard)
      std::cout << fmt::format("; shard {}/{} in {} (combine the shards with chatterlab merge)\n",
                               options.shard->index, options.shard->count, options.out_dir.string());
    else if (summary.output_error.empty())
      std::cout << fmt::format("; results in {}\n", summary.results_file.string());
    else
      std::cout << '\n';
    if (summary.failed > 0)
      std::cout << (options.shard ? "failed points: reasons in meta.json\n"
                                  : "failed points: status column of the results, reasons in meta.json\n");
    if (!summary.output_error.empty())
      std::cerr << fmt::format(
          "chatterlab: error: output could not be written: {} (meta.json: state output_failed); "
          "make room and run again with --resume\n",
          summary.output_error);
    constexpr std::size_t shown = 5;
    for (std::size_t i = 0; i < summary.notices.size() && i < shown; ++i)
      std::cout << fmt::format("notice{}: {}\n",
                               summary.points > 1 ? fmt::format(" (point {})", summary.notices[i].point) : "",
                               summary.notices[i].text);
    if (summary.notices.size() > shown)
      std::cout << fmt::format("... {} more notices in meta.json\n", summary.notices.size() - shown);
  }
}

int run(CLI::App& app, const Arguments& args) {
  // A study names its libraries itself; list and describe read no study, so they take --plugin.
  for (const auto& library : args.plugin_libraries)
    chatterlab::load_plugin_library(std::filesystem::absolute(library).string());
  if (app.got_subcommand("list")) {
    if (is_root()) std::cout << chatterlab::format_plugin_list();
    return 0;
  }
  if (app.got_subcommand("describe")) {
    std::string text = chatterlab::describe_plugin(args.name);
    if (is_root()) std::cout << text;
    return 0;
  }
  if (app.got_subcommand("merge")) {
    chatterlab::RunOptions options;
    options.threads = args.threads;
    if (args.progress || args.no_progress) options.progress = args.progress;
    const chatterlab::RunSummary summary = chatterlab::merge_shards(args.out_dir, args.shard_dirs, options);
    options.out_dir = args.out_dir;
    chatterlab::RunSummary shown = summary;
    shown.resumed = 0;  // every point comes from the shards, which is what merge means
    print_run_summary(shown, options);
    return summary.exit_code();
  }
  chatterlab::Study study = chatterlab::load_study(args.study_file, {.allow_large = args.allow_large});
  chatterlab::cli::record_command_line_plugins(study, args.plugin_libraries);
  if (app.got_subcommand("validate")) {
    if (is_root()) print_summary(study);
    return 0;
  }
  chatterlab::RunOptions options;
  options.out_dir = args.out_dir.empty()
                        ? std::filesystem::path("out") / args.study_file.stem()
                        : args.out_dir;
  options.threads = args.threads;
  options.resume = args.resume;
  options.retry_failed = args.retry_failed;
  options.isolate = args.isolate;
  options.point_timeout_s = args.point_timeout_s;
  if (args.progress || args.no_progress) options.progress = args.progress;
  if (!args.shard.empty()) options.shard = chatterlab::parse_shard(args.shard);
  const chatterlab::RunSummary summary = chatterlab::run_study(study, options);
  print_run_summary(summary, options);
  return summary.exit_code();
}

}  // namespace

int main(int argc, char** argv) {
  // A worker process of the runner (--isolate, time limits): before MPI, which it never joins.
  if (argc > 1 && std::string_view(argv[1]) == "__worker") return chatterlab::run_point_worker(argc, argv);
  MpiSession mpi(argc, argv);

  CLI::App app{"chatterlab: chatter and stability analysis for grinding"};
  app.name("chatterlab");
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("chatterlab ") + CHATTERLAB_VERSION);

  Arguments args;
  auto* list = app.add_subcommand("list", "List every plugin and study kind with a one-line description");
  auto* describe = app.add_subcommand("describe", "Print the parameters of a plugin or study kind");
  describe->add_option("NAME", args.name, "Plugin or study kind name (see `chatterlab list`)")
      ->required();
  for (auto* command : {list, describe})
    command->add_option("--plugin", args.plugin_libraries,
                        "Also load this out-of-tree plugin library (repeatable)");

  auto add_study_arguments = [&](CLI::App* command) {
    command->add_option("STUDY", args.study_file, "Study file (TOML), see docs/studies.md")
        ->required();
    command->add_flag("--allow-large", args.allow_large,
                      "Accept grids larger than this machine's default limit (`chatterlab "
                      "validate` prints it: half the memory over the results' bytes per point)");
  };
  auto* validate = app.add_subcommand("validate", "Check a study file without running it");
  add_study_arguments(validate);
  auto* run_command = app.add_subcommand("run", "Run a study over its grid");
  add_study_arguments(run_command);
  run_command->add_option("--out", args.out_dir, "Output directory (default: out/<study file stem>)");
  run_command->add_option("--threads", args.threads, "OpenMP threads per process (0: all cores)")
      ->check(CLI::Validator(
          [](const std::string& text) {
            return text.find_first_not_of("0123456789") == std::string::npos
                       ? std::string()
                       : "must be 0 (all cores) or a positive whole number, not " + text;
          },
          "N >= 0"));
  auto* resume = run_command->add_flag(
      "--resume", args.resume, "Complete an interrupted run, keeping the points it finished");
  run_command->add_flag("--retry-failed", args.retry_failed,
                        "With --resume: compute the failed and timed-out points again")
      ->needs(resume);
  run_command->add_flag("--isolate", args.isolate,
                        "Run every point in a worker process: a crashing plugin fails only its point");
  run_command->add_option("--point-timeout", args.point_timeout_s,
                          "Time limit of one grid point in seconds (overrides [run] "
                          "point_timeout_s); a point still running then is killed and recorded "
                          "as timeout")
      ->check(CLI::PositiveNumber);
  auto* progress = run_command->add_flag("--progress", args.progress,
                                         "Show a progress bar (default: only on a terminal)");
  run_command->add_flag("--no-progress", args.no_progress, "Never show a progress bar")
      ->excludes(progress);
  run_command->add_option("--shard", args.shard,
                          "Compute only shard I of N of the grid (I/N, 1 <= I <= N; points p "
                          "with p % N = I - 1), e.g. one task of a Slurm array; combine the "
                          "shards with `chatterlab merge`");
  auto* merge = app.add_subcommand(
      "merge", "Combine the output directories of `run --shard I/N` into the single run's result");
  merge->add_option("OUT", args.out_dir, "Output directory of the merged result")->required();
  merge->add_option("SHARD_DIRS", args.shard_dirs, "The output directories of the N shards")
      ->required()
      ->expected(1, -1);
  merge->add_option("--threads", args.threads, "OpenMP threads (plots)");
  merge->add_flag("--no-progress", args.no_progress, "Never show a progress bar");
  for (auto* command : {validate, run_command})
    command->add_option("--plugin", args.plugin_libraries,
                        "Also load this out-of-tree plugin library (repeatable)");
  chatterlab::cli::SdkArguments sdk;
  chatterlab::cli::add_sdk_commands(app, sdk);

  // CLI11 would report an unknown command as "a subcommand is required".
  if (argc > 1 && argv[1][0] != '-') {
    std::vector<std::string> commands;
    for (const auto* command : app.get_subcommands([](const CLI::App*) { return true; }))
      commands.push_back(command->get_name());
    if (std::find(commands.begin(), commands.end(), argv[1]) == commands.end())
      return report_error(fmt::format("unknown command '{}'; commands: {} (see chatterlab --help)",
                                      argv[1], fmt::join(commands, ", ")));
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) {  // --help, --version: CLI11 signals them as exceptions, code 0
      if (is_root()) app.exit(e);
      return 0;
    }
    report_error(fmt::format("{} (see chatterlab --help)", e.what()));
    return exit_bad_input;
  }
  try {
    if (auto code = chatterlab::cli::run_sdk_command(app, sdk)) return *code;
    return run(app, args);
  } catch (const chatterlab::InputError& e) {
    return report_error(e.what());
  } catch (const std::exception& e) {
    // Not bad input but still no result: e.g. out of memory or a failing disk. The runner makes
    // its errors collective; anything else may be on one rank only, whose peers would then wait
    // forever, so print it from whichever rank has it and end all ranks.
    std::cerr << "chatterlab: error: "
              << (is_root() ? "" : fmt::format("(rank {}) ", chatterlab::mpi_rank())) << e.what()
              << '\n';
    const int code =
        dynamic_cast<const chatterlab::OutputError*>(&e) != nullptr ? exit_output_failed : exit_bad_input;
    if (chatterlab::mpi_size() > 1) chatterlab::mpi_abort(code);
    return code;
  } catch (...) {
    std::cerr << "chatterlab: error: " << chatterlab::describe_current_exception() << '\n';
    if (chatterlab::mpi_size() > 1) chatterlab::mpi_abort(exit_bad_input);
    return exit_bad_input;
  }
}
