#include "study_kinds/stability_lobes/time_to_chatter.hpp"

#include <cmath>
#include <numbers>

#include "chatterlab/errors.hpp"
#include "chatterlab/roots.hpp"

namespace chatterlab::lobes {

double time_to_chatter_s(double growth_rate_per_s, const TimeToChatterSettings& s) {
  if (!(growth_rate_per_s > 0.0)) return std::numeric_limits<double>::infinity();
  return std::log(s.tolerance_um / s.initial_waviness_um) / growth_rate_per_s;
}

long parts_before_chatter(double time_to_chatter_s, const TimeToChatterSettings& s) {
  constexpr double cap = 1e9;
  return static_cast<long>(std::min(std::floor(time_to_chatter_s / s.part_time_s), cap));
}

bool dressed_in_time(double time_to_chatter_s, const TimeToChatterSettings& s) {
  return parts_before_chatter(time_to_chatter_s, s) >= s.dressing_interval_parts;
}

std::vector<double> spread(double low, double high, int n) {
  std::vector<double> v;
  const bool geometric = high / low > 10.0;
  for (int i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / (n - 1);
    v.push_back(i == n - 1 ? high : geometric ? low * std::pow(high / low, t) : low + t * (high - low));
  }
  return v;
}

GrowthMap growth_map(const VariedModel& model, const std::vector<double>& speeds, const std::vector<double>& parameters,
                     double band_hz) {
  GrowthMap map{speeds, parameters, std::vector<double>(speeds.size() * parameters.size(), NAN),
                std::vector<double>(speeds.size() * parameters.size(), NAN)};
  for_each_index(map.growth_rate_per_s.size(), [&](std::size_t k) {
    try {
      const auto m = model.at(parameters[k / speeds.size()], speeds[k % speeds.size()]);
      RootSearchOptions options;
      options.max_frequency_hz = band_hz;
      const RightmostRoot r = find_rightmost_root(*m->characteristic(), options);
      map.growth_rate_per_s[k] = r.root.real();
      map.chatter_frequency_hz[k] = std::abs(r.root.imag()) / (2.0 * std::numbers::pi);
    } catch (const PointFailure&) {
      // left NaN: a grey cell in the map, an empty cell in the table
    }
  });
  return map;
}

}  // namespace chatterlab::lobes
