#pragma once
// Capability of an analysis whose result holds long numeric series, one value per window or per
// sample (C1 window features, a detector's score track): it can return them as vectors beside the
// JSON result instead of inside it. A caller that wants arrays (the Python API, issue 24: window
// features of 10^7 samples are 4 x 10^6 numbers) then moves each vector into its array, without
// building a JSON value per number and converting it back; analyse() of the same analysis returns
// the JSON result with the series put in place (ResultWithArrays::merged), so studies, summary
// files and plots see exactly what they saw before.
//
// Found by dynamic_cast<const AnalysisWithArrays*>(&analysis) rather than through a virtual
// accessor of Analysis (chatterlab/analysis.hpp), so that plugins compiled against a header
// without it keep their vtable layout. Series whose length the parameters bound (a mutual
// information curve over lags, correlation sums over radii) stay in the JSON. A series too long
// for summary files (a filtered profile, as long as the input) can be given to array callers only
// (add_array_only): merged() leaves it out, so analyse() is unchanged by it.
#include <string>
#include <utility>
#include <vector>

#include "chatterlab/analysis.hpp"
#include "chatterlab/params.hpp"

namespace chatterlab {

struct ResultArray {
  std::string key;             // top-level key of the result
  std::vector<double> values;  // booleans as 0 / 1 when `boolean`
  bool boolean = false;        // a flag per window (e.g. an alarm state): JSON true/false
  bool in_json = true;         // false: for array callers only, not in merged()
};

struct ResultWithArrays {
  // The result without the series: each key of `arrays` holds null here, in its place, so
  // that merged() keeps the key order of the JSON result.
  Json result = Json::object();
  std::vector<ResultArray> arrays;

  // Sets `key` aside for the series `values` (moved in).
  void add(std::string key, std::vector<double> values, bool boolean = false) {
    result[key] = nullptr;
    arrays.push_back({std::move(key), std::move(values), boolean});
  }

  // A series for array callers only (after the result's own keys there): not in merged().
  void add_array_only(std::string key, std::vector<double> values) {
    arrays.push_back({std::move(key), std::move(values), false, false});
  }

  // The JSON result, each series as an array under its key (what Analysis::analyse returns).
  Json merged() && {
    for (ResultArray& a : arrays) {
      if (!a.in_json) continue;
      Json& slot = result[a.key];
      if (a.boolean) {
        slot = Json::array();
        for (double v : a.values) slot.push_back(v != 0.0);
      } else {
        slot = std::move(a.values);
      }
    }
    arrays.clear();
    return std::move(result);
  }
};

class AnalysisWithArrays {
 public:
  virtual ~AnalysisWithArrays() = default;
  // The same result as Analysis::analyse, with the long series as vectors.
  virtual ResultWithArrays analyse_with_arrays(const SampledSeries& series, const Json& context) const = 0;
};

}  // namespace chatterlab
