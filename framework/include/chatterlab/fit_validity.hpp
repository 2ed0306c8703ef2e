#pragma once
// Can a growth rate fitted to a simulated response be trusted? (issue 19, docs/dynamics.md
// "Validity of a fitted growth rate"). The linear theory's rightmost root (G1, G5..G7) predicts the
// exponential growth of a response only while the contact stays closed, the envelope is still
// exponential and the window spans several regenerative delays; outside that regime a fitted
// slope is a number without meaning. assess_fit classifies the window and says why.
#include <span>
#include <string>

#include "chatterlab/dynamics.hpp"

namespace chatterlab {

enum class ResponseRegime {
  linear_growth,  // exponential growth over the window: the fit estimates the rightmost root
  linear_decay,   // exponential decay over the window: likewise
  saturated,      // growth slows across the window (nonlinearity, amplitude limit)
  contact_lost,   // one-sided contact open for more than the allowed fraction of the window
  transient,      // the window starts too early or spans too few regenerative delays
  not_exponential, // the envelope is not a straight line in ln (beating roots, pulses per revolution)
  steady          // the envelope holds its level: a forced steady state (or a root on Re s = 0)
};
const char* to_string(ResponseRegime regime);

struct FitValidityLimits {
  double max_contact_loss_fraction = 0.02;  // of the fit window
  // The rightmost root governs only once the regenerated surfaces are under the contact: the
  // window starts after this many longest delays and spans at least as many (the pattern of one
  // revolution averaged out).
  double min_delays_in_window = 1.0;
  double max_residual_rms = 0.35;           // ln units: a factor e^0.35 = 1.4 about the line
  // Saturation: the second half's growth rate below this fraction of the first half's, when the
  // first half grew by at least min_growth_for_saturation_check (ln units).
  double saturation_slope_ratio = 0.5;
  double min_growth_for_saturation_check = 1.0;
  // The whole window's slope and the mean of its halves' agree within this fraction of the larger
  // plus this many ln units over the window (an exponential gives the same slope on any part).
  double slope_consistency = 0.2;
  // Steady: the envelope changes by less than this (ln units, 0.02 = 2 %) over the window. A
  // forced response (G6's unbalance) looks like this, and so would a root within a few 1e-3 /s
  // of Re s = 0: the slope cannot tell them apart, so it does not stand for a root.
  double max_steady_change = 0.02;
};

struct FitValidity {
  bool valid = false;
  std::string reason;  // empty when valid
  ResponseRegime regime = ResponseRegime::transient;
  double window_start_s = 0.0, window_end_s = 0.0;
  double contact_loss_fraction = 0.0;     // of the fit window
  double delays_in_window = 0.0;          // window length / longest delay
  double residual_rms = 0.0;              // ln units
  double first_half_growth_per_s = 0.0;   // the envelope's slope over each half of the window
  double second_half_growth_per_s = 0.0;
  double final_amplitude_m = 0.0;         // envelope mean over the window's last eighth
};

// t_s/in_contact: the run's output samples (in_contact 1 or 0; empty = always in contact).
// longest_delay_s: the model's longest regenerative delay (the work revolution for G1).
FitValidity assess_fit(const EnvelopeFit& fit, std::span<const double> t_s, std::span<const double> in_contact,
                       double longest_delay_s, const FitValidityLimits& limits = {});

}  // namespace chatterlab
