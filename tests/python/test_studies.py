"""Studies from Python: run_study of a file or a dict writes what `chatterlab run` writes, its
table is results.csv's values exactly (pandas or numpy), progress reaches the callback, bad
studies raise the command line's message with nothing written; feed_plan / feed_risk; plugins
loaded with load_plugin serve rightmost_root; init_study gives a study that runs."""

import cmath
import json
import math
import tomllib

import numpy as np
import pytest

import chatterlab
from conftest import read_csv_rows, run_cli, toml_text


def load_toml(path):
    with open(path, "rb") as f:
        return tomllib.load(f)


def assert_table_equals_csv(table, rows):
    """`table` (DataFrame or record array) holds results.csv's cells: numbers to the last bit."""
    columns = list(rows[0])
    names = list(table.columns) if hasattr(table, "columns") else list(table.dtype.names)
    assert names == columns
    for column in columns:
        values = np.asarray(table[column])
        assert len(values) == len(rows), column
        for value, row in zip(values, rows):
            cell = row[column]
            if cell in ("true", "false"):
                assert bool(value) == (cell == "true"), column
            elif cell == "":
                assert isinstance(value, float) and math.isnan(value), column
            else:
                try:
                    assert float(value) == float(cell), column
                except ValueError:
                    assert value == cell, column


def test_run_study_of_a_file_equals_the_command_line(cli, source_dir, tmp_path):
    study = source_dir / "studies" / "thompson_band.toml"
    run = run_cli(cli, "run", study, "--out", tmp_path / "cli", "--threads", "2")
    assert run.returncode == 0, run.stderr
    rows = read_csv_rows(tmp_path / "cli" / "results.csv")

    result = chatterlab.run_study(study, tmp_path / "python", threads=2, progress=False)
    assert result.exit_code == 0 and result.failed == 0 and result.points == len(rows)
    assert (tmp_path / "python" / "results.csv").read_bytes() == (tmp_path / "cli" / "results.csv").read_bytes()
    assert_table_equals_csv(result.results, rows)
    assert result.meta["kind"] == "stability_map" and result.meta["points"] == len(rows)  # meta.json
    assert result.plots and all(p.suffix == ".png" for p in result.plots)


def test_results_as_numpy_record_array(cli, source_dir, tmp_path):
    result = chatterlab.run_study(source_dir / "studies" / "thompson_band.toml", tmp_path / "out", threads=1,
                                  plots=False, table="numpy", progress=False)
    assert isinstance(result.results, np.recarray)
    assert_table_equals_csv(result.results, read_csv_rows(tmp_path / "out" / "results.csv"))


def test_run_study_of_a_dict_with_progress(default_model, tmp_path):
    # A 1 x 12 grid over the work speed: the callback sees (0, 12) first, never more than 12
    # done, and (12, 12) last.
    speeds = [20.0 + 5.0 * i for i in range(12)]
    study = {"study": {"kind": "stability_map", "name": "work speed sweep"}, "model": default_model,
             "grid": {"model.work_speed_rpm": speeds}}
    seen = []
    result = chatterlab.run_study(study, tmp_path / "out", threads=2, plots=False,
                                  progress=lambda done, total: seen.append((done, total)))
    assert result.points == 12 and result.exit_code == 0
    assert seen[-1] == (12, 12)
    assert all(total == 12 and 0 <= done <= 12 for done, total in seen)
    assert [done for done, _ in seen] == sorted(done for done, _ in seen)
    # Each row is the rightmost root of that point's model.
    for i in (0, 7):
        root = chatterlab.rightmost_root({**default_model, "work_speed_rpm": speeds[i]})
        assert float(result.results["growth_rate_per_s"][i]) == root.growth_rate_per_s


def test_progress_bar_in_a_notebook(default_model, tmp_path, capsys, monkeypatch):
    # In a notebook (ipykernel loaded) run_study shows a progress bar by default (tqdm's when
    # installed, else a text line redrawn with carriage returns, which Jupyter shows as one
    # line); outside a notebook and terminal, none unless asked for.
    import sys
    import types
    study = {"study": {"kind": "stability_map"}, "model": default_model,
             "grid": {"model.work_speed_rpm": [30.0, 40.0, 50.0]}}
    chatterlab.run_study(study, tmp_path / "quiet", plots=False)
    assert "3/3" not in capsys.readouterr().err
    monkeypatch.setitem(sys.modules, "ipykernel", types.ModuleType("ipykernel"))
    chatterlab.run_study(study, tmp_path / "notebook", plots=False)
    shown = capsys.readouterr().err
    assert "3/3" in shown and "stability_map" in shown


@pytest.mark.parametrize("table", ["pandas", "numpy"])
def test_hdf5_results_give_the_same_table_as_csv(default_model, tmp_path, table):
    # The same 3 x 4 grid written as results.csv and as results.h5 ([output] format = "hdf5"):
    # run_study returns the same table, column for column (names, dtypes: float64, bool, text),
    # value for value, bit for bit.
    if table == "pandas":
        pandas = pytest.importorskip("pandas")
    study = {"study": {"kind": "stability_map", "name": "csv or hdf5"}, "model": default_model,
             "grid": {"model.wheel_speed_rpm": [1400.0, 1500.0, 1600.0],
                      "model.work_speed_rpm": [30.0, 45.0, 60.0, 75.0]}}
    as_csv = chatterlab.run_study(study, tmp_path / "csv", threads=2, plots=False, progress=False, table=table)
    as_hdf5 = chatterlab.run_study({**study, "output": {"format": "hdf5"}}, tmp_path / "hdf5", threads=2,
                                   plots=False, progress=False, table=table)
    assert as_hdf5.meta["results_file"] == "results.h5"
    assert (tmp_path / "hdf5" / "results.h5").is_file() and not (tmp_path / "hdf5" / "results.csv").exists()
    assert as_csv.points == as_hdf5.points == 12 and as_hdf5.exit_code == 0
    if table == "pandas":
        assert isinstance(as_hdf5.results, pandas.DataFrame)
        pandas.testing.assert_frame_equal(as_hdf5.results, as_csv.results, check_exact=True)
        columns = list(as_csv.results.columns)
        dtypes = {c: as_csv.results[c].dtype for c in columns}
    else:
        assert isinstance(as_hdf5.results, np.recarray)
        assert as_hdf5.results.dtype == as_csv.results.dtype
        columns = list(as_csv.results.dtype.names)
        for column in columns:
            np.testing.assert_array_equal(as_hdf5.results[column], as_csv.results[column], err_msg=column)
        dtypes = {c: as_csv.results[c].dtype for c in columns}
    assert columns[:2] == ["model.wheel_speed_rpm", "model.work_speed_rpm"] and columns[-1] == "status"
    # Every kind of column is covered: numbers, booleans and text.
    assert dtypes["growth_rate_per_s"] == np.float64 and dtypes["stable"] == np.bool_
    assert dtypes["certificate"] == object
    assert_table_equals_csv(as_hdf5.results, read_csv_rows_of(as_csv))


def read_csv_rows_of(run):
    return read_csv_rows(run.out_dir / "results.csv")


def test_results_h5_of_another_study_is_refused(default_model, tmp_path):
    study = {"study": {"kind": "stability_map"}, "model": default_model, "output": {"format": "hdf5"},
             "grid": {"model.work_speed_rpm": [30.0, 45.0]}}
    chatterlab.run_study(study, tmp_path / "out", plots=False, progress=False)
    other = chatterlab.load_study({**study, "grid": {"model.work_speed_rpm": [30.0, 50.0]}})
    with pytest.raises(chatterlab.InputError, match=r"results\.h5: written by another study"):
        chatterlab._chatterlab.read_results_h5(other._study, str(tmp_path / "out" / "results.h5"))


def test_a_bad_study_raises_the_command_line_message_and_writes_nothing(cli, default_model, tmp_path):
    tables = {"study": {"kind": "stability_map"}, "model": default_model,
              "grid": {"model.work_speed_rpm": [30.0, -5.0]}}
    file = tmp_path / "bad.toml"
    file.write_text(toml_text(tables))
    run = run_cli(cli, "validate", file)
    assert run.returncode == 2
    cli_message = run.stderr.strip().removeprefix("chatterlab: error: ")
    assert cli_message.startswith(f"{file}:")

    with pytest.raises(chatterlab.InputError) as from_file:
        chatterlab.run_study(file, tmp_path / "out_file")
    assert str(from_file.value) == cli_message
    # A dict has no lines: "run_study: " stands where "<file>:<line>: " stood.
    with pytest.raises(chatterlab.InputError) as from_dict:
        chatterlab.run_study(tables, tmp_path / "out_dict")
    after_location = cli_message.split(": ", 1)[1]
    after_location = after_location.split(": ", 1)[1] if after_location[0].isdigit() else after_location
    assert str(from_dict.value) == "run_study: " + after_location
    assert not (tmp_path / "out_file").exists() and not (tmp_path / "out_dict").exists()

    with pytest.raises(chatterlab.InputError, match="unknown study kind 'stability_mapp'"):
        chatterlab.load_study({"study": {"kind": "stability_mapp"}})
    with pytest.raises(TypeError, match="model.modes.0.damping_ratio: cannot use a"):
        chatterlab.load_study({"study": {"kind": "stability_map"},
                               "model": {**default_model, "modes": [{"damping_ratio": object()}]}})


def test_feed_plan_and_feed_risk_equal_the_command_line(cli, source_dir, tmp_path):
    problem1 = load_toml(source_dir / "studies" / "feed_plan_problem1.toml")
    run = run_cli(cli, "run", source_dir / "studies" / "feed_plan_problem1.toml", "--out", tmp_path / "cli_plan")
    assert run.returncode == 0, run.stderr
    plan = chatterlab.feed_plan(problem1["machine"], problem1["part"], problem1["wheel"], problem1.get("plan"),
                                out=tmp_path / "plan", plots=False, progress=False)
    assert_table_equals_csv(plan.results, read_csv_rows(tmp_path / "cli_plan" / "results.csv"))
    assert plan.results["certified"][0]
    pulses = plan.table("pulses")
    assert len(pulses) == len(read_csv_rows(tmp_path / "cli_plan" / "pulses.csv"))
    assert plan.summary() == json.loads((tmp_path / "cli_plan" / "summary.json").read_text())

    risk = load_toml(source_dir / "studies" / "feed_risk_constant.toml")
    run = run_cli(cli, "run", source_dir / "studies" / "feed_risk_constant.toml", "--out", tmp_path / "cli_risk")
    assert run.returncode == 0, run.stderr
    rows = read_csv_rows(tmp_path / "cli_risk" / "results.csv")
    here = chatterlab.feed_risk(risk["model"], risk["feed_risk"], machine=risk["machine"], part=risk["part"],
                                wheel=risk["wheel"], out=tmp_path / "risk", plots=False, progress=False)
    assert_table_equals_csv(here.results, rows)
    assert here.results["worst_risk"][0] == "chatter"
    # The same plan made first and passed on: the same risk.
    saved = chatterlab.feed_plan(risk["machine"], risk["part"], risk["wheel"], out=tmp_path / "saved",
                                 plots=False, progress=False)
    from_saved = chatterlab.feed_risk(risk["model"], risk["feed_risk"], plan=saved, out=tmp_path / "risk2",
                                      plots=False, progress=False)
    assert_table_equals_csv(from_saved.results, rows)


def test_plugin_model_through_load_plugin(cli, example_plugin, tmp_path):
    registered = chatterlab.load_plugin(example_plugin)
    assert [p["name"] for p in registered] == ["example_delay_model"]
    assert chatterlab.load_plugin(example_plugin) == registered  # a re-run notebook cell
    # Without regeneration (stiffness_ratio 0) the root is the mode's: -zeta w + i w sqrt(1 - zeta^2).
    omega, zeta = 2 * math.pi * 100.0, 0.05
    alone = chatterlab.rightmost_root({"type": "example_delay_model", "natural_frequency_hz": 100.0,
                                       "damping_ratio": zeta, "stiffness_ratio": 0.0, "work_speed_rpm": 60.0})
    assert cmath.isclose(alone.root, complex(-zeta * omega, omega * math.sqrt(1 - zeta * zeta)), rel_tol=1e-10)
    # With regeneration: the same root as a stability_map study that loads the library.
    model = {"type": "example_delay_model", "natural_frequency_hz": 100.0, "damping_ratio": zeta,
             "stiffness_ratio": 0.3, "work_speed_rpm": 60.0}
    study = tmp_path / "plugin.toml"
    study.write_text(f'plugins = ["{example_plugin}"]\n' + toml_text({"study": {"kind": "stability_map"}, "model": model}))
    run = run_cli(cli, "run", study, "--out", tmp_path / "out")
    assert run.returncode == 0, run.stderr
    [row] = read_csv_rows(tmp_path / "out" / "results.csv")
    root = chatterlab.rightmost_root(model)
    assert root.growth_rate_per_s == float(row["growth_rate_per_s"]) and root.growth_rate_per_s > 0
    assert root.chatter_frequency_hz == float(row["chatter_frequency_hz"])

    with pytest.raises(chatterlab.InputError, match="no_such_plugin.so"):
        chatterlab.load_plugin(tmp_path / "no_such_plugin.so")


def test_init_study_runs(tmp_path):
    template = chatterlab.init_study("stability_map", name="from init")
    assert template.validated, template.error
    path = template.write(tmp_path / "init.toml")
    study = chatterlab.load_study(path)
    assert study.kind == "stability_map" and study.point_count >= 1
    kinds = {kind for _, kind in chatterlab.shipped_studies()}
    assert {"stability_map", "simulate", "feed_plan"} <= kinds


def test_simulation_time_series_as_npy_table():
    # A simulate study writing timeseries.npy (a NumPy structured array): table() reads it, and
    # its columns are the arrays simulate() returns, bit for bit.
    model = {"type": "plunge_regenerative", "wheel_speed_rpm": 1450, "work_speed_rpm": 55,
             "contact_stiffness_n_per_m": 1e8, "wheel_wear_stiffness_n_per_m": 5e9,
             "work_removal_stiffness_n_per_m": 5e7,
             "modes": [{"frequency_hz": 184.08, "damping_ratio": 0.05, "stiffness_n_per_m": 5e7}]}
    settings = {"duration_s": 0.2, "sample_rate_hz": 5000.0, "initial_waviness_m": 1e-6, "seed": 3,
                "infeed_rate_m_per_s": 15e-6}
    run = chatterlab.run_study({"study": {"kind": "simulate"}, "model": model,
                                "simulation": {**settings, "timeseries_format": "npy"}},
                               plots=False, progress=False, table="numpy")
    assert "timeseries" in run.tables()
    series = run.table("timeseries")
    assert isinstance(series, np.recarray)
    direct = chatterlab.simulate(model, 0.2, sample_rate_hz=5000.0, initial_waviness_m=1e-6, seed=3,
                                 infeed_rate_m_per_s=15e-6)
    for column in ("t_s", "displacement_m", "force_n", "depth_of_cut_m"):
        np.testing.assert_array_equal(series[column], getattr(direct, column), err_msg=column)
