#pragma once
// A study kind ([study] kind = "..."): what to compute at one grid point and which plots to draw.
// Kinds register in their own registry like plugins:  CHATTERLAB_REGISTER_STUDY_KIND(StabilityMap);
// The runner (grid, threads, MPI ranks, resume, results.csv, meta.json) is shared by all kinds.
#include <filesystem>
#include <memory>
#include <string>
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
};

class StudyKind {
 public:
  virtual ~StudyKind() = default;

  // Validates the kind's own tables in `document` (e.g. [model] through the model registry,
  // [stability] against its specs) and fills defaults in place. `sources` locates lines for
  // errors. Throws InputError.
  virtual void validate(Json& document, const SourceMap& sources) const = 0;

  // Names of the numeric output columns (after the grid columns, before `status`).
  virtual std::vector<std::string> output_columns(const Json& document) const = 0;

  // Computes one grid point from its document (grid values applied, already validated).
  // Returns one value per output column (number, boolean or short string). Throws PointFailure
  // (recorded, run continues). Must be thread-safe: called concurrently for different points.
  virtual std::vector<Json> run_point(const Json& point_document) const = 0;

  // Plots and any other whole-study artefacts (PNG + SVG). Called once, after all points.
  virtual void write_artifacts(const Study& study, const ResultTable& results,
                               const std::filesystem::path& out_dir) const = 0;

  // The plugins this point uses might be serial-only (ThreadSafety::serial).
  virtual bool requires_serial(const Json& /*document*/) const { return false; }
};

Registry<StudyKind>& study_kind_registry();

}  // namespace chatterlab

#define CHATTERLAB_REGISTER_STUDY_KIND(Type) \
  CHATTERLAB_DETAIL_REGISTER(::chatterlab::study_kind_registry, Type)
