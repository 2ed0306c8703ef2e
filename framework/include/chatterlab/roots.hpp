#pragma once
// Rightmost characteristic root within a frequency band, with a certificate.
// Used by the stability_map study kind (and later by feed_risk).
//
// Method (details in framework/src/roots.cpp and docs/models/plunge_regenerative.md):
//   1. Newton (with E') from the model's initial guesses; roots are mapped to Im >= 0,
//      deduplicated, and declared neutral roots are removed. Guesses that can no longer lead
//      to the rightmost root after a few steps are dropped (the certificate covers that).
//   2. Certificate: the argument principle counts the zeros of E on the rectangle
//      [certified_real_part, real_part_bound] x [-band, band] (phase tracked adaptively along
//      the boundary). The count minus the known zeros inside (neutral roots, roots just outside
//      the band) must be 0: then no root in the band lies right of certified_real_part.
//   3. Repair: if the count says zeros are missing, the rectangle is subdivided until each
//      missing zero is isolated and located by Newton; then the search is certified again.
#include <string>
#include <vector>

#include "chatterlab/characteristic.hpp"

namespace chatterlab {

struct RootSearchOptions {
  double max_frequency_hz = 0.0;  // band |Im s| <= 2 pi max_frequency_hz; > 0 required
  double newton_relative_tolerance = 1e-13;
  int max_newton_iterations = 60;
  // Rounds of "locate the zeros the count says were missed, then certify again". 0 disables the
  // repair: a missed root then shows as certified = false (used by tests of the certificate).
  int max_repair_rounds = 3;
  // Work budget per search (evaluations of E); beyond it the result is returned uncertified.
  long max_function_evaluations = 3'000'000;
  // Warm start: approximate roots of a nearby parameter set (a neighbouring search's
  // RightmostRoot::approximate_roots) as Newton's guesses in place of the model's lattice
  // guesses. The certificate is the same; when it fails from the warm guesses, the search is
  // redone from the model's own guesses, so a warm start can only save work, never lose a root.
  // The result then depends on the warm guesses too (the same root, converged from elsewhere:
  // equal to rounding): choose their source by the data, not by thread timing.
  const std::vector<Complex>* warm_start = nullptr;
  // Fill RightmostRoot::approximate_roots (for warm-starting a neighbouring search).
  bool keep_approximate_roots = false;
};

struct RightmostRoot {
  Complex root;             // Im >= 0
  int roots_found = 0;      // distinct roots (upper half plane) located in the band; roots that
                            // cannot be the rightmost are not polished, so this is a lower bound
  // Certificate: argument-principle count of zeros of E(s) in the rectangle
  // Re s in [certified_real_part, real_part_bound], |Im s| <= band, minus neutral roots.
  bool certified = false;
  double certified_real_part = 0.0;  // no root in the band has Re s above this (when certified)
  int zeros_right_of_contour = -1;   // unknown zeros counted right of the contour (0 when certified)
  int function_evaluations = 0;
  std::string certificate;  // human-readable outcome, e.g. "ok: 0 zeros in Re s > -1.23e-2"
  int repaired_roots = 0;            // roots the guesses missed and the repair step located
  int neutral_roots_excluded = 0;    // declared neutral roots met by Newton and dropped
  bool warm_started = false;         // certified from options.warm_start (no cold retry needed)
  // With options.keep_approximate_roots: every root located plus where each Newton candidate
  // dropped as "cannot be the rightmost" stood (Im >= 0, sorted by Im): warm-start guesses for a
  // search at nearby parameters.
  std::vector<Complex> approximate_roots;
};

// Throws PointFailure when no root could be located at all (or the options are invalid);
// nothing else escapes. Thread-safe and deterministic: the result depends only on the inputs.
RightmostRoot find_rightmost_root(const CharacteristicFunction& characteristic,
                                  const RootSearchOptions& options);

}  // namespace chatterlab
