"""What a call from Python costs beyond the analysis (issue 24: numpy input of 10^7 samples, call
overhead under 1 % of the analysis time). Not a test (timing is not a test): run it by hand,
numbers in docs/performance.md ("Python API").

    PYTHONPATH=build/ci/python /usr/bin/python3 tests/bench/python_call_bench.py [repeats [analysis ...]]

For each analysis, on a C-contiguous float64 array of 10^7 samples (signals: a growing 73 Hz
chatter tone in noise at 10 kHz; profiles: 4 mm and 0.05 mm waves plus noise at 0.5 um spacing,
as tests/bench/surface_memory.sh): the wall time of the Python call (chatterlab.analyse: argument checks,
parameter validation, the analysis, the result as Python objects with numpy curves) against the
analysis' own time inside the call (timing["analyse_s"]); overhead = wall - analysis: argument
checks, handing the samples over (input_s: the analysis reads the numpy buffer through a view,
no copy; the script checks that numpy did not convert the array either) and the result's
conversion to Python objects (result_s, measured inside the call: long series are moved into
numpy arrays, chatterlab/analysis_arrays.hpp). Medians over `repeats` calls (default 3).
"""

import statistics
import sys
import time

import numpy as np

import chatterlab

SAMPLES = 10_000_000
RATE_HZ = 10_000.0
SPACING_MM = 0.0005
SIGNAL = {"sample_rate_hz": RATE_HZ}
# An open profile in um (5 m of it), lc = 0.8 mm.
PROFILE = {"sample_interval": SPACING_MM, "sample_unit": "mm", "cutoff_mm": 0.8}
CASES = [
    # (analysis, input, sampling and parameters, what the case shows)
    ("surface_profile", "profile", PROFILE, "Gaussian waviness + MOTIF, open profile"),
    ("window_features", "signal", {**SIGNAL, "window_samples": 10}, "10^6 windows: 4 x 10^6 result values"),
    ("window_features", "signal", {**SIGNAL, "window_samples": 1000}, "10^4 windows"),
    ("rbf_density", "signal", {**SIGNAL, "hop_samples": 10_000}, "10^3 windows of the density criterion"),
    ("rbf_density", "signal", SIGNAL, "hop 10 (default): 10^6 windows"),
]
# Not here: the phase-space analyses (embedding, lyapunov) on 10^7 samples did not finish within
# 15-25 minutes on the shared 2-core machine; their cost grows faster than the signal, so the copy
# is an even smaller part of it.


def main() -> None:
    repeats = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    only = sys.argv[2:]  # analysis names to run (default: every case)
    rng = np.random.default_rng(1)
    t = np.arange(SAMPLES) / RATE_HZ
    x_mm = np.arange(SAMPLES) * SPACING_MM
    inputs = {
        "signal": np.sin(2 * np.pi * 73.0 * t) * np.exp(0.05 * t) + 0.1 * rng.standard_normal(SAMPLES),
        "profile": 1.5 * np.sin(2 * np.pi * x_mm / 4.0) + 0.3 * np.sin(2 * np.pi * x_mm / 0.05)
        + 0.1 * rng.standard_normal(SAMPLES),
    }
    for x in inputs.values():
        assert x.flags["C_CONTIGUOUS"] and x.dtype == np.float64
    print(f"{SAMPLES} samples; medians of {repeats} calls")
    print(f"{'analysis':16} {'case':38} {'wall s':>9} {'analysis s':>10} {'input s':>8} {'result s':>9} "
          f"{'overhead s':>10} {'overhead %':>10}")
    for name, kind, params, case in CASES:
        if only and name not in only:
            continue
        walls, analyses, handed_over, results = [], [], [], []
        result = None
        for _ in range(repeats):
            # The previous call's result is freed before the clock starts: freeing 80 MB of a
            # filtered profile is not part of the next call.
            result = None
            start = time.perf_counter()
            result = chatterlab.analyse(name, inputs[kind], **params)
            walls.append(time.perf_counter() - start)
            analyses.append(result.timing["analyse_s"])
            handed_over.append(result.timing["input_s"])
            results.append(result.timing.get("result_s", float("nan")))  # absent before 8c53b04
            assert not result.timing["input_converted"], "numpy copied the input"
        overheads = [w - a for w, a in zip(walls, analyses)]
        wall, analysis, handed, converted, overhead = (
            statistics.median(v) for v in (walls, analyses, handed_over, results, overheads))
        print(f"{name:16} {case:38} {wall:9.3f} {analysis:10.3f} {handed:8.2g} {converted:9.2g} {overhead:10.4f} "
              f"{100 * overhead / analysis:10.3f}", flush=True)


if __name__ == "__main__":
    main()
