"""Analyses on numpy arrays: the registered analysis plugins (chaos: MODELS.md N; surface
metrology: W, E), with the parameters and results of a study's [analysis.<name>] table, and
multi-probe error separation through its study kind.

Signals are one-dimensional arrays of float64 (other dtypes and strided views are converted once
by numpy); C-contiguous float64 arrays are read in place. The GIL is released while an analysis
runs.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Mapping as MappingABC
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, Iterator, Mapping, Optional, Sequence, Union

import numpy as np

from . import _chatterlab
from .studies import RunResult, run_study

__all__ = ["AnalysisResult", "analyse", "embedding", "correlation_dimension", "lyapunov",
           "lyapunov_spectrum", "surrogates", "surface_profile", "waviness", "roundness",
           "error_separation"]

PathLike = Union[str, os.PathLike]


@dataclass(frozen=True)
class AnalysisResult(MappingABC):
    """The result of one analysis: the JSON object its plugin returns, as a read-only mapping
    (``result["delay_samples"]``, ``dict(result)``), with curves as numpy arrays: series with a
    value per window or sample (window features, detector scores, a bool ``alarm`` array) moved
    from the library without conversion, shorter curves converted in one pass. Scalar estimates
    follow chatterlab's convention ``{"value", "ci_low", "ci_high", "quality", "reason"}``.

    Attributes:
        name: the analysis plugin.
        result: the plugin's result.
        timing: seconds spent handing the samples to the analysis (``input_s``: a view of the
            array, no copy), whether numpy had to convert the input to a C-contiguous float64
            array first (``input_converted``), seconds in the analysis itself (``analyse_s``)
            and in turning its result into Python objects (``result_s``); the rest of a call
            is Python.
    """

    name: str
    result: dict = field(repr=False)
    timing: dict = field(repr=False, compare=False)

    def __getitem__(self, key: str) -> Any:
        return self.result[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.result)

    def __len__(self) -> int:
        return len(self.result)

    def __repr__(self) -> str:
        return f"AnalysisResult({self.name!r}, keys={list(self.result)})"


def _with_arrays(value: Any) -> Any:
    """Rectangular lists of curves as 2-D numpy arrays (the compiled module already returns every
    list of numbers as a float64 array)."""
    if isinstance(value, dict):
        return {key: _with_arrays(item) for key, item in value.items()}
    if isinstance(value, list) and value:
        items = [_with_arrays(v) for v in value]
        if all(isinstance(v, np.ndarray) and v.ndim == 1 and len(v) == len(items[0]) for v in items):
            return np.vstack(items)
        return items
    return value


def _interval(sample_rate_hz: Optional[float], sample_interval: Optional[float]) -> float:
    if sample_rate_hz is not None and sample_interval is not None:
        raise ValueError("give sample_rate_hz or sample_interval, not both")
    if sample_rate_hz is not None:
        if not sample_rate_hz > 0:
            raise _chatterlab.InputError(f"sample_rate_hz = {sample_rate_hz}: must be > 0")
        return 1.0 / sample_rate_hz
    return 1.0 if sample_interval is None else sample_interval


def analyse(name: str, values: Any, *, sample_rate_hz: Optional[float] = None,
            sample_interval: Optional[float] = None, sample_unit: str = "s", closed: bool = False,
            context: Optional[Mapping[str, Any]] = None, series_name: str = "",
            plot_dir: Optional[PathLike] = None, **params: Any) -> AnalysisResult:
    """Runs the registered analysis ``name`` (``chatterlab.plugins()``) on a one-dimensional array.

    sample_rate_hz or sample_interval: the sampling (default: one sample per unit, so rates come
        out per sample); sample_unit: "s" for signals, "mm" for open profiles, "deg"/"rad" for
        closed ones (closed=True: one revolution, the values wrap around).
    context: results of analyses run before (by name), e.g. {"embedding": embedding(x)} gives
        lyapunov the embedding's delay and dimension.
    plot_dir: also draw the analysis' plots (PNG + SVG) there.
    params: the analysis' parameters (``chatterlab.describe(name)``), as in a study's
        [analysis.<name>] table.

    Raises chatterlab.InputError naming the parameter and its limit, or when the series cannot be
    analysed as configured (too short, constant, NaN); chatterlab.PointFailure for a numerical
    failure.
    """
    earlier = None if context is None else {key: dict(value) for key, value in context.items()}
    result, timing = _chatterlab.analyse(name, values, _interval(sample_rate_hz, sample_interval), sample_unit,
                                         closed, params, earlier, series_name,
                                         None if plot_dir is None else os.fspath(plot_dir))
    return AnalysisResult(name, _with_arrays(result), timing)


def embedding(x: Any, *, sample_rate_hz: Optional[float] = None, **params: Any) -> AnalysisResult:
    """Delay-embedding parameters (MODELS.md N1): the delay by average mutual information, the
    dimension by false nearest neighbours and Cao's method, the Theiler window by space-time
    separation. params: ``chatterlab.describe("embedding")``."""
    return analyse("embedding", x, sample_rate_hz=sample_rate_hz, **params)


def correlation_dimension(x: Any, *, sample_rate_hz: Optional[float] = None,
                          context: Optional[Mapping[str, Any]] = None, **params: Any) -> AnalysisResult:
    """Correlation dimension D2 (N2, Grassberger-Procaccia with a Theiler window) from an
    automatically detected scaling region, over embedding dimensions until it saturates."""
    return analyse("correlation_dimension", x, sample_rate_hz=sample_rate_hz, context=context, **params)


def lyapunov(x: Any, *, sample_rate_hz: Optional[float] = None, context: Optional[Mapping[str, Any]] = None,
             **params: Any) -> AnalysisResult:
    """Largest Lyapunov exponent (N3, N4) by Rosenstein's and Kantz's divergence methods, per
    sample and, with sample_rate_hz, per second."""
    return analyse("lyapunov", x, sample_rate_hz=sample_rate_hz, context=context, **params)


def lyapunov_spectrum(x: Any, *, sample_rate_hz: Optional[float] = None,
                      context: Optional[Mapping[str, Any]] = None, **params: Any) -> AnalysisResult:
    """Lyapunov spectrum (N3) from local Jacobians with QR re-orthonormalisation; spurious
    exponents flagged by time reversal."""
    return analyse("lyapunov_spectrum", x, sample_rate_hz=sample_rate_hz, context=context, **params)


def surrogates(x: Any, *, sample_rate_hz: Optional[float] = None, context: Optional[Mapping[str, Any]] = None,
               **params: Any) -> AnalysisResult:
    """IAAFT surrogate test for determinism (N4): nonlinear prediction error rank test and
    time-reversal asymmetry."""
    return analyse("surrogates", x, sample_rate_hz=sample_rate_hz, context=context, **params)


def surface_profile(profile: Any, *, spacing_mm: Optional[float] = None, closed: bool = False,
                    unit: str = "um", plot_dir: Optional[PathLike] = None, **params: Any) -> AnalysisResult:
    """Surface metrology of one profile (MODELS.md W1, W2; docs/analysis/surface.md): ISO Gaussian
    or robust filter, waviness parameters, MOTIF (open profiles), roundness about the LS, MZ, MC
    and MI circles and Wz|f bands (closed profiles).

    An open profile needs spacing_mm (sample spacing) and cutoff_mm; a closed one (closed=True)
    is one revolution of equally spaced samples (cutoff_upr, default 50 UPR). unit: of the
    values, "um", "mm" or "m". Besides the study kind's summary, the result holds the filtered
    (waviness) profile ``waviness_um``, one value per input sample, form included (the
    roughness profile is the input, in um, minus it)."""
    if closed:
        if spacing_mm is not None:
            raise ValueError("a closed profile is one revolution: give no spacing_mm")
        n = len(profile)
        return analyse("surface_profile", profile, sample_interval=360.0 / max(n, 1), sample_unit="deg",
                       closed=True, unit=unit, plot_dir=plot_dir, **params)
    if spacing_mm is None:
        raise ValueError("an open profile needs spacing_mm (the distance between samples)")
    return analyse("surface_profile", profile, sample_interval=spacing_mm, sample_unit="mm", unit=unit,
                   plot_dir=plot_dir, **params)


def waviness(profile: Any, spacing_mm: float, cutoff_mm: float, *, unit: str = "um",
             **params: Any) -> AnalysisResult:
    """Waviness parameters of an open profile (W1): surface_profile with a cut-off wavelength."""
    return surface_profile(profile, spacing_mm=spacing_mm, unit=unit, cutoff_mm=cutoff_mm, **params)


def roundness(profile: Any, *, unit: str = "um", cutoff_upr: float = 50.0, **params: Any) -> AnalysisResult:
    """Roundness of one revolution (W1, W2): surface_profile of a closed profile, deviations
    about the least-squares, minimum-zone, minimum-circumscribed and maximum-inscribed circles."""
    return surface_profile(profile, closed=True, unit=unit, cutoff_upr=cutoff_upr, **params)


def error_separation(probes: Any, angles_deg: Sequence[float], *, method: str = "frequency",
                     probes_table: Optional[Mapping[str, Any]] = None,
                     separation: Optional[Mapping[str, Any]] = None,
                     out: Optional[PathLike] = None, **run_options: Any) -> RunResult:
    """Roundness and spindle error motion from 2-8 probes (MODELS.md E1-E5,
    docs/analysis/error_separation.md), through the ``error_separation`` study kind.

    probes: array of shape (samples per revolution, probes), one column per probe, in um,
    sampled synchronously over one revolution. angles_deg: the probe angles. method and
    probes_table: the [probes] table (method, weights ...); separation: the [separation] table.
    Returns the run (``results`` row: roundness_um, ...; ``table(...)``: the separated profile,
    spindle motion and transfer functions; ``summary()``). run_options: as run_study.
    """
    data = np.asarray(probes, dtype=np.float64)
    if data.ndim != 2 or data.shape[1] < 2:
        raise ValueError(f"probes: expected an array of shape (samples, probes) with 2-8 probes, not {data.shape}")
    directory = Path(tempfile.mkdtemp(prefix="chatterlab-error-separation-"))
    names = [f"probe_{i}" for i in range(data.shape[1])]
    file = directory / "probes.csv"
    np.savetxt(file, data, delimiter=",", header=",".join(names), comments="", fmt="%.17g")
    probes_settings: Dict[str, Any] = {"angles_deg": list(angles_deg), "method": method}
    probes_settings.update(probes_table or {})
    document: Dict[str, Any] = {
        "study": {"kind": "error_separation", "name": "error separation"},
        "input": {"file": os.fspath(file), "columns": names, "samples_per_rev": int(data.shape[0])},
        "probes": probes_settings,
    }
    if separation:
        document["separation"] = dict(separation)
    return run_study(document, out if out is not None else directory / "out", **run_options)
