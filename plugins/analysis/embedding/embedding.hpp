#pragma once
// Analysis `embedding` (MODELS.md N1): the delay from the first minimum of the average mutual
// information (autocorrelation 1/e as the reported fallback), the embedding dimension from false
// nearest neighbours (Kennel et al. 1992) cross-checked with Cao's method (E1 saturation, E2 for
// determinism), and the Theiler window from a space-time separation plot. Other analyses reuse
// its result through the study's shared context (resolve_embedding). docs/analysis/chaos.md.
#include "shared/nonlinear/embedding_choice.hpp"
#include "shared/nonlinear/nonlinear_common.hpp"
#include "chatterlab/analysis.hpp"

namespace chatterlab {

// The plugin: info(), analyse() and plot() are defined in embedding.cpp.
struct EmbeddingMethod;
using EmbeddingAnalysis = nonlinear::MethodAnalysis<EmbeddingMethod>;

}  // namespace chatterlab
