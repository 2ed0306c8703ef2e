#pragma once
// Time to chatter (docs/studies.md, "stability_lobes", [time_to_chatter]): in grinding "stable"
// is often "grows slowly enough to dress in time". From the growth rate sigma of the rightmost
// root, a waviness a0 grows as a0 e^{sigma t}; it exceeds the tolerance a_tol after
//   t = ln(a_tol / a0) / sigma        (never when sigma <= 0),
// that is after floor(t / part_time) whole parts. The wheel carries its waviness from part to part
// until it is dressed, so wheel-regenerative chatter accumulates over the parts of a dressing
// interval: the wheel is "dressed in time" when more parts than the interval are ground before t.
// (Workpiece-regenerative chatter starts afresh on every part: for it, compare t with part_time.)
#include <limits>
#include <vector>

#include "study_kinds/stability_lobes/lobes_settings.hpp"

namespace chatterlab::lobes {

double time_to_chatter_s(double growth_rate_per_s, const TimeToChatterSettings& s);
// Whole parts ground before the tolerance is exceeded (a large number, capped, when stable).
long parts_before_chatter(double time_to_chatter_s, const TimeToChatterSettings& s);
bool dressed_in_time(double time_to_chatter_s, const TimeToChatterSettings& s);

// The rightmost root over speed x parameter (row-major: parameter index outer), by the certified
// root search (the roots route); NaN where a search failed.
struct GrowthMap {
  std::vector<double> speeds, parameters;
  std::vector<double> growth_rate_per_s, chatter_frequency_hz;
};
GrowthMap growth_map(const VariedModel& model, const std::vector<double>& speeds,
                     const std::vector<double>& parameters, double band_hz);

// n values from low to high, geometric when high/low > 10.
std::vector<double> spread(double low, double high, int n);

}  // namespace chatterlab::lobes
