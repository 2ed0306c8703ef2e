// The stability_lobes plots: the lobe diagram (stable region shaded, every traced lobe, the limit,
// chatter-free windows at the window value) and the time-to-chatter map.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "study_kinds/stability_lobes/lobe_results.hpp"

namespace chatterlab::lobes {

namespace {

// The margin of the window value from the limit along the speeds, > 0 where chatter-free: limit -
// level where the stable side is below the limit, level - limit where it is above; +inf where
// nothing crosses in the range (stable throughout), -inf where the whole range is unstable. The
// lobe intersections between speeds are included.
std::vector<std::pair<double, double>> margin_profile(const LobeDiagram& d, double level) {
  std::vector<std::pair<double, double>> profile;
  std::size_t next = 0;
  for (const Crossing& c : d.envelope) {
    while (next + 1 < d.speeds.size() && d.speeds[next] < c.speed) ++next;
    const bool below = d.at[next].stable_below;
    profile.emplace_back(c.speed, below ? c.parameter - level : level - c.parameter);
  }
  for (std::size_t i = 0; i < d.speeds.size(); ++i) {
    if (d.at[i].limit) continue;
    const bool stable = d.at[i].note.rfind("no crossing", 0) == 0;
    const bool unstable = d.at[i].note.rfind("unstable", 0) == 0;
    if (stable || unstable) profile.emplace_back(d.speeds[i], stable ? INFINITY : -INFINITY);
  }
  std::sort(profile.begin(), profile.end());
  return profile;
}

}  // namespace

std::vector<Window> chatter_free_windows(const LobeDiagram& d, double level) {
  const auto profile = margin_profile(d, level);
  std::vector<Window> windows;
  std::optional<Window> open;
  auto zero_at = [&](const std::pair<double, double>& a, const std::pair<double, double>& b) {
    // Next to a speed where nothing crosses (or everything is unstable) the edge is that speed:
    // the windows claim only what was computed.
    if (!std::isfinite(a.second) || !std::isfinite(b.second)) return std::isfinite(a.second) ? b.first : a.first;
    return a.first - a.second / (b.second - a.second) * (b.first - a.first);
  };
  for (std::size_t i = 0; i < profile.size(); ++i) {
    const auto& [v, m] = profile[i];
    if (m > 0.0 && !open) open = Window{i == 0 ? v : zero_at(profile[i - 1], profile[i]), 0.0, m, v};
    if (m <= 0.0 && open) {
      open->to = zero_at(profile[i - 1], profile[i]);
      windows.push_back(*open);
      open.reset();
    }
    if (m > 0.0 && open && m > open->peak_value) open->peak_value = m, open->peak_speed = v;
  }
  if (open) {
    open->to = profile.back().first;
    windows.push_back(*open);
  }
  // The peak as a limit value, not a margin.
  for (Window& w : windows)
    for (const Crossing& c : d.envelope)
      if (c.speed == w.peak_speed) w.peak_value = c.parameter;
  return windows;
}

namespace {

// The stable region: below the limit (filled to the bottom) or above it (filled to the top), as
// most speeds have it; a speed with nothing crossing in the range is stable throughout.
plot::Series stable_region(const LobeDiagram& d, double top) {
  const auto above = std::count_if(d.at.begin(), d.at.end(), [](const SpeedResult& r) { return r.limit && !r.stable_below; });
  const auto below = std::count_if(d.at.begin(), d.at.end(), [](const SpeedResult& r) { return r.limit && r.stable_below; });
  plot::Series stable{"stable", {}, {}, above > below ? "area_above" : "area"};
  for (const auto& [v, m] : margin_profile(d, 0.0)) {
    stable.x.push_back(v);
    // margin_profile at level 0 is the limit itself (below) or its negative (above)
    stable.y.push_back(std::isinf(m) ? (m > 0 ? (above > below ? 0.0 : top) : (above > below ? top : 0.0))
                                     : std::min(std::abs(m), top));
  }
  return stable;
}

}  // namespace

void plot_lobe_diagram(const LobeStudy& study, const LobeResults& r, const std::filesystem::path& dir,
                       kit::Figures& figures) {
  const LobeDiagram& d = r.diagram;
  double highest = 0.0;
  for (const Crossing& c : d.envelope) highest = std::max(highest, c.parameter);
  if (!(highest > 0.0)) highest = study.settings.parameter_range[1];
  // Room for the lobes above the limit, and for the window value when it is not far above.
  double top = 2.5 * highest;
  if (study.window_value > top && study.window_value < 8.0 * highest) top = 1.2 * study.window_value;
  top = std::min(top, study.settings.parameter_range[1]);
  plot::Curves f;
  f.title = fmt::format("{}: lobe diagram ({} lobes traced)", study.title, d.lobes.size());
  f.x_label = kit::axis_label(study.settings.speed);
  f.y_label = "critical " + kit::axis_label(study.settings.parameter);
  f.y_range = {{0.0, top}};
  plot::Series lobes{fmt::format("lobes ({})", d.lobes.size()), {}, {}, "lines"};
  for (const Lobe& lobe : d.lobes) {
    for (const Crossing& c : lobe.points) {
      lobes.x.push_back(c.speed);
      lobes.y.push_back(c.parameter);
    }
    lobes.x.push_back(NAN);  // a gap between lobes
    lobes.y.push_back(NAN);
  }
  plot::Series limit{"stability limit", {}, {}, "lines"};
  for (const Crossing& c : d.envelope) {
    limit.x.push_back(c.speed);
    limit.y.push_back(c.parameter);
  }
  const bool shown = study.window_value <= top;
  plot::Series windows{fmt::format("chatter-free at {:.4g}{} ({} window{})", study.window_value,
                                   shown ? "" : " (above the plot)", r.windows.size(), r.windows.size() == 1 ? "" : "s"),
                       {NAN}, {NAN}, "lines"};
  for (const Window& w : r.windows) {
    windows.x.insert(windows.x.end(), {w.from, w.to, NAN});
    windows.y.insert(windows.y.end(), {study.window_value, study.window_value, NAN});
  }
  // The model's own speed and parameter: where the study's machine runs.
  plot::Series operating{fmt::format("operating point ({:.4g}, {:.4g})", study.operating_speed, study.window_value),
                         {study.operating_speed}, {study.window_value}, "points"};
  f.series = {stable_region(d, top), lobes, limit, windows, operating};
  f.looks = {{"#56b4e9", 0.0}, {"#a8a8a8", 0.8}, {"#000000", 2.5}, {"#009e73", 6.0}, {"#d55e00", 3.0}};
  if (shown) {
    f.reference_y = study.window_value;
    f.reference_label = fmt::format("{} = {:.4g}", kit::axis_label(study.settings.parameter), study.window_value);
  }
  figures.render(f, dir, "lobe_diagram");
}

void plot_time_to_chatter(const LobeStudy& study, const LobeResults& r, const std::filesystem::path& dir,
                          kit::Figures& figures) {
  const GrowthMap& g = *r.growth;
  const TimeToChatterSettings& s = *study.time_to_chatter;
  const double cycle = s.part_time_s * s.dressing_interval_parts;
  constexpr double decades = 3.0;  // the colour scale spans 1/1000 to 1000 dressing cycles
  plot::Heatmap h;
  h.title = fmt::format("{}: time for {:g} um to grow to {:g} um", study.title, s.initial_waviness_um, s.tolerance_um);
  h.x_label = kit::axis_label(study.settings.speed);
  h.y_label = kit::axis_label(study.settings.parameter);
  // Red where chatter comes first, as on every chatter map of the plot service: the colour is
  // log10(dressing cycle / time to chatter), > 0 when the tolerance is reached within the cycle.
  h.z_label = fmt::format("log10(dressing cycle ({} x {:g} s) / time to chatter)", s.dressing_interval_parts,
                          s.part_time_s);
  h.x = g.speeds;
  h.y = g.parameters;
  h.log_y = g.parameters.back() / g.parameters.front() > 10.0;
  for (double sigma : g.growth_rate_per_s) {
    const double t = time_to_chatter_s(sigma, s);
    h.z.push_back(std::isnan(sigma) ? NAN : std::clamp(std::log10(cycle / t), -decades, decades));
  }
  h.contour_level = 0.0;
  h.contour_label = "tolerance reached at dressing";
  h.diverging = true;
  h.low_label = "dressed in time";
  h.high_label = "chatter first";
  plot::Series limit{"stability limit", {}, {}, "dashes"};
  for (const Crossing& c : r.diagram.envelope) {
    limit.x.push_back(c.speed);
    limit.y.push_back(c.parameter);
  }
  h.overlays.push_back(limit);
  h.overlay_looks.push_back({"#000000", 1.5});
  figures.render(h, dir, "time_to_chatter_map");
}

}  // namespace chatterlab::lobes
