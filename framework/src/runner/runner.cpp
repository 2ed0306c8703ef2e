// run_study(): the grid loop shared by every study kind.
//
// Work split: MPI rank r of R computes the points with index % R == r (an interleaved split keeps
// ranks balanced when cost varies smoothly across the grid); inside a rank OpenMP threads take
// points dynamically. Each point's result is appended to this rank's journal as soon as it is
// known (resume), then sent to rank 0 at the end; rank 0 alone writes results.csv (in grid order,
// numbers in round-trip form, no timings or ranks), meta.json and the plots. So the bytes of
// results.csv depend only on the study, never on ranks, threads or interruptions.
#include "chatterlab/runner.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <functional>
#include <mutex>
#include <stdexcept>

#include "chatterlab/detail/mpi_env.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/study_kind.hpp"
#include "runner/build_info.hpp"
#include "runner/mpi_exchange.hpp"
#include "runner/output_dir.hpp"
#include "runner/progress.hpp"
#include "runner/results_io.hpp"

namespace chatterlab {

namespace {

namespace fs = std::filesystem;
using runner::JournalContents;
using runner::JournalHeader;
using runner::PointResult;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string utc_now() {
  std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

// This rank's journal for the current session. Lines are buffered and written whole at most
// every 0.1 s: a kill loses at most that much work, and thousands of points per second do not
// become thousands of system calls. A write error (disk full) stops journaling but not the run:
// the results are still complete in memory; meta.json reports the error.
class JournalWriter {
 public:
  JournalWriter(const fs::path& file, const std::string& header) : file_(file) {
    fd_ = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_APPEND | O_CLOEXEC, 0644);
    if (fd_ < 0 || !write_all(header))
      throw std::runtime_error(
          fmt::format("cannot write {}: {}", file.string(), std::strerror(errno)));
    last_flush_ = Clock::now();
  }
  JournalWriter(const JournalWriter&) = delete;
  JournalWriter& operator=(const JournalWriter&) = delete;
  ~JournalWriter() {
    flush();
    if (fd_ >= 0) ::close(fd_);
  }

  void append(const std::string& line) {
    std::lock_guard lock(mutex_);
    buffer_ += line;
    if (Clock::now() - last_flush_ > flush_interval) flush_locked();
  }
  void flush() {
    std::lock_guard lock(mutex_);
    flush_locked();
  }
  std::string error() const { return error_; }

 private:
  static constexpr auto flush_interval = std::chrono::milliseconds(100);

  void flush_locked() {
    last_flush_ = Clock::now();
    if (buffer_.empty() || !error_.empty()) return;
    if (!write_all(buffer_))
      error_ = fmt::format("journal {} not written: {}", file_.string(), std::strerror(errno));
    buffer_.clear();
  }
  bool write_all(std::string_view text) {
    while (!text.empty()) {
      ssize_t n = ::write(fd_, text.data(), text.size());
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) return false;
      text.remove_prefix(static_cast<std::size_t>(n));
    }
    return true;
  }

  fs::path file_;
  int fd_ = -1;
  std::string buffer_;
  std::string error_;
  Clock::time_point last_flush_;
  std::mutex mutex_;
};

// One grid point. Nothing escapes: this runs inside the OpenMP region.
PointResult compute_point(const StudyKind& kind, const Study& study, std::size_t point,
                          const std::vector<std::string>& columns, const RunOptions& options) {
  PointResult result;
  result.done = true;
  try {
    PointContext context;
    context.index = point;
    context.point_count = study.point_count();
    context.artifact_dir = runner::point_artifact_dir(options.out_dir, point, context.point_count);
    context.plots = options.plots;
    std::vector<Json> outputs = kind.run_point(study.point_document(point), context);
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
  } catch (const std::exception& e) {
    result.outputs.assign(columns.size(), Json());
    result.status = runner::failure_status(e.what());
  } catch (...) {
    result.outputs.assign(columns.size(), Json());
    result.status = runner::failure_status("unknown exception");
  }
  return result;
}

// What rank 0 learns before the computation and every rank needs.
struct Preparation {
  int session = 1;
  std::string done;  // one '0'/'1' per point: finished in an earlier session
  std::vector<std::pair<std::size_t, PointResult>> resumed;  // rank 0 only
  std::size_t journal_lines_truncated = 0;
  std::size_t journal_lines_invalid = 0;
};

Preparation prepare_on_root(const RunOptions& options, const JournalHeader& expected,
                            const std::function<Json()>& running_meta) {
  runner::prepare_output_dir(options.out_dir, options.resume);
  Preparation prep;
  prep.done.assign(expected.points, '0');
  if (options.resume) {
    for (const auto& file : runner::journal_files(options.out_dir)) {
      JournalContents journal = runner::parse_journal(runner::read_file(file));
      prep.journal_lines_truncated += journal.truncated_lines;
      prep.journal_lines_invalid += journal.invalid_lines;
      if (!journal.header_found) continue;  // killed before its first line was complete
      if (journal.header.study_fingerprint != expected.study_fingerprint ||
          journal.header.points != expected.points || journal.header.columns != expected.columns)
        throw InputError(fmt::format(
            "cannot resume from {}: it was written for a different study (the resolved study, "
            "its grid or the output columns changed); run without --resume to start over",
            file.string()));
      for (auto& record : journal.records) {
        if (prep.done[record.first] == '1') continue;  // the first record of a point wins
        prep.done[record.first] = '1';
        prep.resumed.push_back(std::move(record));
      }
    }
  }
  // Only now, when the journals were accepted: a refused --resume leaves the old run untouched.
  // A run that is killed leaves meta.json saying so, next to its journal.
  runner::write_file_atomically(options.out_dir / "meta.json",
                                runner::json_text(running_meta(), 2) + "\n");
  prep.session = runner::next_journal_session(options.out_dir);
  std::error_code ec;
  fs::create_directories(runner::journal_dir(options.out_dir), ec);
  if (ec)
    throw InputError(fmt::format("output directory {}: cannot create journal/: {}",
                                 options.out_dir.string(), ec.message()));
  return prep;
}

// Rank 0 prepares; every rank gets the session and the finished points, or the same InputError.
// Everything rank 0 does here is inside the try: an exception on one rank alone would leave the
// others waiting in the broadcast.
Preparation prepare(const RunOptions& options, const JournalHeader& expected,
                    const std::function<Json()>& running_meta) {
  Preparation prep;
  std::string message;
  if (mpi_rank() == 0) {
    Json outcome;
    try {
      prep = prepare_on_root(options, expected, running_meta);
      outcome = {{"session", prep.session}, {"done", prep.done}};
    } catch (const std::exception& e) {
      outcome = {{"error", e.what()}};
    }
    message = runner::json_text(outcome);
  }
  runner::broadcast_from_root(message);
  Json outcome = Json::parse(message);
  if (outcome.contains("error")) throw InputError(outcome["error"].get<std::string>());
  if (mpi_rank() != 0) {
    prep.session = outcome["session"].get<int>();
    prep.done = outcome["done"].get<std::string>();
  }
  return prep;
}

std::unique_ptr<JournalWriter> open_journal(const RunOptions& options, const Preparation& prep,
                                            const JournalHeader& header) {
  std::unique_ptr<JournalWriter> journal;
  std::string error;
  try {
    journal = std::make_unique<JournalWriter>(
        runner::journal_file(options.out_dir, prep.session, mpi_rank()),
        runner::journal_header_line(header));
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (!runner::all_ranks_agree(error.empty()))
    throw InputError(fmt::format(
        "output directory {}: a rank cannot write its journal{} (under MPI the output directory "
        "must be on a file system every rank sees)",
        options.out_dir.string(), error.empty() ? "" : ": " + error));
  return journal;
}

// Counters of one rank's computation, summed on rank 0.
struct ComputeStats {
  std::size_t computed = 0;
  double compute_s = 0.0;  // summed over points (thread time spent in run_point)
  std::vector<std::string> journal_errors;
};

struct MetaInputs {
  const Study& study;
  const RunOptions& options;
  const std::vector<std::string>& columns;
  std::string started_utc;
  int threads = 1;
  bool serial = false;
};

Json run_description(const MetaInputs& in) {
  Json run = Json::object();
  run["started_utc"] = in.started_utc;
  run["out_dir"] = fs::absolute(in.options.out_dir).string();
  run["resume"] = in.options.resume;
  run["ranks"] = mpi_size();
  run["threads_per_rank"] = in.threads;
  if (in.serial) run["serial_reason"] = "a plugin of this study is serial-only";
  return run;
}

Json meta_header(const MetaInputs& in) {
  Json meta = Json::object();
  meta["study_file"] = fs::absolute(in.study.file).string();
  meta["kind"] = in.study.kind;
  meta["study"] = in.study.document;
  Json grid = Json::array();
  for (const auto& axis : in.study.grid)
    grid.push_back({{"key", axis.key}, {"path", axis.path}, {"values", axis.values.size()}});
  meta["grid"] = std::move(grid);
  meta["output_columns"] = in.columns;
  meta["points"] = in.study.point_count();
  meta["build"] = runner::build_info();
  return meta;
}

Json failed_points(const Study& study, const ResultTable& table) {
  Json failed = Json::array();
  for (std::size_t p = 0; p < table.status.size(); ++p) {
    if (table.status[p] == "ok") continue;
    Json grid = Json::object();
    for (std::size_t a = 0; a < study.grid.size(); ++a) grid[study.grid[a].key] = table.rows[p][a];
    std::string reason = table.status[p].substr(std::string_view("failed: ").size());
    failed.push_back({{"point", p}, {"grid", std::move(grid)}, {"reason", std::move(reason)}});
  }
  return failed;
}

// The kind's `notice` column (study_kind.hpp): what the user must read even when every point
// completed, e.g. "no stable candidate".
Json point_notices(const ResultTable& table) {
  Json notices = Json::array();
  const auto column = std::find(table.output_columns.begin(), table.output_columns.end(), "notice");
  if (column == table.output_columns.end()) return notices;
  const std::size_t c = table.grid_columns.size() + static_cast<std::size_t>(column - table.output_columns.begin());
  for (std::size_t p = 0; p < table.rows.size(); ++p)
    if (c < table.rows[p].size() && table.rows[p][c].is_string() && !table.rows[p][c].get<std::string>().empty())
      notices.push_back({{"point", p}, {"notice", table.rows[p][c]}});
  return notices;
}

// Rank 0 after all points: results.csv, plots, meta.json. Returns the failed-point count and
// the points' notices.
Json write_outputs(const StudyKind& kind, const MetaInputs& in, const Preparation& prep,
                          const std::vector<PointResult>& results, const ComputeStats& stats,
                          Clock::time_point start) {
  const fs::path& out = in.options.out_dir;
  ResultTable table = runner::assemble_results(in.study, in.columns, results);
  runner::write_file_atomically(out / "results.csv", runner::format_csv(table, in.threads));

  Json plot_errors = Json::array();
  if (in.options.plots) {
    // A plot that cannot be drawn (gnuplot missing) must not cost the user the computed grid.
    try {
      kind.write_artifacts(in.study, table, out);
    } catch (const std::exception& e) {
      plot_errors.push_back(e.what());
    }
  }

  Json failed = failed_points(in.study, table);
  const std::size_t failed_count = failed.size();
  Json meta = meta_header(in);
  meta["state"] = "complete";
  meta["points_failed"] = failed_count;
  meta["failed_points"] = std::move(failed);
  Json notices = point_notices(table);
  meta["notices"] = notices;
  Json run = run_description(in);
  run["journal_session"] = prep.session;
  run["points_resumed"] = prep.resumed.size();
  run["points_computed"] = stats.computed;
  run["journal_lines_ignored"] = {{"truncated", prep.journal_lines_truncated},
                                  {"invalid", prep.journal_lines_invalid}};
  if (!stats.journal_errors.empty()) run["journal_errors"] = stats.journal_errors;
  meta["run"] = std::move(run);
  const double wall = seconds_since(start);
  Json timings = Json::object();
  timings["wall_s"] = wall;
  timings["compute_s"] = stats.compute_s;
  if (stats.computed > 0) {
    timings["point_mean_s"] = stats.compute_s / static_cast<double>(stats.computed);
    timings["points_per_s"] = static_cast<double>(stats.computed) / wall;
  }
  meta["timings"] = std::move(timings);
  meta["plot_errors"] = std::move(plot_errors);
  runner::write_file_atomically(out / "meta.json", runner::json_text(meta, 2) + "\n");
  return {{"failed", failed_count}, {"notices", std::move(notices)}};
}

}  // namespace

RunSummary run_study(const Study& study, const RunOptions& options) {
  const Clock::time_point start = Clock::now();
  const std::string started_utc = utc_now();
  const int rank = mpi_rank(), ranks = mpi_size();

  auto kind = study_kind_registry().at(study.kind).create(ParamValues{});
  const std::vector<std::string> columns = kind->output_columns(study.document);
  const std::size_t n = study.point_count();
  const JournalHeader header{runner::study_fingerprint(study, columns), n, columns};

  const bool serial = kind->requires_serial(study.document);
  const int threads = serial ? 1 : options.threads > 0 ? options.threads : omp_get_max_threads();
  const MetaInputs meta_in{study, options, columns, started_utc, threads, serial};
  Preparation prep = prepare(options, header, [&meta_in] {
    Json meta = meta_header(meta_in);
    meta["state"] = "running (or interrupted: complete it with --resume)";
    meta["run"] = run_description(meta_in);
    return meta;
  });
  std::unique_ptr<JournalWriter> journal = open_journal(options, prep, header);

  std::vector<std::size_t> todo;
  for (std::size_t p = static_cast<std::size_t>(rank); p < n; p += static_cast<std::size_t>(ranks))
    if (prep.done[p] == '0') todo.push_back(p);

  runner::ProgressBar progress(rank == 0 && options.progress.value_or(runner::stderr_is_terminal()),
                               todo.size());
  std::vector<PointResult> mine(todo.size());
  double compute_s = 0.0;
  const auto count = static_cast<std::ptrdiff_t>(todo.size());
#pragma omp parallel for schedule(dynamic) num_threads(threads) reduction(+ : compute_s)
  for (std::ptrdiff_t k = 0; k < count; ++k) {
    const Clock::time_point point_start = Clock::now();
    const std::size_t p = todo[static_cast<std::size_t>(k)];
    PointResult result = compute_point(*kind, study, p, columns, options);
    compute_s += seconds_since(point_start);
    journal->append(runner::journal_line(p, result));
    mine[static_cast<std::size_t>(k)] = std::move(result);
    progress.point_done();
  }
  journal->flush();
  progress.finish();

  // Every rank's new points to rank 0, in the journal's round-trip format.
  Json payload = {
      {"computed", todo.size()}, {"compute_s", compute_s}, {"journal_error", journal->error()}};
  if (rank != 0) {
    std::string records;
    for (std::size_t k = 0; k < todo.size(); ++k) records += runner::journal_line(todo[k], mine[k]);
    payload["records"] = std::move(records);
  }
  std::vector<std::string> payloads = runner::gather_to_root(runner::json_text(payload));

  std::string outcome;
  if (rank == 0) {
    Json result = Json::object();
    try {
      std::vector<PointResult> results(n);
      for (auto& [p, r] : prep.resumed) results[p] = std::move(r);
      for (std::size_t k = 0; k < todo.size(); ++k) results[todo[k]] = std::move(mine[k]);
      ComputeStats stats;
      for (std::size_t r = 0; r < payloads.size(); ++r) {
        Json from = Json::parse(payloads[r]);
        stats.computed += from["computed"].get<std::size_t>();
        stats.compute_s += from["compute_s"].get<double>();
        if (auto error = from["journal_error"].get<std::string>(); !error.empty())
          stats.journal_errors.push_back(error);
        if (r == 0) continue;
        JournalContents records =
            runner::parse_journal_records(from["records"].get<std::string>(), n, columns.size());
        if (records.invalid_lines + records.truncated_lines > 0)
          throw std::logic_error(fmt::format("runner: garbled results from rank {}", r));
        for (auto& [p, record] : records.records) results[p] = std::move(record);
      }
      const Json outputs = write_outputs(*kind, meta_in, prep, results, stats, start);
      result["failed"] = outputs["failed"];
      result["notices"] = outputs["notices"];
    } catch (const std::exception& e) {
      if (ranks == 1) throw;
      result["error"] = e.what();
    }
    outcome = runner::json_text(result);
  }
  // Every rank returns the same summary (and exit code), or fails the same way.
  runner::broadcast_from_root(outcome);
  Json result = Json::parse(outcome);
  if (result.contains("error")) throw std::runtime_error(result["error"].get<std::string>());

  RunSummary summary;
  summary.points = n;
  summary.failed = result["failed"].get<std::size_t>();
  for (const Json& n : result["notices"])
    summary.notices.push_back({n["point"].get<std::size_t>(), n["notice"].get<std::string>()});
  summary.resumed = static_cast<std::size_t>(std::count(prep.done.begin(), prep.done.end(), '1'));
  return summary;
}

}  // namespace chatterlab
