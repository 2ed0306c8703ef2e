// The stability_lobes plots: the lobe diagram (stable region shaded, every traced lobe, the limit,
// chatter-free windows at the window value) and the time-to-chatter map.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "study_kinds/stability_lobes/lobe_results.hpp"

namespace chatterlab::lobes {

namespace {

// The envelope as a function of speed for the windows: +inf where nothing crosses in the range
// (stable throughout), -inf where the range's lower end is already unstable, else the limit;
// with the lobe intersections between speeds.
std::vector<std::pair<double, double>> envelope_profile(const LobeDiagram& d) {
  std::vector<std::pair<double, double>> profile;
  for (const Crossing& c : d.envelope) profile.emplace_back(c.speed, c.parameter);
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
  const auto profile = envelope_profile(d);
  std::vector<Window> windows;
  std::optional<Window> open;
  auto crossing_speed = [&](const std::pair<double, double>& a, const std::pair<double, double>& b) {
    if (!std::isfinite(a.second) || !std::isfinite(b.second)) return std::isfinite(a.second) ? a.first : b.first;
    return a.first + (level - a.second) / (b.second - a.second) * (b.first - a.first);
  };
  for (std::size_t i = 0; i < profile.size(); ++i) {
    const auto& [v, p] = profile[i];
    const bool above = p > level;
    if (above && !open) {
      open = Window{i == 0 ? v : crossing_speed(profile[i - 1], profile[i]), 0.0, p, v};
    } else if (!above && open) {
      open->to = crossing_speed(profile[i - 1], profile[i]);
      windows.push_back(*open);
      open.reset();
    }
    if (above && open && p > open->peak_value) open->peak_value = p, open->peak_speed = v;
  }
  if (open) {
    open->to = profile.back().first;
    windows.push_back(*open);
  }
  return windows;
}

void plot_lobe_diagram(const LobeStudy& study, const LobeResults& r, const std::filesystem::path& dir,
                       kit::Figures& figures) {
  const LobeDiagram& d = r.diagram;
  const double p_hi = study.settings.parameter_range[1];
  double highest = study.window_value;
  for (const Crossing& c : d.envelope) highest = std::max(highest, c.parameter);
  const double top = std::min(p_hi, 1.6 * highest), bottom = 0.0;
  plot::Curves f;
  f.title = fmt::format("{}: lobe diagram ({} lobes traced)", study.title, d.lobes.size());
  f.x_label = kit::axis_label(study.settings.speed);
  f.y_label = "critical " + kit::axis_label(study.settings.parameter);
  f.y_range = {{bottom, top}};
  // Stable region: below the limit; up to the top where nothing crosses in the range.
  plot::Series stable{"stable (below the limit)", {}, {}, "area"};
  for (const auto& [v, p] : envelope_profile(d)) {
    stable.x.push_back(v);
    stable.y.push_back(std::isinf(p) ? (p > 0 ? top : bottom) : std::min(p, top));
  }
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
  plot::Series windows{fmt::format("chatter-free at {:.4g} ({} window{})", study.window_value, r.windows.size(),
                                   r.windows.size() == 1 ? "" : "s"),
                       {}, {}, "lines"};
  for (const Window& w : r.windows) {
    windows.x.insert(windows.x.end(), {w.from, w.to, NAN});
    windows.y.insert(windows.y.end(), {study.window_value, study.window_value, NAN});
  }
  if (r.windows.empty()) {  // keep the key entry: "0 windows" is the message
    windows.x = {NAN};
    windows.y = {NAN};
  }
  f.series = {stable, lobes, limit, windows};
  f.looks = {{"#56b4e9", 0.0}, {"#9a9a9a", 1.0}, {"#000000", 2.5}, {"#009e73", 6.0}};
  f.reference_y = study.window_value;
  f.reference_label = fmt::format("{} = {:.4g}", kit::axis_label(study.settings.parameter), study.window_value);
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
  h.z_label = fmt::format("log10(time to chatter / dressing cycle of {} x {:g} s)", s.dressing_interval_parts, s.part_time_s);
  h.x = g.speeds;
  h.y = g.parameters;
  h.log_y = g.parameters.back() / g.parameters.front() > 10.0;
  for (double sigma : g.growth_rate_per_s) {
    const double t = time_to_chatter_s(sigma, s);
    h.z.push_back(std::isnan(sigma) ? NAN : std::clamp(std::log10(t / cycle), -decades, decades));
  }
  h.contour_level = 0.0;
  h.contour_label = "tolerance reached at the dressing interval";
  h.diverging = true;
  h.low_label = "chatter first";
  h.high_label = "dressed in time";
  plot::Series limit{"stability limit (traced lobes)", {}, {}, "lines"};
  for (const Crossing& c : r.diagram.envelope) {
    limit.x.push_back(c.speed);
    limit.y.push_back(c.parameter);
  }
  h.overlays.push_back(limit);
  h.overlay_looks.push_back({"#000000", 2.0});
  figures.render(h, dir, "time_to_chatter_map");
}

}  // namespace chatterlab::lobes
