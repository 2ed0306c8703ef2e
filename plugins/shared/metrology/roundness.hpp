#pragma once
// Roundness of a closed (circumferential) profile about four reference circles (ISO 12181;
// docs/analysis/surface.md, MODELS.md W1/E). The profile is radial deviation r_i at angle
// theta_i, small against the radius, so a circle of centre (a, b) and radius R reads as the
// limacon R + a cos theta + b sin theta (the linearisation every roundness instrument uses):
//   least_squares (LSCI): min sum d_i^2, d_i = r_i - R - a cos - b sin (linear least squares);
//   minimum_zone (MZCI): min over (a, b) of max d - min d (two concentric circles);
//   minimum_circumscribed (MCCI): min over (a, b) of max (r_i - a cos - b sin);
//   maximum_inscribed (MICI): max over (a, b) of min (r_i - a cos - b sin).
// The last three are linear programs in (a, b) and the radii; they are solved exactly (simplex on
// the dual, with constraint generation over the samples: solve on a subset, add every violated
// sample, repeat), and certified: the final centre satisfies every sample's constraint and the
// primal and dual objectives agree (`certified`, `duality_gap`).
// Deviations from each reference: RONt = peak-to-valley, RONp = largest peak above the reference
// circle, RONv = deepest valley below it (>= 0), RONq = rms of the deviations about their mean
// radius with that reference's centre.
//
// Memory: a constant number of bytes per sample beside the radii (issue 23: a 10^7-sample
// revolution within 48 bytes per sample, docs/performance.md): cos and sin of equally spaced
// angles are computed when read, not stored; deviations are summed as they are computed; the
// least-squares deviations are an array only when asked for.
#include <span>
#include <string>
#include <vector>

namespace chatterlab::surface {

struct ReferenceCircle {
  std::string name;         // least_squares, minimum_zone, minimum_circumscribed, maximum_inscribed
  double centre_x = 0, centre_y = 0;  // a, b: centre offset, profile unit
  double radius = 0;        // R: the reference radius (offset of the limacon), profile unit
  double RONt = 0, RONp = 0, RONv = 0, RONq = 0;
  bool certified = true;    // LP optimum verified on every sample (always true for LS)
  double duality_gap = 0;   // |primal - dual| objective of the LP
};

struct Roundness {
  ReferenceCircle least_squares, minimum_zone, minimum_circumscribed, maximum_inscribed;
  // r_i minus the least-squares circle; empty unless Deviations::least_squares was asked for.
  std::vector<double> least_squares_deviations;
};

// Which circles to compute: all four, or least squares and minimum zone only (the other two
// are then left default, name empty).
enum class References { all, least_squares_and_zone };

// Whether to return the least-squares deviations (an array of the samples' size).
enum class Deviations { none, least_squares };

// `radius`: deviations r_i; `angle_rad`: theta_i (any order, must span more than half a turn in
// every direction: the MC/MI/MZ programs need samples all round). Throws std::invalid_argument
// for fewer than 4 samples or mismatched sizes.
Roundness roundness(std::span<const double> radius, std::span<const double> angle_rad,
                    References references = References::all,
                    Deviations deviations = Deviations::none);

// Equally spaced samples of one revolution: theta_i = 2 pi i / N.
Roundness roundness(std::span<const double> radius, References references = References::all,
                    Deviations deviations = Deviations::none);

// Deviations from one reference given its centre: r_i - a cos theta_i - b sin theta_i - R.
std::vector<double> deviations(const ReferenceCircle& circle, std::span<const double> radius,
                               std::span<const double> angle_rad);

std::vector<double> equally_spaced_angles(std::size_t n);

// Smallest value of the linear program  min e.x  s.t.  A_j . x >= c_j  (j = 0..n-1), x free in
// R^m (m <= 4), by the simplex method on its dual  max c.y  s.t.  sum_j y_j A_j = e, y >= 0
// (Bland's rule). Exposed for tests. Returns x, or an empty vector when the dual is infeasible
// on these columns (the primal is unbounded).
struct LinearProgramResult {
  std::vector<double> x;
  double primal_objective = 0, dual_objective = 0;
};
LinearProgramResult solve_covering_lp(const std::vector<std::vector<double>>& rows,
                                      const std::vector<double>& c, const std::vector<double>& e);

}  // namespace chatterlab::surface
