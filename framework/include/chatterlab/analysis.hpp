#pragma once
// Base class of analysis plugins (MODELS.md N chaos, C monitoring, W waviness, E roundness): an
// analysis takes one uniformly sampled series (a vibration signal over time, or a surface profile
// over length or angle) and returns named results. Study kinds pick analyses by registered name,
// e.g. `[analysis] methods = ["embedding", "lyapunov"]`, so a new method is one plugin folder.
//
// Results are JSON objects so that every method can report what it needs; the convention for a
// scalar estimate is an object
//     { "value": v, "ci_low": a, "ci_high": b, "quality": "good" | "uncertain" | "failed",
//       "reason": "..." }
// and curves (e.g. AMI over lag) as arrays under their own keys, which plot() draws.
#include <filesystem>
#include <string>
#include <vector>

#include "chatterlab/params.hpp"
#include "chatterlab/registry.hpp"

namespace chatterlab {

struct SampledSeries {
  std::vector<double> values;
  double sample_interval = 1.0;    // in sample_unit: s for signals, mm for open profiles, rad or
                                   // deg for closed (circumferential) profiles
  std::string sample_unit = "s";
  bool closed = false;             // one full revolution: values wrap around (periodic)
  std::string name;                // e.g. the input column, for plot titles

  double sample_rate() const { return 1.0 / sample_interval; }  // samples per sample_unit
};

class Analysis {
 public:
  virtual ~Analysis() = default;

  // Results of this analysis (with the parameters it was built with) on `series`. `context` holds
  // results of analyses run earlier in the same study, keyed by plugin name (e.g. a Lyapunov
  // estimate reads "embedding" for delay and dimension when its own parameters say "auto").
  // Throws InputError when the series cannot be analysed as configured (too short for the
  // dimension, constant, non-finite), naming the minimum; PointFailure for numerical failure.
  virtual Json analyse(const SampledSeries& series, const Json& context) const = 0;

  // Plots (PNG + SVG through chatterlab/plot.hpp) of a result from analyse(), file stems starting
  // with the plugin name. Default: none.
  virtual void plot(const Json& /*result*/, const SampledSeries& /*series*/,
                    const std::filesystem::path& /*out_dir*/) const {}
};

}  // namespace chatterlab
