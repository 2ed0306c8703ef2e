#pragma once
// Analysis `lyapunov` (MODELS.md N3/N4, largest exponent): divergence of neighbouring
// trajectories in the delay embedding. Kantz's curves (1994, all neighbours within eps) for three
// embedding dimensions x six neighbourhood sizes, Rosenstein's (1993, the nearest neighbour)
// for the same dimensions; each curve S(k) = < ln distance after k samples > with the slope of its
// automatically detected linear region. The exponent is reported only when the curves show
// exponential divergence: a linear region whose slope is the same for several dimensions and
// neighbourhood sizes, with curves for different sizes staying apart (parallel) over it, as
// they do for deterministic divergence and do not for noise, where neighbours separate at
// once. docs/analysis/chaos.md, section "Largest Lyapunov exponent".
#include <string>
#include <vector>

#include "shared/nonlinear/divergence.hpp"
#include "shared/nonlinear/kantz_scan.hpp"
#include "shared/nonlinear/nonlinear_common.hpp"
#include "chatterlab/analysis.hpp"

namespace chatterlab {

// The plugin: info(), analyse() and plot() are defined in lyapunov.cpp.
struct LyapunovMethod;
using LyapunovAnalysis = nonlinear::MethodAnalysis<LyapunovMethod>;

}  // namespace chatterlab
