#pragma once
// Rightmost characteristic root within a frequency band, with a certificate.
// Used by the stability_map study kind (and later by feed_risk).
#include <string>

#include "chatterlab/characteristic.hpp"

namespace chatterlab {

struct RootSearchOptions {
  double max_frequency_hz = 0.0;  // band |Im s| <= 2 pi max_frequency_hz; > 0 required
  double newton_relative_tolerance = 1e-13;
  int max_newton_iterations = 60;
};

struct RightmostRoot {
  Complex root;             // Im >= 0
  int roots_found = 0;      // distinct roots (upper half plane) located in the band
  // Certificate: argument-principle count of zeros of E(s) in the rectangle
  // Re s in [certified_real_part, real_part_bound], |Im s| <= band, minus neutral roots.
  bool certified = false;
  double certified_real_part = 0.0;  // no root in the band has Re s above this (when certified)
  int zeros_right_of_contour = -1;   // the count (0 when certified)
  int function_evaluations = 0;
  std::string certificate;  // human-readable outcome, e.g. "ok: 0 zeros in Re s > -1.23e-2"
};

// Throws PointFailure when no root could be located at all.
RightmostRoot find_rightmost_root(const CharacteristicFunction& characteristic,
                                  const RootSearchOptions& options);

}  // namespace chatterlab
