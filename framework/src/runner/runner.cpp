// run_study(): the grid loop shared by every study kind.
//
// Work split: MPI ranks claim blocks of the points to compute from a shared counter on rank 0
// (runner/mpi_scheduler.hpp: guided blocks, so a grid whose cost varies keeps every rank busy);
// inside a rank OpenMP threads take points dynamically, or, with --isolate or a time limit per
// point, worker processes do (runner/worker_pool.hpp). Each point's result is queued for this
// rank's journal as soon as it is known (a writer thread puts it on disk within 0.1 s). Rank 0
// alone writes results.csv (in grid order, numbers in round-trip form, no timings or ranks),
// meta.json and the plots: its own points stream into results.csv as they finish, the other
// ranks send each finished block (runner::RecordStream), and the points of an earlier session
// are read back from disk when their row is due (runner/resume.hpp). The writer
// (runner/result_writer.hpp) holds only the rows that finish ahead of an earlier one, not the
// grid. So the bytes of results.csv depend only on the study, never on ranks, threads, worker
// processes or interruptions.
//
// Order of a run, so that exit code 2 means "nothing was written": everything that can reject the
// run (the study's output columns, the ranks' input files, starting the worker processes, the
// output directory's lock, the journals of a --resume) is checked before the first file changes.
#include "chatterlab/runner.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <functional>
#include <span>
#include <iostream>
#include <stdexcept>

#include "chatterlab/detail/mpi_env.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/input_files.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/plugin_api.hpp"
#include "chatterlab/study_kind.hpp"
#include "runner/input_watch.hpp"
#include "runner/journal_writer.hpp"
#include "runner/mpi_scheduler.hpp"
#include "runner/mpi_exchange.hpp"
#include "runner/output_dir.hpp"
#include "runner/point_compute.hpp"
#include "runner/progress.hpp"
#include "runner/results_io.hpp"
#include "runner/result_writer.hpp"
#include "runner/resume.hpp"
#include "runner/run_meta.hpp"
#include "runner/shards.hpp"
#include "runner/worker_pool.hpp"

namespace chatterlab {

namespace {

namespace fs = std::filesystem;
using runner::ComputedPoint;
using runner::JournalContents;
using runner::JournalHeader;
using runner::JournalWriter;
using runner::MetaInputs;
using runner::PointResult;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Runs `step` on every rank; rank-local exceptions become the same InputError on every rank (an
// exception on one rank alone would leave the others waiting in the next collective call).
template <class Step>
void collectively(Step&& step) {
  std::string error;
  try {
    step();
  } catch (...) {
    error = describe_current_exception();
    if (error.empty()) error = "unknown error";
  }
  std::vector<std::string> errors = runner::gather_to_root(error);
  std::string first;
  for (std::size_t r = 0; r < errors.size() && first.empty(); ++r)
    if (!errors[r].empty())
      first = r == 0 ? errors[r] : fmt::format("(rank {}) {}", r, errors[r]);
  runner::broadcast_from_root(first);
  if (!first.empty()) throw InputError(first);
}

// Every rank must have read the same bytes (a cluster node with another copy of a data file
// would silently compute something else).
void check_ranks_read_the_same_inputs(const Study& study) {
  const std::string mine = runner::json_text(runner::result_inputs(study));
  std::vector<std::string> all = runner::gather_to_root(mine);
  std::string message;
  for (std::size_t r = 1; r < all.size() && message.empty(); ++r)
    if (all[r] != all[0])
      message = fmt::format(
          "MPI rank {} read other input files than rank 0 ({} on rank {}, {} on rank 0): every "
          "rank must see the same files",
          r, all[r], r, all[0]);
  runner::broadcast_from_root(message);
  if (!message.empty()) throw InputError(message);
}

// A warning (not a refusal: the estimate is for the heaviest kind per cell, and a resume needs
// less) when the output file system has less room than the grid's results are estimated to take.
void warn_if_the_disk_is_too_small(const fs::path& out_dir, const GridCost& cost) {
  fs::path existing = fs::absolute(out_dir);
  while (!existing.empty() && !fs::exists(existing) && existing != existing.parent_path())
    existing = existing.parent_path();
  std::error_code ec;
  const fs::space_info space = fs::space(existing, ec);
  if (ec || space.available >= cost.disk_bytes()) return;
  std::cerr << fmt::format(
      "chatterlab: warning: {} has {:.1f} MiB free, and this grid's results are estimated to take "
      "{:.1f} MiB ({} points x {} bytes): the run may end with exit code 3 (output could not be "
      "written)\n",
      existing.string(), static_cast<double>(space.available) / (1 << 20),
      static_cast<double>(cost.disk_bytes()) / (1 << 20), cost.points, cost.disk_bytes_per_point);
}

// What rank 0 learns before the computation and every rank needs.
struct Preparation {
  int session = 1;
  std::string done;  // one '0'/'1' per point: finished in an earlier session
  runner::ResumedPoints resumed;                // rank 0 only: read back as results are written
  std::unique_ptr<runner::OutputLock> lock;     // rank 0 only: held until the run's last write
};

Preparation prepare_on_root(const RunOptions& options, const JournalHeader& expected,
                            const Study& study, const Json& running_meta) {
  Preparation prep;
  warn_if_the_disk_is_too_small(
      options.out_dir, grid_cost(expected.points, study.grid.size(), expected.columns.size()));
  prep.lock = runner::prepare_output_dir(options.out_dir, options.resume, study.file.string());
  prep.done.assign(expected.points, '0');
  if (options.resume) {
    // A complete HDF5 run keeps no journal (results.h5 holds every point): resume from that.
    prep.resumed =
        runner::read_resumable_points(options.out_dir, expected, study, options.retry_failed);
    for (std::size_t p = 0; p < expected.points; ++p)
      if (prep.resumed.has(p)) prep.done[p] = '1';
  }
  // Only now, when the journals were accepted: a refused --resume leaves the old run untouched.
  // A run that is killed leaves meta.json saying so, next to its journal.
  const std::string meta_text = runner::json_text(running_meta, 2) + "\n";
  runner::write_file_atomically(options.out_dir / "meta.json", meta_text);
  // Room for the final meta.json, given back if the disk fills up (then meta.json can still say
  // what could not be written): twice this meta.json plus 64 KiB.
  runner::write_file_atomically(options.out_dir / runner::output_reserve_name,
                                std::string(2 * meta_text.size() + 65536, '\0'));
  prep.session = runner::next_journal_session(options.out_dir);
  std::error_code ec;
  fs::create_directories(runner::journal_dir(options.out_dir), ec);
  if (ec)
    throw InputError(fmt::format("output directory {}: cannot create journal/: {}",
                                 options.out_dir.string(), ec.message()));
  return prep;
}

// Rank 0 prepares; every rank gets the session and the finished points, or the same InputError.
Preparation prepare(const RunOptions& options, const JournalHeader& expected, const Study& study,
                    const Json& running_meta) {
  Preparation prep;
  std::string message;
  if (mpi_rank() == 0) {
    Json outcome;
    try {
      prep = prepare_on_root(options, expected, study, running_meta);
      outcome = {{"session", prep.session}, {"done", prep.done}};
    } catch (...) {
      outcome = {{"error", describe_current_exception()}};
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

// Removes what prepare() wrote when the run cannot start after all (a rank cannot journal):
// exit 2 then leaves no meta.json claiming a run.
void undo_prepare(const RunOptions& options) {
  if (mpi_rank() != 0) return;
  std::error_code ignored;
  fs::remove(options.out_dir / "meta.json", ignored);
  fs::remove(options.out_dir / runner::output_reserve_name, ignored);
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
  if (!runner::all_ranks_agree(error.empty())) {
    undo_prepare(options);
    throw InputError(fmt::format(
        "output directory {}: a rank cannot write its journal{} (under MPI the output directory "
        "must be on a file system every rank sees)",
        options.out_dir.string(), error.empty() ? "" : ": " + error));
  }
  return journal;
}

// Counters of one rank's computation, summed on rank 0.
struct ComputeStats {
  std::size_t computed = 0;
  double compute_s = 0.0;  // summed over points (thread time spent in run_point)
  std::size_t output_failures = 0;  // points that could not write their files
  std::vector<std::string> journal_errors;
  std::vector<std::string> input_changes;
  // Per rank: points computed, compute_s, and loop_s (wall time from its first block request to
  // its last point): what the load balance is judged by.
  Json per_rank = Json::array();
};

// Of the thread time the ranks spent in their point loops (ranks x threads x the longest loop),
// the share spent computing points: 1 when every thread was busy until the last point ended.
double load_balance(const Json& per_rank, int threads) {
  double busy = 0.0, longest = 0.0;
  for (const Json& rank : per_rank) {
    busy += rank["compute_s"].get<double>();
    longest = std::max(longest, rank["loop_s"].get<double>());
  }
  const double available = static_cast<double>(per_rank.size()) * threads * longest;
  return available > 0.0 ? busy / available : 0.0;
}

struct OutputsWritten {
  std::size_t failed = 0, timed_out = 0;
  std::string output_error;
  Json notices = Json::array();  // [{point, notice}]
};

// Rank 0 after all points: results.csv, plots, meta.json. An output that cannot be written (disk
// full, I/O error) is reported, not thrown: meta.json then says so (state output_failed), using
// the space reserved for it, and the run exits 3.
OutputsWritten write_outputs(const StudyKind& kind, const MetaInputs& in, const Preparation& prep,
                             runner::GridOrderWriter& results, const ComputeStats& stats,
                             Clock::time_point start) {
  const fs::path& out = in.options.out_dir;
  OutputsWritten written;
  try {
    results.commit();
  } catch (const OutputError& e) {
    written.output_error = e.what();
  }

  Json plot_errors = Json::array();
  if (in.options.plots && written.output_error.empty()) {
    // A plot that cannot be drawn (gnuplot missing) must not cost the user the computed grid;
    // a plot that cannot be written (the disk) is an output failure.
    const std::size_t failed_writes = failed_output_writes_on_this_thread();
    try {
      const ResultTable table = results.take_plot_table();
      kind.write_artifacts(results.plot_study(), table, out);
    } catch (const std::exception& e) {
      if (failed_output_writes_on_this_thread() != failed_writes)
        written.output_error = std::string("plots: ") + e.what();
      else
        plot_errors.push_back(e.what());
    }
  }
  if (stats.output_failures > 0)  // first: the points' own files come before the plots
    written.output_error = fmt::format(
        "{} point(s) could not write their files (recorded as failed: run again with --resume "
        "--retry-failed once the disk has room){}{}",
        stats.output_failures, written.output_error.empty() ? "" : "; ", written.output_error);

  Json failed = results.failed_points();
  written.failed = failed.size();
  for (const auto& f : failed) written.timed_out += f["status"] == "timeout" ? 1 : 0;
  Json meta = runner::meta_header(in);
  meta["state"] = written.output_error.empty() ? runner::state_complete : runner::state_output_failed;
  if (!written.output_error.empty()) meta["output_error"] = written.output_error;
  meta["points_failed"] = written.failed;
  meta["points_timed_out"] = written.timed_out;
  written.notices = results.notices();
  meta["notices"] = written.notices;
  meta["failed_points"] = std::move(failed);
  Json run = runner::run_description(in);
  run["journal_session"] = prep.session;
  run["points_resumed"] = static_cast<std::size_t>(std::count(prep.done.begin(), prep.done.end(), '1'));
  run["points_computed"] = stats.computed;
  run["journal_lines_ignored"] = {{"truncated", prep.resumed.truncated_lines},
                                  {"invalid", prep.resumed.invalid_lines}};
  if (!stats.journal_errors.empty()) run["journal_errors"] = stats.journal_errors;
  // The journal only serves --resume of an unfinished run; once results.h5 holds every point it
  // is removed (by default), after meta.json says so: about the size of the results again.
  const runner::ResultsFormat format = runner::results_format(in.study);
  const bool remove_journal = format == runner::ResultsFormat::hdf5 &&
                              written.output_error.empty() && !runner::keep_journal(in.study);
  run["journal"] = remove_journal ? "removed: the run is complete and results.h5 holds every "
                                    "point (--resume reads it)"
                                  : "kept";
  meta["run"] = std::move(run);
  meta["results_file"] = runner::results_path(fs::path(), format).string();
  const double wall = seconds_since(start);
  Json timings = Json::object();
  timings["wall_s"] = wall;
  timings["compute_s"] = stats.compute_s;
  if (stats.computed > 0) {
    timings["point_mean_s"] = stats.compute_s / static_cast<double>(stats.computed);
    timings["points_per_s"] = static_cast<double>(stats.computed) / wall;
    timings["load_balance"] = load_balance(stats.per_rank, in.threads);
  }
  timings["ranks"] = stats.per_rank;
  meta["timings"] = std::move(timings);
  meta["plot_errors"] = std::move(plot_errors);
  // The reserve goes first: its space is what lets meta.json be written on a full disk.
  std::error_code ignored;
  fs::remove(out / runner::output_reserve_name, ignored);
  try {
    runner::write_file_atomically(out / "meta.json", runner::json_text(meta, 2) + "\n");
  } catch (const std::exception& e) {
    if (written.output_error.empty()) written.output_error = e.what();
  }
  if (remove_journal && written.output_error.empty())
    fs::remove_all(runner::journal_dir(out), ignored);  // one left behind costs disk, not results
  return written;
}

// An input file changed while the run went: its results describe data that is no longer there.
// meta.json says so (results.csv is not written), and the run ends with exit 2.
std::string input_changed(const MetaInputs& in, const std::vector<std::string>& changes) {
  std::string message = fmt::format(
      "an input file changed while the study ran, so the run was stopped and {} was not "
      "written: {}. Run the study again (without --resume: the finished points belong to the old "
      "file)",
      runner::results_path(fs::path(), runner::results_format(in.study)).string(),
      fmt::join(changes, "; "));
  Json meta = runner::meta_with_state(in, runner::state_input_changed);
  meta["input_changes"] = changes;
  std::error_code ignored;
  fs::remove(in.options.out_dir / runner::output_reserve_name, ignored);
  try {
    runner::write_file_atomically(in.options.out_dir / "meta.json",
                                  runner::json_text(meta, 2) + "\n");
  } catch (const std::exception&) {  // the message on stderr still says it
  }
  return message;
}

}  // namespace

RunSummary run_study(const Study& study, const RunOptions& options) {
  const Clock::time_point start = Clock::now();
  const std::string started_utc = runner::utc_now();
  const int rank = mpi_rank(), ranks = mpi_size();
  // Every data file a point reads comes from the snapshot load_study took.
  InputScope reads_through(study.inputs);

  auto kind = study_kind_registry().at(study.kind).create(ParamValues{});
  std::vector<std::string> columns;
  collectively([&] {
    try {
      columns = kind->output_columns(study.document);
    } catch (...) {
      throw InputError(fmt::format("{}: the study kind cannot list its outputs: {}",
                                   study.file.string(),
                                   runner::with_plugin_context(describe_current_exception(),
                                                               study.document,
                                                               study.file.string())));
    }
  });
  check_ranks_read_the_same_inputs(study);
  const std::size_t n = study.point_count();
  if (options.shard) runner::check_shard(*options.shard, n, study.file.string());
  const std::string fingerprint = runner::study_fingerprint(study, columns);
  const JournalHeader header{fingerprint, n, columns, runner::result_inputs(study)};

  const Json run_table = study.document.value("run", Json::object());
  std::optional<double> timeout_s = options.point_timeout_s;
  if (!timeout_s && run_table.contains("point_timeout_s") && run_table["point_timeout_s"].is_number())
    timeout_s = run_table["point_timeout_s"].get<double>();
  std::string isolation;
  if (timeout_s)
    isolation = "a time limit per point (point_timeout_s)";
  else if (options.isolate)
    isolation = "--isolate";
  else if (run_table.value("isolate", false))
    isolation = "[run] isolate = true";

  const bool serial = kind->requires_serial(study.document);
  const int threads = serial ? 1 : options.threads > 0 ? options.threads : omp_get_max_threads();
  const MetaInputs meta_in{study, options, columns, fingerprint, started_utc,
                           threads, serial,  isolation, timeout_s};

  // Worker processes start before the output directory is touched: one that cannot start is
  // bad input with nothing written.
  std::unique_ptr<runner::WorkerPool> pool;
  if (!isolation.empty())
    collectively([&] {
      pool = std::make_unique<runner::WorkerPool>(study, columns, options, threads, timeout_s);
    });

  Preparation prep =
      prepare(options, header, study, runner::meta_with_state(meta_in, runner::state_running));
  std::unique_ptr<JournalWriter> journal = open_journal(options, prep, header);

  // Every rank lists the same points; the scheduler hands out blocks of the list (rank 0
  // coordinates under MPI).
  const std::vector<std::size_t> todo = runner::points_to_compute(prep.done, options.shard);
  runner::ProgressBar progress(rank == 0 && options.progress.value_or(runner::stderr_is_terminal()),
                               todo.size());
  runner::PointScheduler scheduler(todo.size(), threads,
                                   [&](std::size_t elsewhere) { progress.points_done(elsewhere); });
  // Rank 0 streams every point (its own, the other ranks', the resumed ones) into results.csv
  // (docs/architecture.md, "Streaming results"). A shard writes no results.csv (`chatterlab
  // merge` does, from the shards' journals), so its rank 0 keeps its points, for meta.json's
  // failed points.
  std::unique_ptr<runner::GridOrderWriter> writer;
  try {
    collectively([&] {
      if (rank == 0 && !options.shard) {
        const runner::ResultsFormat format = runner::results_format(study);
        writer = std::make_unique<runner::GridOrderWriter>(
            study, columns, runner::results_path(options.out_dir, format), format,
            runner::meta_header(meta_in));
      }
    });
  } catch (const InputError&) {
    undo_prepare(options);
    throw;
  }
  if (writer) writer->take_resumed_points(&prep.resumed);
  // Another rank sends each finished block to rank 0 (runner::RecordStream), whose main thread
  // hands the blocks to the writer between its own points; a shard's rank 0 keeps them.
  runner::RecordStream stream;
  std::vector<std::pair<std::size_t, PointResult>> shard_kept;  // rank 0 of a shard
  std::string stream_error;  // rank 0: a garbled block (reported after the loop, not thrown in it)
  auto take_block = [&](int from, std::string&& text) {
    JournalContents records = runner::parse_journal_records(text, n, columns.size());
    if (records.invalid_lines + records.truncated_lines > 0) {
      if (stream_error.empty()) stream_error = fmt::format("runner: garbled results from rank {}", from);
      return;
    }
    for (auto& [p, record] : records.records) {
      if (writer)
        writer->add(p, std::move(record));
      else
        shard_kept.emplace_back(p, std::move(record));
    }
  };
  auto serve = [&] {
    scheduler.serve();  // rank 0's main thread lets MPI progress the other ranks' claims
    stream.poll(take_block);
  };
  // The points of this rank's current block: a view of `todo` (one process: the whole list,
  // which is not copied).
  std::span<const std::size_t> block_points;
  std::vector<PointResult> block_results;  // their results when this rank has no writer
  std::atomic<std::size_t> computed_points{0};
  double compute_s = 0.0;
  std::atomic<std::size_t> points_done{0};
  if (options.on_point_done) options.on_point_done(0, todo.size());
  std::atomic<std::size_t> output_failures{0};
  runner::InputWatch watch(study.inputs);
  auto keep = [&](std::size_t k, ComputedPoint&& computed) {
    journal->append(runner::journal_line(block_points[k], computed.result));
    if (computed.output_failed) ++output_failures;
    ++computed_points;
    if (writer)
      writer->add(block_points[k], std::move(computed.result));
    else
      block_results[k] = std::move(computed.result);
    progress.point_done();
    if (options.on_point_done) options.on_point_done(++points_done, todo.size());
  };
  // A plugin that crashes or calls exit() here takes the process with it: the guard says which
  // point did it, and records an exit() in meta.json.
  std::optional<runner::InProcessGuard> guard;
  if (!pool)
    guard.emplace(
        threads,
        [&](const std::string& message) {
          journal->flush();
          if (rank != 0) return;
          std::error_code ignored;  // no half results file left behind
          if (writer) fs::remove(writer->temporary_path(), ignored);
          Json meta = runner::meta_with_state(meta_in, runner::state_ended_by_plugin);
          meta["error"] = message;
          runner::write_file_atomically(options.out_dir / "meta.json",
                                        runner::json_text(meta, 2) + "\n");
        },
        [](void* journal_writer) { static_cast<JournalWriter*>(journal_writer)->flush_before_dying(); },
        journal.get());
  const Clock::time_point loop_start = Clock::now();
  // This rank's block when it is done: to rank 0 (another rank), or kept (a shard's rank 0).
  auto block_done = [&] {
    if (writer) return;
    std::string records;
    for (std::size_t k = 0; k < block_points.size(); ++k) {
      if (!block_results[k].done) continue;
      if (rank != 0)
        records += runner::journal_line(block_points[k], block_results[k]);
      else
        shard_kept.emplace_back(block_points[k], std::move(block_results[k]));
    }
    stream.send(std::move(records));
  };
  while (auto block = scheduler.next(points_done.load())) {
    block_points = std::span<const std::size_t>(todo).subspan(block->begin, block->size());
    if (!writer) block_results.assign(block_points.size(), PointResult{});
    if (pool) {
      pool->run(std::vector<std::size_t>(block_points.begin(), block_points.end()), [&](std::size_t k, ComputedPoint&& computed) {
        compute_s += computed.compute_s;
        keep(k, std::move(computed));
        serve();
      }, watch.changed());
      block_done();
      continue;
    }
    const auto count = static_cast<std::ptrdiff_t>(block->size());
    // No more threads than points: a team of one is an inactive region, so a lone point's own
    // OpenMP loops (feed_risk's root searches, lobe tracing) get the threads instead of running
    // nested and serial (libgomp's max-active-levels is 1).
    const int team = static_cast<int>(std::min<std::ptrdiff_t>(threads, std::max<std::ptrdiff_t>(count, 1)));
#pragma omp parallel for schedule(dynamic) num_threads(team) reduction(+ : compute_s)
    for (std::ptrdiff_t k = 0; k < count; ++k) {
      if (watch.changed().load()) continue;  // stopped: the inputs are not what they were
      const std::size_t index = static_cast<std::size_t>(k);
      guard->started(omp_get_thread_num(), block_points[index]);
      ComputedPoint computed = runner::compute_point(*kind, study, block_points[index], columns,
                                                     options.out_dir, options.plots);
      guard->finished(omp_get_thread_num());
      compute_s += computed.compute_s;
      keep(index, std::move(computed));
      serve();
    }
    block_done();
  }
  const double loop_s = seconds_since(loop_start);
  // Rank 0 takes the blocks still on their way; the others say they are done.
  if (rank == 0)
    stream.drain(take_block);
  else
    stream.close();
  pool.reset();
  guard.reset();
  journal->flush();
  progress.finish();

  // The files on disk compared in full once more: a change the watch has not seen yet (or one
  // that kept size and times) still fails the run.
  std::vector<std::string> changes = watch.changes();
  if (changes.empty() && study.inputs) changes = study.inputs->changes();

  // Every rank's counters to rank 0 (its points went by the stream).
  Json payload = {{"computed", computed_points.load()},
                  {"compute_s", compute_s},
                  {"loop_s", loop_s},
                  {"output_failures", output_failures.load()},
                  {"journal_error", journal->error()},
                  {"input_changes", changes}};
  journal.reset();
  std::vector<std::string> payloads = runner::gather_to_root(runner::json_text(payload));

  std::string outcome;
  if (rank == 0) {
    Json result = Json::object();
    try {
      if (!stream_error.empty()) throw std::logic_error(stream_error);
      std::vector<PointResult> shard_results;  // a shard's points, by grid index
      if (!writer) {
        shard_results.resize(n);
        for (std::size_t p = 0; p < n; ++p)
          if (prep.resumed.has(p)) shard_results[p] = prep.resumed.take(p);
        for (auto& [p, r] : shard_kept) shard_results[p] = std::move(r);
        decltype(shard_kept)().swap(shard_kept);
      }
      ComputeStats stats;
      for (std::size_t r = 0; r < payloads.size(); ++r) {
        Json from = Json::parse(payloads[r]);
        stats.computed += from["computed"].get<std::size_t>();
        stats.compute_s += from["compute_s"].get<double>();
        stats.per_rank.push_back({{"points", from["computed"]},
                                  {"compute_s", from["compute_s"]},
                                  {"loop_s", from["loop_s"]}});
        stats.output_failures += from["output_failures"].get<std::size_t>();
        if (auto error = from["journal_error"].get<std::string>(); !error.empty())
          stats.journal_errors.push_back(error);
        for (const auto& change : from["input_changes"])
          if (std::find(stats.input_changes.begin(), stats.input_changes.end(), change) ==
              stats.input_changes.end())
            stats.input_changes.push_back(change.get<std::string>());
      }
      if (!stats.input_changes.empty()) {
        if (writer) writer->abandon();
        result["input_error"] = input_changed(meta_in, stats.input_changes);
      } else if (options.shard) {
        runner::ShardRun shard_run{prep.session, prep.resumed.count(), stats.computed,
                                   stats.compute_s, seconds_since(start), stats.journal_errors,
                                   stats.output_failures > 0
                                       ? fmt::format("{} point(s) could not write their files",
                                                     stats.output_failures)
                                       : ""};
        runner::ShardOutcome written = runner::write_shard_meta(meta_in, shard_results, shard_run);
        result["failed"] = written.failed;
        result["timed_out"] = written.timed_out;
        result["output_error"] = written.output_error;
      } else {
        OutputsWritten written =
            write_outputs(*kind, meta_in, prep, *writer, stats, start);
        result["failed"] = written.failed;
        result["timed_out"] = written.timed_out;
        result["output_error"] = written.output_error;
        result["notices"] = written.notices;
      }
    } catch (const std::exception& e) {
      if (ranks == 1) throw;
      result["error"] = e.what();
    }
    outcome = runner::json_text(result);
  }
  // Every rank returns the same summary (and exit code), or fails the same way.
  runner::broadcast_from_root(outcome);
  Json result = Json::parse(outcome);
  if (result.contains("input_error")) throw InputError(result["input_error"].get<std::string>());
  if (result.contains("error")) throw std::runtime_error(result["error"].get<std::string>());

  RunSummary summary;
  summary.points = options.shard ? runner::shard_point_count(n, *options.shard) : n;
  summary.failed = result["failed"].get<std::size_t>();
  summary.timed_out = result["timed_out"].get<std::size_t>();
  summary.output_error = result["output_error"].get<std::string>();
  if (!options.shard)
    summary.results_file = runner::results_path(options.out_dir, runner::results_format(study));
  if (result.contains("notices"))
    for (const Json& notice : result["notices"])
      summary.notices.push_back({notice["point"].get<std::size_t>(), notice["notice"].get<std::string>()});
  summary.resumed = static_cast<std::size_t>(std::count(prep.done.begin(), prep.done.end(), '1'));
  return summary;
}

}  // namespace chatterlab
