#pragma once
// A study kind ([study] kind = "..."): what to compute at one grid point and which plots to draw.
// Kinds register in their own registry like plugins, with one line in their .cpp:
//
//     CHATTERLAB_REGISTER_STUDY_KIND(StabilityMap);
//
// Convention: the class has `static PluginInfo info()` whose name is the kind name and whose
// params/example_params describe the kind's own settings table (e.g. [stability]; thread_safety
// is always `shareable` for a kind, set at registration), so that
// `chatterlab describe` and the conformance test treat kinds like plugins; and a default
// constructor (a kind holds no per-study state: everything arrives in the document). A
// constructor from `const ParamValues&` is accepted instead, and then gets an empty table.
// The runner (grid, threads, MPI ranks, resume, results.csv, meta.json) is shared by all kinds.
#include <filesystem>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "chatterlab/params.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/study.hpp"

namespace chatterlab {

// The finished results of a run, in grid order, as the runner hands them to plotting.
struct ResultTable {
  std::vector<std::string> grid_columns;    // grid keys as written
  std::vector<std::string> output_columns;  // the kind's outputs
  // rows[i] = grid values then outputs (null for a failed point's outputs); status[i] "ok" or
  // "failed: <reason>". Cells are numbers, booleans or short strings.
  std::vector<std::vector<Json>> rows;
  std::vector<std::string> status;
  // Plots of a large grid get a bounded table (docs/architecture.md, "Streaming results"): the
  // points on every strides[a]-th value of grid axis a, out of full_point_count points, and the
  // Study handed to write_artifacts with it has exactly those axis values, so a kind draws it as
  // it would draw the whole grid. results.csv always holds every point. Empty: every point.
  std::vector<std::size_t> strides;
  std::size_t full_point_count = 0;
  bool decimated() const { return !strides.empty(); }
};

// Where a point may put its own files. A study without [grid] has one point, whose artefact
// directory is the output directory itself (a `simulate` run writes timeseries.csv and
// summary.json next to results.csv). In a grid, point i gets <out>/points/<i, 6 digits>/, which
// the kind creates only if it writes something (a kind may write nothing per point, e.g. for
// large grids). Write through write_file_atomically (chatterlab/output_files.hpp): a killed run
// must not leave half a file that a resumed run would take for finished.
struct PointContext {
  std::size_t index = 0;        // grid point index
  std::size_t point_count = 1;  // points in the study
  std::filesystem::path artifact_dir;  // empty: write no files (unit tests, benchmarks)
  bool plots = true;                   // false: data files only (chatterlab run --no-plots)
  bool single_point() const { return point_count == 1; }
};

class StudyKind {
 public:
  virtual ~StudyKind() = default;

  // The top-level tables this kind reads besides [study] and [grid] (and `plugins`), e.g.
  // {"model", "stability"}. load_study rejects any other top-level key, listing these, and grid
  // keys may only point into them. Default: the [model] table alone.
  virtual std::vector<std::string> tables() const { return {"model"}; }

  // Analyses this kind configures from sub-tables [<table>.<analysis name>] of one of its own
  // tables, e.g. chatter_monitor's [monitor.bp_network]: `chatterlab describe <analysis>` names
  // them (a kind that lists analyses under [analysis] methods needs nothing here).
  struct NestedAnalyses {
    std::string table;
    std::vector<std::string> analyses;
  };
  virtual std::vector<NestedAnalyses> nested_analyses() const { return {}; }

  // Validates the kind's own tables in `document` (e.g. [model] through the model registry,
  // [stability] against its specs) and fills defaults in place. `sources` locates lines for
  // errors. Throws InputError. Must accept its own output unchanged (idempotent): load_study
  // re-validates the validated document once per grid value, with that value written in, and
  // for long grid axes does so from several threads at once (on different documents).
  virtual void validate(Json& document, const SourceMap& sources) const = 0;

  // Names of the output columns (after the grid columns, before `status`). A column named
  // `notice` holds what the user must read even when the point completed (e.g. "no stable
  // candidate: ..."): the runner lists its non-empty cells in meta.json and on the terminal.
  virtual std::vector<std::string> output_columns(const Json& document) const = 0;

  // Computes one grid point from its document (grid values applied, already validated).
  // Returns one value per output column (number, boolean or short string). Throws PointFailure
  // (recorded, run continues). Must be thread-safe: called concurrently for different points.
  // Per-point files (time series, spectra, a summary.json) go to context.artifact_dir.
  virtual std::vector<Json> run_point(const Json& point_document,
                                      const PointContext& context) const = 0;

  // Plots and any other whole-study artefacts (PNG + SVG). Called once, after all points.
  // Default: none (a kind whose figures belong to one point draws them in run_point, into the
  // point's artefact directory; a grid of such points is compared through results.csv).
  virtual void write_artifacts(const Study& /*study*/, const ResultTable& /*results*/,
                               const std::filesystem::path& /*out_dir*/) const {}

  // The plugins this point uses might be serial-only (ThreadSafety::serial). Default: when the
  // kind reads a [model] table (tables() lists "model"), whether that model plugin is declared
  // serial (model_is_serial); otherwise false. A kind that builds other plugins says so here.
  virtual bool requires_serial(const Json& document) const;
};

Registry<StudyKind>& study_kind_registry();  // kind name "study kind"

// True when the model plugin named by model_table["type"] declares itself serial: what a kind
// that builds the study's [model] returns from requires_serial.
bool model_is_serial(const Json& model_table);

namespace detail {
Json validate_component(const Json& document, const std::string& table,
                        const std::string& registry_kind, const std::vector<const PluginInfo*>& plugins,
                        const SourceMap& sources);
}

// For StudyKind::validate: checks the component table `[table] type = "<plugin>" + parameters`
// (e.g. [model] against model_registry()) and returns it validated: `type` first, then every
// declared parameter with defaults filled in. Throws InputError when the table is missing or not a
// table, `type` is missing or names no registered plugin (listing the valid names), or a
// parameter is wrong (see validate_params).
template <class Product>
Json validate_component(const Json& document, const std::string& table,
                        const Registry<Product>& registry, const SourceMap& sources) {
  std::vector<const PluginInfo*> plugins;
  for (const auto* entry : registry.sorted()) plugins.push_back(&entry->info);
  return detail::validate_component(document, table, registry.kind(), plugins, sources);
}

// The declaration of study kind T as registered: T::info() with the thread safety every kind has
// by contract. One kind instance computes all points of a run concurrently (run_point is const
// and thread-safe, see above), so a kind need not, and cannot, declare anything else.
template <class T>
PluginInfo study_kind_info() {
  PluginInfo info = T::info();
  info.thread_safety = ThreadSafety::shareable;
  return info;
}

// Adds study kind T (see the convention above) to a registry.
template <class T>
void add_study_kind(Registry<StudyKind>& registry, std::string origin = "built-in") {
  registry.add(study_kind_info<T>(), []([[maybe_unused]] const ParamValues& p) -> std::unique_ptr<StudyKind> {
    if constexpr (std::is_default_constructible_v<T>)
      return std::make_unique<T>();
    else
      return std::make_unique<T>(p);
  }, std::move(origin));
}

}  // namespace chatterlab

#define CHATTERLAB_REGISTER_STUDY_KIND(Type)                                              \
  namespace {                                                                              \
  [[maybe_unused]] const bool CHATTERLAB_DETAIL_CAT(chatterlab_registered_kind_, __LINE__) = \
      (::chatterlab::add_study_kind<Type>(::chatterlab::study_kind_registry()), true);    \
  }
