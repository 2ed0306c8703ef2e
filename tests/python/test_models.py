"""Models from Python: the rightmost root equals the command line's stability_map result, errors
carry the command line's messages, simulate() returns the engine's series and releases the GIL."""

import math
import re
import sys
import threading
import time

import numpy as np
import pytest

import chatterlab
from conftest import read_csv_rows, run_cli, toml_text

STABILITY_COLUMNS = ("growth_rate_per_s", "chatter_frequency_hz", "growth_rate_per_wheel_rev",
                     "certified_real_part_per_s")


def assert_matches_row(root: chatterlab.RootResult, row: dict) -> None:
    for column in STABILITY_COLUMNS:
        expected = float(row[column])
        assert abs(getattr(root, column) - expected) <= 1e-12 * max(1.0, abs(expected)), column
    assert root.certified == (row["certified"] == "true")
    assert root.stable == (row["stable"] == "true")
    assert root.certificate == row["certificate"]


def test_rightmost_root_of_g1_equals_the_command_line(cli, default_model, tmp_path):
    # One point: the G8 grinder of studies/g8_speed_map.toml (MODELS.md G1), through `chatterlab run`.
    study = tmp_path / "g1.toml"
    study.write_text(toml_text({"study": {"kind": "stability_map"}, "model": default_model}))
    run = run_cli(cli, "run", study, "--out", tmp_path / "out")
    assert run.returncode == 0, run.stderr
    [row] = read_csv_rows(tmp_path / "out" / "results.csv")
    root = chatterlab.rightmost_root(default_model)
    assert_matches_row(root, row)
    assert root.growth_rate_per_s > 0 and 70 < root.chatter_frequency_hz < 80  # the G8 grinder chatters
    assert root.root == complex(root.growth_rate_per_s, 2 * math.pi * root.chatter_frequency_hz)


def test_rightmost_root_over_the_default_grid_equals_the_command_line(cli, source_dir, tmp_path):
    run = run_cli(cli, "run", source_dir / "studies" / "g8_speed_map.toml", "--out", tmp_path / "out", "--threads", "2")
    assert run.returncode == 0, run.stderr
    rows = read_csv_rows(tmp_path / "out" / "results.csv")
    study = chatterlab.load_study(source_dir / "studies" / "g8_speed_map.toml")
    stability = study.document["stability"]
    for point in (0, 100, len(rows) - 1):
        document = study.point_document(point)
        root = chatterlab.rightmost_root(document["model"], stability["max_frequency_hz"])
        assert_matches_row(root, rows[point])


def cli_message(cli, tmp_path, model: dict) -> str:
    study = tmp_path / "bad.toml"
    study.write_text(toml_text({"study": {"kind": "stability_map"}, "model": model}))
    run = run_cli(cli, "validate", study)
    assert run.returncode == 2
    prefix = f"chatterlab: error: {study}:"
    assert run.stderr.startswith(prefix), run.stderr
    return re.sub(r"^\d+: ", "", run.stderr[len(prefix):].strip())


@pytest.mark.parametrize("change", [{"wheel_speed_rpm": -1450.0}, {"no_such_key": 1.0}, {"type": "plunge_regenerativ"}])
def test_input_errors_carry_the_command_line_message(cli, default_model, tmp_path, change):
    model = {**default_model, **change}
    expected = cli_message(cli, tmp_path, model)
    with pytest.raises(chatterlab.InputError) as caught:
        chatterlab.rightmost_root(model)
    assert isinstance(caught.value, ValueError)
    assert str(caught.value) == "rightmost_root: " + expected


def test_validate_model_fills_defaults(default_model):
    table = chatterlab.validate_model({key: value for key, value in default_model.items()})
    assert list(table)[0] == "type"
    assert set(default_model) <= set(table)
    described = {p["key"] for p in next(p for p in chatterlab.plugins() if p["name"] == "plunge_regenerative")["params"]}
    assert set(table) - {"type"} == described


def test_every_registered_model_has_a_root_or_says_why():
    for plugin in chatterlab.plugins():
        if plugin["registry"] != "model":
            continue
        model = {"type": plugin["name"], **plugin["example_params"]}
        try:
            root = chatterlab.rightmost_root(model)
        except chatterlab.InputError as e:
            assert "has no characteristic function" in str(e) or "max_frequency_hz" in str(e), (plugin["name"], str(e))
            continue
        assert np.isfinite(root.growth_rate_per_s) and root.max_frequency_hz > 0, plugin["name"]


SMALL_G1 = {"type": "plunge_regenerative", "wheel_speed_rpm": 1450, "work_speed_rpm": 55,
            "contact_stiffness_n_per_m": 1e8, "wheel_wear_stiffness_n_per_m": 5e9,
            "work_removal_stiffness_n_per_m": 5e7,
            "modes": [{"frequency_hz": 184.08, "damping_ratio": 0.05, "stiffness_n_per_m": 5e7}]}


def test_simulate_equals_the_simulate_study(cli, tmp_path):
    # The same engine run through `chatterlab run` (kind simulate, timeseries.csv at full
    # precision) and through simulate(): every series agrees to the last bit.
    settings = {"duration_s": 0.3, "sample_rate_hz": 5000.0, "initial_waviness_m": 1e-6, "seed": 3,
                "infeed_rate_m_per_s": 15e-6, "divergence_limit_m": 0.01,
                "wheel_speed_modulation": "sinusoidal", "wheel_speed_amplitude_ratio": 0.1,
                "wheel_speed_frequency_hz": 5.0}
    study = tmp_path / "simulate.toml"
    study.write_text(toml_text({"study": {"kind": "simulate"}, "model": SMALL_G1, "simulation": settings}))
    run = run_cli(cli, "run", study, "--out", tmp_path / "out")
    assert run.returncode == 0, run.stderr
    rows = read_csv_rows(tmp_path / "out" / "timeseries.csv")
    python = chatterlab.simulate(SMALL_G1, 0.3, sample_rate_hz=5000.0, initial_waviness_m=1e-6, seed=3,
                                 infeed_rate_m_per_s=15e-6, divergence_limit_m=0.01,
                                 wheel_speed={"modulation": "sinusoidal", "amplitude_ratio": 0.1, "frequency_hz": 5.0})
    assert len(python.t_s) == len(rows)
    for column in rows[0]:
        expected = np.array([float(row[column]) for row in rows])
        np.testing.assert_array_equal(getattr(python, column), expected, err_msg=column)


def test_simulate_returns_numpy_series(default_model):
    run = chatterlab.simulate(default_model, 0.2, sample_rate_hz=5000.0, snapshot_times_s=[0.1, 0.2],
                              wheel_speed={"schedule": [[0.0, 1450.0], [0.2, 1000.0]]})
    n = len(run.t_s)
    assert n == 1001
    for name in ("t_s", "displacement_m", "force_n", "wheel_speed_rpm", "work_speed_rpm", "in_contact"):
        series = getattr(run, name)
        assert isinstance(series, np.ndarray) and series.dtype == np.float64 and len(series) == n, name
    np.testing.assert_allclose(run.t_s, np.arange(n) / 5000.0, rtol=0, atol=1e-12)
    # The schedule: 1450 rpm falling linearly to 1000 rpm at 0.2 s; the work at the model's speed.
    np.testing.assert_allclose(run.wheel_speed_rpm, 1450.0 - 450.0 * run.t_s / 0.2, rtol=1e-9)
    np.testing.assert_allclose(run.work_speed_rpm, default_model["work_speed_rpm"], rtol=1e-12)
    assert [s["t_s"] for s in run.snapshots] == pytest.approx([0.1, 0.2], abs=1e-3)  # at the steps
    assert run.snapshots[0]["work_surface_m"].shape == run.snapshots[0]["angle_deg"].shape


@pytest.mark.parametrize("key, value", [("duration_s", -1.0), ("wheel_contact_arc_deg", 120.0),
                                        ("relative_tolerance", 0.5), ("integrator", "euler")])
def test_simulate_settings_errors_carry_the_command_line_message(cli, tmp_path, key, value):
    # The simulate kind's [simulation] table with the same bad value, through `chatterlab validate`.
    settings = {"duration_s": 0.2, key: value}
    study = tmp_path / "bad.toml"
    study.write_text(toml_text({"study": {"kind": "simulate"}, "model": SMALL_G1, "simulation": settings}))
    run = run_cli(cli, "validate", study)
    assert run.returncode == 2
    prefix = f"chatterlab: error: {study}:"
    assert run.stderr.startswith(prefix), run.stderr
    expected = re.sub(r"^\d+: ", "", run.stderr[len(prefix):].strip())
    with pytest.raises(chatterlab.InputError) as caught:
        chatterlab.simulate(SMALL_G1, **settings)
    assert str(caught.value) == "simulate: " + expected


def test_simulate_refuses_bad_settings(default_model):
    with pytest.raises(chatterlab.InputError, match=r"simulation\.duration_s = -1 \[s\]: out of range, must be > 0"):
        chatterlab.simulate(default_model, -1.0)
    with pytest.raises(chatterlab.InputError, match="simulation.snapshot_times_s"):
        chatterlab.simulate(default_model, 0.1, snapshot_times_s=[0.5])
    with pytest.raises(chatterlab.InputError, match="wheel_speed: unknown key 'amplitude'"):
        chatterlab.simulate(default_model, 0.1, wheel_speed={"modulation": "sinusoidal", "amplitude": 0.1})
    with pytest.raises(ValueError, match="amplitude"):
        chatterlab.simulate(default_model, 0.1, wheel_speed={"modulation": "sinusoidal", "amplitude_ratio": 1.5,
                                                             "frequency_hz": 1.0})


def test_the_gil_is_released_while_the_engine_integrates(default_model):
    # Another Python thread counts while this one calls simulate(). With the switch interval set
    # far beyond the test's length, the interpreter never takes the GIL from a thread: the counter
    # can only advance while this thread gives the GIL up of its own accord, which between the two
    # reads of the counter happens only inside the compiled call (gil_scoped_release). A binding
    # that held the GIL would leave the count at 0 whatever the timing; one that releases it lets
    # the counter run unless the OS never schedules the counting thread during a call, hence up
    # to 20 calls (each ~0.1 s of engine time) before concluding.
    counter = [0]
    stop = threading.Event()

    def count():
        while not stop.is_set():
            counter[0] += 1
            time.sleep(0)  # gives the GIL back, so the calling thread can resume

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1000.0)
    ticker = threading.Thread(target=count)
    try:
        ticker.start()
        during = []
        for _ in range(20):
            before = counter[0]
            run = chatterlab.simulate(default_model, 1.0)
            during.append(counter[0] - before)
            if during[-1] > 0:
                break
    finally:
        stop.set()
        sys.setswitchinterval(interval)
        ticker.join()
    assert run.status == "completed"
    assert during[-1] > 0, f"no progress of another thread during {len(during)} calls"


def test_roots_from_several_threads_equal_one_thread(default_model):
    from concurrent.futures import ThreadPoolExecutor
    models = [{**default_model, "work_speed_rpm": speed} for speed in (30.0, 45.0, 60.0, 75.0)]
    alone = [chatterlab.rightmost_root(m).root for m in models]
    with ThreadPoolExecutor(max_workers=4) as pool:
        together = [r.root for r in pool.map(chatterlab.rightmost_root, models)]
    assert together == alone
