"""Analyses on numpy arrays: the same results as a study's [analysis] (to 1e-12), the known
answers of the Henon map, metrology and error separation on synthetic profiles, input checks."""

import math

import numpy as np
import pytest

import chatterlab
from conftest import run_cli, toml_text


def plain(value):
    """An analysis result as JSON-like data (numpy arrays back to lists) for comparisons."""
    if isinstance(value, dict) or isinstance(value, chatterlab.AnalysisResult):
        return {key: plain(item) for key, item in value.items()}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, list):
        return [plain(item) for item in value]
    return value


def assert_same(actual, expected, where="result"):
    """Equal structure, text and flags; numbers equal to 1e-12 relative. Not to the last bit: the
    embedding's Cao sums are an OpenMP reduction whose order varies from run to run (observed:
    E1 differing in the 15th digit between two runs of the same array)."""
    actual, expected = plain(actual), plain(expected)
    if isinstance(expected, dict):
        assert isinstance(actual, dict) and list(actual) == list(expected), where
        for key in expected:
            assert_same(actual[key], expected[key], f"{where}.{key}")
    elif isinstance(expected, list):
        assert isinstance(actual, list) and len(actual) == len(expected), where
        for i, (a, e) in enumerate(zip(actual, expected)):
            assert_same(a, e, f"{where}.{i}")
    elif isinstance(expected, float) and not isinstance(expected, bool):
        assert actual == pytest.approx(expected, rel=1e-12, abs=1e-300, nan_ok=True), where
    else:
        assert actual == expected, where


def test_analyses_equal_the_signal_analysis_study(cli, source_dir, henon, tmp_path):
    settings = {"lyapunov": {"max_reference_points": 500}, "lyapunov_spectrum": {"max_reference_points": 500}}
    study = tmp_path / "henon.toml"
    study.write_text(toml_text({
        "study": {"kind": "signal_analysis"},
        "input": {"file": str(source_dir / "studies" / "data" / "henon_x.csv"), "column": "x", "sample_rate_hz": 1.0},
        "analysis": {"methods": ["embedding", "lyapunov", "lyapunov_spectrum"]},
        "analysis.lyapunov": settings["lyapunov"],
        "analysis.lyapunov_spectrum": settings["lyapunov_spectrum"],
    }))
    run = run_cli(cli, "run", study, "--out", tmp_path / "out")
    assert run.returncode == 0, run.stderr
    import json
    methods = json.loads((tmp_path / "out" / "summary.json").read_text())["methods"]

    embedding = chatterlab.embedding(henon, sample_rate_hz=1.0)
    lyapunov = chatterlab.lyapunov(henon, sample_rate_hz=1.0, context={"embedding": embedding}, **settings["lyapunov"])
    spectrum = chatterlab.lyapunov_spectrum(henon, sample_rate_hz=1.0, context={"embedding": embedding, "lyapunov": lyapunov},
                                            **settings["lyapunov_spectrum"])
    assert_same(embedding, methods["embedding"])
    assert_same(lyapunov, methods["lyapunov"])
    assert_same(spectrum, methods["lyapunov_spectrum"])


def test_per_window_series_are_arrays_equal_to_the_study_json(cli, tmp_path):
    # window_features and rbf_density hand their per-window series to Python as numpy arrays
    # (chatterlab/analysis_arrays.hpp), not through JSON; a signal_analysis study writes the same
    # analyses' JSON into summary.json. The two routes agree bit for bit, key order included.
    rng = np.random.default_rng(5)
    t = np.arange(20_000) / 10_000.0
    x = np.sin(2 * math.pi * 73.0 * t) * np.exp(3.0 * t) + 0.2 * rng.standard_normal(len(t))
    data = tmp_path / "signal.csv"
    np.savetxt(data, np.column_stack([t, x]), delimiter=",", header="t_s,x", comments="", fmt="%.17g")
    params = {"window_features": {"window_samples": 10}, "rbf_density": {"hop_samples": 50}}
    study = tmp_path / "monitor.toml"
    study.write_text(toml_text({
        "study": {"kind": "signal_analysis"},
        "input": {"file": str(data), "column": "x", "sample_rate_hz": 10_000.0},
        "analysis": {"methods": list(params)},
        **{f"analysis.{name}": settings for name, settings in params.items()},
    }))
    run = run_cli(cli, "run", study, "--out", tmp_path / "out")
    assert run.returncode == 0, run.stderr
    import json
    methods = json.loads((tmp_path / "out" / "summary.json").read_text())["methods"]
    for name, settings in params.items():
        result = chatterlab.analyse(name, x, sample_rate_hz=10_000.0, **settings)
        assert list(result) == list(methods[name]), name
        for key in ("t_s", "variance", "rho1", "residual_variance", "score", "alarm"):
            if key in methods[name]:
                assert isinstance(result[key], np.ndarray), (name, key)
                np.testing.assert_array_equal(result[key], np.array(methods[name][key]), err_msg=f"{name}.{key}")
        assert_same({k: v for k, v in result.items()}, methods[name], name)
    assert len(chatterlab.analyse("window_features", x, window_samples=10)["variance"]) == 2000
    assert chatterlab.analyse("rbf_density", x, hop_samples=50)["alarm"].dtype == np.bool_


def test_henon_known_answers(henon):
    # Henon map (a = 1.4, b = 0.3): delay 1, dimension 2, largest exponent 0.419 per iteration.
    embedding = chatterlab.embedding(henon)
    assert embedding["embedding_dimension"]["value"] == 2 and embedding["delay_samples"]["value"] == 1
    largest = chatterlab.lyapunov(henon, context={"embedding": embedding})["lyapunov_max_per_sample"]
    assert largest["quality"] == "good"
    assert largest["ci_low"] - 0.01 <= 0.419 <= largest["ci_high"] + 0.01
    assert isinstance(embedding["mutual_information_nats"], np.ndarray)


def test_strided_and_other_dtypes_give_the_same_result(henon):
    contiguous = chatterlab.embedding(henon, delay_samples=1, max_dimension=4)
    strided = np.repeat(henon, 2)[::2]
    assert not strided.flags["C_CONTIGUOUS"]
    assert_same(chatterlab.embedding(strided, delay_samples=1, max_dimension=4), contiguous)
    as_list = chatterlab.embedding(henon.tolist(), delay_samples=1, max_dimension=4)
    assert_same(as_list, contiguous)
    assert set(contiguous.timing) == {"input_s", "input_converted", "analyse_s", "result_s"}
    # Zero-copy input (issue 24): the analysis reads a float64 C-contiguous array in place; numpy
    # converts strided views and lists once.
    assert contiguous.timing["input_converted"] is False
    assert chatterlab.embedding(strided, delay_samples=1, max_dimension=4).timing["input_converted"] is True


def test_bad_input_is_refused_with_the_command_line_message(cli, source_dir, henon, tmp_path):
    study = tmp_path / "bad.toml"
    study.write_text(toml_text({
        "study": {"kind": "signal_analysis"},
        "input": {"file": str(source_dir / "studies" / "data" / "henon_x.csv"), "column": "x", "sample_rate_hz": 1.0},
        "analysis": {"methods": ["embedding"]},
        "analysis.embedding": {"max_dimension": 1},
    }))
    run = run_cli(cli, "validate", study)
    assert run.returncode == 2
    expected = run.stderr.strip().split(": ", 3)[-1]  # after "chatterlab: error: <file>:<line>: "
    with pytest.raises(chatterlab.InputError) as caught:
        chatterlab.embedding(henon, max_dimension=1)
    assert str(caught.value) == "analyse: " + expected

    with pytest.raises(chatterlab.InputError, match="unknown analysis 'lyapunof'.*lyapunov"):
        chatterlab.analyse("lyapunof", henon)
    with pytest.raises(ValueError, match="one-dimensional"):
        chatterlab.embedding(np.zeros((100, 2)))
    with_nan = henon.copy()
    with_nan[10] = np.nan
    with pytest.raises(chatterlab.InputError):
        chatterlab.embedding(with_nan)
    with pytest.raises(chatterlab.InputError, match="sample_rate_hz = 0"):
        chatterlab.embedding(henon, sample_rate_hz=0.0)


def test_roundness_of_a_known_profile():
    # r = 5 cos 3t + 2 sin 7t um: no first harmonic, so the least-squares centre is the origin
    # and RONt is the profile's peak to valley; a 500 UPR filter passes 3 and 7 UPR (> 0.9998).
    n = 3600
    theta = np.arange(n) * 2 * math.pi / n
    profile = 5 * np.cos(3 * theta) + 2 * np.sin(7 * theta)
    result = chatterlab.roundness(profile, cutoff_upr=500.0)
    least_squares = result["roundness"]["least_squares"]
    assert least_squares["RONt_um"] == pytest.approx(profile.max() - profile.min(), rel=2e-4)
    assert abs(least_squares["centre_x_um"]) < 1e-9 and abs(least_squares["centre_y_um"]) < 1e-9
    # The minimum zone is never wider than the least-squares zone.
    assert result["roundness"]["minimum_zone"]["RONt_um"] <= least_squares["RONt_um"]


def test_waviness_of_a_long_cosine():
    # A cosine of 8 mm wavelength and 1 um amplitude over 40 mm, symmetric about the middle (so
    # the least-squares line that removes form is flat): the 0.8 mm cut-off passes it with the
    # Gaussian transmission exp(-pi (0.4697 x 0.8 / 8)^2) = 0.99309, so Wt = 2 x 0.99309 um and
    # WSm is the wavelength (MODELS.md W1).
    spacing = 0.005
    x = np.arange(0, 40 + spacing / 2, spacing)
    profile = np.cos(2 * math.pi * (x - 20.0) / 8.0)
    result = chatterlab.waviness(profile, spacing_mm=spacing, cutoff_mm=0.8)
    alpha = math.sqrt(math.log(2) / math.pi)
    transmission = math.exp(-math.pi * (alpha * 0.8 / 8.0) ** 2)
    assert result["Wt_um"] == pytest.approx(2.0 * transmission, rel=1e-4)
    assert result["WSm_mm"] == pytest.approx(8.0, rel=1e-3)
    # The filtered profile itself (array callers only, not in summary files): one value per
    # sample, the cosine times the transmission over the evaluation length (lc/2 left out at each
    # end), to 0.1 % of the amplitude: the unfiltered cosine is 0.7 % away.
    waviness_um = result["waviness_um"]
    assert isinstance(waviness_um, np.ndarray) and waviness_um.shape == profile.shape
    inside = (x >= result["evaluation_from_mm"]) & (x <= result["evaluation_to_mm"])
    np.testing.assert_allclose(waviness_um[inside], transmission * profile[inside], rtol=0, atol=1e-3)
    assert np.abs(profile[inside] - transmission * profile[inside]).max() > 5e-3
    with pytest.raises(ValueError, match="spacing_mm"):
        chatterlab.surface_profile(profile)


def test_error_separation_recovers_a_known_profile():
    # Three probes at 0, 99, 202 deg (MODELS.md E1) see r(t + phi) + dx cos phi + dy sin phi.
    n = 360
    theta = np.arange(n) * 2 * math.pi / n
    def form(t):
        return 3 * np.cos(2 * t) + 1.5 * np.sin(5 * t) + 0.8 * np.cos(11 * t + 0.3)
    dx = 0.7 * np.sin(3 * theta + 0.2) + 0.2 * np.cos(17 * theta)
    dy = 0.5 * np.cos(4 * theta) - 0.3 * np.sin(9 * theta)
    angles = [0.0, 99.0, 202.0]
    probes = np.column_stack([form(theta + math.radians(a)) + dx * math.cos(math.radians(a)) +
                              dy * math.sin(math.radians(a)) for a in angles])
    run = chatterlab.error_separation(probes, angles, plots=False)
    assert run.exit_code == 0
    expected = form(theta)
    assert run.results["roundness_um"][0] == pytest.approx(expected.max() - expected.min(), rel=1e-9)
    assert "profile" in run.tables()
