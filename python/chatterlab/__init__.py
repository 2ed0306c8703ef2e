"""chatterlab: chatter and stability analysis for grinding, from Python (docs/python.md).

Models and studies are plain Python data, exactly the tables of a study file:

    import chatterlab
    model = {"type": "plunge_regenerative", "wheel_speed_rpm": 1450.0, ...}
    root = chatterlab.rightmost_root(model)          # certified rightmost root, as stability_map
    run = chatterlab.run_study("studies/default.toml")
    run.results                                      # results.csv as a pandas DataFrame

Functions:
    rightmost_root, simulate, validate_model, fit_envelope          models (chatterlab.models)
    analyse, embedding, correlation_dimension, lyapunov,             analyses on numpy arrays
    lyapunov_spectrum, surrogates, surface_profile, waviness,        (chatterlab.analysis)
    roundness, error_separation
    load_study, run_study, init_study, shipped_studies,              studies (chatterlab.studies)
    feed_plan, feed_risk
    plugins, describe, load_plugin                                   the registries

Errors carry the command line's messages: InputError (a ValueError: bad input, naming the key,
value and limit), PointFailure (a RuntimeError: a numerical failure), PlotError.
"""

from ._chatterlab import InputError, PlotError, PointFailure, __version__

for _error in (InputError, PlotError, PointFailure):
    _error.__module__ = __name__  # tracebacks say chatterlab.InputError, where users catch it
del _error
from .analysis import (AnalysisResult, analyse, correlation_dimension, embedding, error_separation, lyapunov,
                       lyapunov_spectrum, roundness, surface_profile, surrogates, waviness)
from .catalog import describe, load_plugin, plugins
from .models import (EnvelopeFit, RootResult, SimulationResult, fit_envelope, rightmost_root, simulate,
                     validate_model)
from .studies import (RunResult, Study, StudyTemplate, feed_plan, feed_risk, init_study, load_study, run_study,
                      shipped_studies)

__all__ = [
    "__version__", "InputError", "PointFailure", "PlotError",
    "RootResult", "SimulationResult", "EnvelopeFit", "rightmost_root", "simulate", "validate_model", "fit_envelope",
    "AnalysisResult", "analyse", "embedding", "correlation_dimension", "lyapunov", "lyapunov_spectrum",
    "surrogates", "surface_profile", "waviness", "roundness", "error_separation",
    "Study", "RunResult", "StudyTemplate", "load_study", "run_study", "init_study", "shipped_studies",
    "feed_plan", "feed_risk",
    "plugins", "describe", "load_plugin",
]
