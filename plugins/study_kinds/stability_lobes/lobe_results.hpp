#pragma once
// One stability_lobes point: what it reads from its document, what it computes, and the files and
// plots it writes (stability_lobes.cpp, lobe_plots.cpp).
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/kit.hpp"
#include "study_kinds/stability_lobes/lobe_tracer.hpp"
#include "study_kinds/stability_lobes/lobes_settings.hpp"
#include "study_kinds/stability_lobes/time_to_chatter.hpp"

namespace chatterlab::lobes {

struct LobeStudy {
  LobeStudy(LobesSettings s, VariedModel m) : settings(std::move(s)), model(std::move(m)) {}
  LobesSettings settings;
  std::optional<TimeToChatterSettings> time_to_chatter;
  VariedModel model;
  Route route = Route::roots;
  double band_hz = 0.0;
  std::vector<double> speeds;
  double window_value = 0.0;
  double operating_speed = 0.0;  // the model's own value of the speed key
  std::string title;
};

// A speed interval where the limit lies above the window value: chatter-free there.
struct Window {
  double from = 0.0, to = 0.0;
  double peak_value = 0.0, peak_speed = 0.0;  // the highest limit inside
};

struct LobeResults {
  LobeDiagram diagram;
  std::vector<Window> windows;
  std::vector<std::string> sensitivity_keys;
  std::vector<std::vector<double>> elasticities;  // [speed][key]: relative change of the limit per relative change of the key
  std::optional<GrowthMap> growth;
};

// The speed intervals where the envelope exceeds `level` (ends interpolated linearly between traced
// points; a speed with no crossing in the range counts as above, one unstable at the range's lower
// end as below).
std::vector<Window> chatter_free_windows(const LobeDiagram& d, double level);

void plot_lobe_diagram(const LobeStudy& study, const LobeResults& r, const std::filesystem::path& dir,
                       kit::Figures& figures);
void plot_time_to_chatter(const LobeStudy& study, const LobeResults& r, const std::filesystem::path& dir,
                          kit::Figures& figures);

}  // namespace chatterlab::lobes
