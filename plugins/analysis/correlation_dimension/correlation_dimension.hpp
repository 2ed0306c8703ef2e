#pragma once
// Analysis `correlation_dimension` (MODELS.md N2): Grassberger-Procaccia correlation sums C(r)
// with a Theiler window (no self-pairs, no temporally correlated pairs), D2 from an automatically
// detected scaling region (plateau of the local slopes d ln C / d ln r), D2 versus embedding
// dimension until it saturates, a noise level that moves the scaling window, and a bootstrap
// confidence interval. docs/analysis/chaos.md, section "Correlation dimension".
#include "shared/nonlinear/correlation_sums.hpp"
#include "shared/nonlinear/nonlinear_common.hpp"
#include "chatterlab/analysis.hpp"

namespace chatterlab {

// The plugin: info(), analyse() and plot() are defined in correlation_dimension.cpp.
struct CorrelationDimensionMethod;
using CorrelationDimension = nonlinear::MethodAnalysis<CorrelationDimensionMethod>;

}  // namespace chatterlab
