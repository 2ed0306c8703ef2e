"""Models: validation, the certified rightmost characteristic root and time-domain simulation.

A model is a plain dict, exactly a study's [model] table: ``{"type": "plunge_regenerative",
"wheel_speed_rpm": 1450.0, ...}`` (``chatterlab.describe("plunge_regenerative")`` lists the keys).
Any registered model works, including models of libraries loaded with ``chatterlab.load_plugin``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Optional, Sequence

import numpy as np

from . import _chatterlab

__all__ = ["RootResult", "EnvelopeFit", "SimulationResult", "validate_model", "rightmost_root",
           "simulate", "fit_envelope"]


def validate_model(model: Mapping[str, Any]) -> dict:
    """The model table as a study validates it: ``type`` first, then every parameter with its
    default filled in. Raises chatterlab.InputError with the command line's message for an unknown
    type, an unknown key or a value outside its limits."""
    return _chatterlab.validate_model(model)


@dataclass(frozen=True)
class RootResult:
    """The rightmost characteristic root of a model's linear stability (MODELS.md G1: roots of the
    characteristic equation with both regenerations), found and certified the way the
    ``stability_map`` study kind does it: the same numbers as its results.csv row.

    Attributes:
        root: the rightmost root s [1/s] with Im s >= 0.
        growth_rate_per_s: Re s; > 0 means the vibration grows (chatter).
        chatter_frequency_hz: |Im s| / 2 pi.
        growth_rate_per_wheel_rev: G3's Tg Re s / 2 pi for models with a wheel, else None.
        stable: Re s < 0.
        certified: the argument principle proved that no root in the band lies right of
            ``certified_real_part_per_s``.
        certified_real_part_per_s: the certified bound on Re s.
        certificate: the certificate in words (why not, when ``certified`` is False).
        zeros_right_of_contour: zeros counted right of the contour that were not located.
        roots_found, repaired_roots, neutral_roots_excluded, function_evaluations: search
            statistics.
        max_frequency_hz: the search band |Im s| <= 2 pi max_frequency_hz that was used.
        model: the validated model table (defaults filled in).
    """

    root: complex
    growth_rate_per_s: float
    chatter_frequency_hz: float
    growth_rate_per_wheel_rev: Optional[float]
    stable: bool
    certified: bool
    certified_real_part_per_s: float
    certificate: str
    zeros_right_of_contour: int
    roots_found: int
    repaired_roots: int
    neutral_roots_excluded: int
    function_evaluations: int
    max_frequency_hz: float
    model: dict = field(repr=False)


def rightmost_root(model: Mapping[str, Any], max_frequency_hz: Optional[float] = None, *,
                   max_newton_iterations: Optional[int] = None,
                   newton_relative_tolerance: Optional[float] = None,
                   max_function_evaluations: Optional[int] = None) -> RootResult:
    """The certified rightmost characteristic root of ``model`` (a [model] table as a dict).

    max_frequency_hz: search band |Im s| <= 2 pi max_frequency_hz; None: 4 x the model's
        highest structural natural frequency (the stability_map default).
    The keyword settings are the [stability] table's (``chatterlab.describe("stability_map")``);
    None leaves their defaults.

    Raises chatterlab.InputError for a model table that does not validate or a model without a
    characteristic function, chatterlab.PointFailure when no root could be located. The GIL is
    released while the root is searched, so threads may search several models at once.
    """
    stability = {key: value for key, value in (("max_newton_iterations", max_newton_iterations),
                                                ("newton_relative_tolerance", newton_relative_tolerance),
                                                ("max_function_evaluations", max_function_evaluations))
                 if value is not None}
    return RootResult(**_chatterlab.rightmost_root(model, max_frequency_hz, stability))


@dataclass(frozen=True)
class EnvelopeFit:
    """Growth of a vibration from its envelope (chatterlab/dynamics.hpp fit_envelope): the
    envelope is half the peak-to-peak swing of each period of the dominant frequency, and
    ln(envelope) is fitted by least squares over [start_s, end_s]."""

    growth_rate_per_s: float
    intercept: float
    start_s: float
    end_s: float
    residual_rms: float
    t_s: np.ndarray = field(repr=False)
    envelope: np.ndarray = field(repr=False)


def fit_envelope(t_s: Sequence[float], x: Sequence[float], start_s: float, end_s: float,
                 min_frequency_hz: float = 0.0) -> EnvelopeFit:
    """Growth rate [1/s] of x(t) (uniform samples) over [start_s, end_s]; spectral peaks below
    min_frequency_hz are not taken for the dominant frequency. ValueError for fewer than 64
    samples or 8 periods in the window."""
    return EnvelopeFit(**_chatterlab.fit_envelope(t_s, x, start_s, end_s, min_frequency_hz))


@dataclass(frozen=True)
class SimulationResult:
    """A time-domain simulation by the dynamics engine (docs/dynamics.md). The series are numpy
    arrays sampled at t_s = i / sample_rate_hz up to ``end_time_s``; surfaces are radius removed
    so far [m]."""

    t_s: np.ndarray = field(repr=False)
    displacement_m: np.ndarray = field(repr=False)
    force_n: np.ndarray = field(repr=False)
    depth_of_cut_m: np.ndarray = field(repr=False)
    infeed_m: np.ndarray = field(repr=False)
    wheel_speed_rpm: np.ndarray = field(repr=False)
    work_speed_rpm: np.ndarray = field(repr=False)
    wheel_surface_at_contact_m: np.ndarray = field(repr=False)
    work_surface_at_contact_m: np.ndarray = field(repr=False)
    in_contact: np.ndarray = field(repr=False)
    #: surfaces at the snapshot times: dicts of t_s, angle_deg, wheel_surface_m, work_surface_m
    snapshots: list = field(repr=False)
    contact_loss_intervals_s: list = field(repr=False)
    contact_loss_time_s: float
    diverged: bool
    end_time_s: float
    status: str
    diagnostics: list
    steps: int
    rhs_evaluations: int
    contact_events: int
    #: how the run was integrated, e.g. "fixed step 1.6667e-04 s, exact exponential (linear form)"
    method: str
    fixed_step_s: float  # the fixed-step engine's step; 0 for the SUNDIALS routes
    model: dict = field(repr=False)

    def growth_rate(self, start_s: Optional[float] = None, end_s: Optional[float] = None,
                    min_frequency_hz: float = 10.0) -> EnvelopeFit:
        """The displacement's envelope growth rate over [start_s, end_s] (default: the second
        half of the run, as the ``simulate`` study kind fits it)."""
        start = 0.5 * self.end_time_s if start_s is None else start_s
        end = self.end_time_s if end_s is None else end_s
        return fit_envelope(self.t_s, self.displacement_m, start, end, min_frequency_hz)

    def to_dataframe(self):
        """The series as a pandas DataFrame (needs pandas)."""
        import pandas  # noqa: PLC0415 (optional dependency)
        return pandas.DataFrame({name: getattr(self, name) for name in _SERIES})


_SERIES = ("t_s", "displacement_m", "force_n", "depth_of_cut_m", "infeed_m", "wheel_speed_rpm",
           "work_speed_rpm", "wheel_surface_at_contact_m", "work_surface_at_contact_m", "in_contact")
_D = _chatterlab.simulation_defaults()


def simulate(model: Mapping[str, Any], duration_s: float, *,
             sample_rate_hz: float = _D["sample_rate_hz"],
             initial_displacement_m: float = _D["initial_displacement_m"],
             initial_velocity_m_per_s: float = _D["initial_velocity_m_per_s"],
             initial_waviness_m: float = _D["initial_waviness_m"],
             seed: int = _D["seed"],
             infeed_rate_m_per_s: float = _D["infeed_rate_m_per_s"],
             one_sided_contact: bool = _D["one_sided_contact"],
             wheel_contact_arc_deg: float = _D["wheel_contact_arc_deg"],
             work_contact_arc_deg: float = _D["work_contact_arc_deg"],
             snapshot_times_s: Sequence[float] = (),
             relative_tolerance: float = _D["relative_tolerance"],
             integrator: str = _D["integrator"],
             fixed_steps_per_wave: float = _D["fixed_steps_per_wave"],
             samples_per_wave: float = _D["samples_per_wave"],
             max_steps_per_wave: float = _D["max_steps_per_wave"],
             divergence_limit_m: float = _D["divergence_limit_m"],
             wheel_speed: Optional[Mapping[str, Any]] = None,
             work_speed: Optional[Mapping[str, Any]] = None) -> SimulationResult:
    """Integrates the model's time-domain form (MODELS.md G1, G5-G7) with the dynamics engine:
    wheel and work surfaces stored by rotation angle, one-sided contact; the fixed-step engine
    (integrator "fixed_step", the default) or the adaptive SUNDIALS reference routes
    ("explicit_runge_kutta", "adams"; docs/dynamics.md).

    The settings are the engine's (chatterlab/dynamics.hpp SimulationSettings, defaults shown);
    they match the ``simulate`` study kind's [simulation] keys of the same names.
    wheel_speed / work_speed: None (the model's speed), a modulation
        ``{"modulation": "sinusoidal" | "triangular" | "square", "amplitude_ratio": 0.1,
        "frequency_hz": 2.0}`` around the model's speed (or "mean_rpm"), or a schedule
        ``{"schedule": [[t_s, rpm], ...]}`` (piecewise linear, held after the last row).

    Raises chatterlab.InputError for a model that does not validate or has no time-domain form,
    and for settings outside their limits, with the command line's message for that key of the
    simulate kind's [simulation] table ("simulate: simulation.duration_s = -1 [s]: out of range,
    must be > 0 ..."); ValueError for settings only the engine checks (samples_per_wave,
    max_steps_per_wave, speed laws); chatterlab.PointFailure when the integrator fails. A diverging response is not an error: ``diverged`` and ``status`` say so.
    The GIL is released during the integration.
    """
    table = {"duration_s": duration_s, "sample_rate_hz": sample_rate_hz,
             "initial_displacement_m": initial_displacement_m, "initial_velocity_m_per_s": initial_velocity_m_per_s,
             "initial_waviness_m": initial_waviness_m, "seed": seed, "infeed_rate_m_per_s": infeed_rate_m_per_s,
             "one_sided_contact": one_sided_contact, "wheel_contact_arc_deg": wheel_contact_arc_deg,
             "work_contact_arc_deg": work_contact_arc_deg, "relative_tolerance": relative_tolerance,
             "integrator": integrator, "fixed_steps_per_wave": fixed_steps_per_wave,
             "divergence_limit_m": divergence_limit_m}
    if len(snapshot_times_s):
        table["snapshot_times_s"] = list(snapshot_times_s)
    _chatterlab.check_simulation(model, table)
    settings = _chatterlab._SimulationSettings(
        duration_s=duration_s, sample_rate_hz=sample_rate_hz, initial_displacement_m=initial_displacement_m,
        initial_velocity_m_per_s=initial_velocity_m_per_s, initial_waviness_m=initial_waviness_m, seed=seed,
        infeed_rate_m_per_s=infeed_rate_m_per_s, one_sided_contact=one_sided_contact,
        wheel_contact_arc_deg=wheel_contact_arc_deg, work_contact_arc_deg=work_contact_arc_deg,
        snapshot_times_s=list(snapshot_times_s), relative_tolerance=relative_tolerance, integrator=integrator,
        fixed_steps_per_wave=fixed_steps_per_wave, samples_per_wave=samples_per_wave, max_steps_per_wave=max_steps_per_wave,
        divergence_limit_m=divergence_limit_m)
    return SimulationResult(**_chatterlab.simulate(model, settings, wheel_speed, work_speed))
