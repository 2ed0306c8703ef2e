#pragma once
// The study kit: what every study kind uses instead of re-implementing it (docs/plugins.md,
// "Writing a study kind"). Settings tables bound to structs, the study's model with its certified
// rightmost root, simulation settings, plugins chosen by capability, plots over the grid, and the
// point's output files.
#include "chatterlab/kit/capabilities.hpp"
#include "chatterlab/kit/model.hpp"
#include "chatterlab/kit/output.hpp"
#include "chatterlab/kit/plots.hpp"
#include "chatterlab/kit/settings.hpp"
#include "chatterlab/kit/simulation.hpp"
#include "chatterlab/param_table.hpp"
#include "chatterlab/study_kind.hpp"
