#pragma once
// ISO 12085 MOTIF parameters (docs/analysis/surface.md, "MOTIF"), for open profiles.
//
// What is implemented (the standard's combination algorithm, Annex A, as summarised here):
//   1. Roughness motifs: the profile is cut at its local peaks (y[i] >= y[i-1], y[i] > y[i+1];
//      both end points also delimit motifs). A motif spans two adjacent peaks P1, P2; its valley
//      is the lowest sample between them (inclusive); its depths are H1 = y(P1) - valley,
//      H2 = y(P2) - valley, its characteristic depth T = min(H1, H2).
//   2. Two adjacent motifs (P1, P2) and (P2, P3) are combined into (P1, P3) when all four
//      conditions hold:
//        C1 envelope:      y(P2) <= max(y(P1), y(P3))  (the common peak is not above both);
//        C2 width:         x(P3) - x(P1) <= A (roughness) or B (waviness);
//        C3 enlargement:   T(P1, P3) >= max(T1, T2)    (combining never makes motifs shallower);
//        C4 relative depth: min(T1, T2) < 0.6 T(P1, P3) (one of them is small in the result).
//      Combinations are made smallest first: repeatedly the admissible pair with the smallest
//      min(T1, T2), until no pair is admissible.
//   3. R = mean of all depths H (two per motif), AR = mean motif length, Rx = largest depth.
//   4. Upper envelope = the polyline through the peaks that delimit the final roughness motifs.
//      Waviness motifs: steps 1-2 applied to the envelope's points with limit B;
//      W = mean depth, AW = mean length, Wx = largest depth; Wte = highest minus lowest point of
//      the upper envelope.
// Not implemented: the standard's optional rules for isolated exceptional peaks/valleys.
#include <cstddef>
#include <span>
#include <vector>

namespace chatterlab::surface {

struct Motifs {
  std::vector<std::size_t> boundaries;  // indices of the delimiting peaks (into the input points)
  std::vector<double> depths;           // H1, H2 of every motif, in order
  std::vector<double> lengths;          // x(P2) - x(P1) of every motif
};

// Motifs of the points (x[i], y[i]) (x increasing), combined with width limit `limit`.
Motifs combine_motifs(const std::vector<double>& x, const std::vector<double>& y, double limit);

struct MotifParameters {
  double R = 0, AR = 0, Rx = 0;   // roughness motifs (height unit, x unit, height unit)
  double W = 0, AW = 0, Wx = 0, Wte = 0;
  std::size_t roughness_motifs = 0, waviness_motifs = 0;
};

// Profile y sampled at `spacing` (mm); limits A and B in mm (ISO 12085 defaults 0.5 and 2.5).
MotifParameters motif_parameters(std::span<const double> y, double spacing, double a_mm = 0.5,
                                 double b_mm = 2.5);

// The same on the profile y[i] - (intercept + slope i) (form removal by a straight line), without
// making that profile: a 10^7-sample profile keeps its memory to the motifs themselves.
MotifParameters motif_parameters(std::span<const double> y, double intercept, double slope,
                                 double spacing, double a_mm, double b_mm);

}  // namespace chatterlab::surface
