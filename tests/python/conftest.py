"""Shared fixtures of the Python module's tests (tests/python/CMakeLists.txt sets the environment:
the build tree's package on PYTHONPATH, the source tree, the `chatterlab` command, the example
plugin library)."""

import csv
import os
import subprocess
import tomllib
from pathlib import Path

import numpy as np
import pytest


def _env_path(name: str) -> Path:
    value = os.environ.get(name)
    if not value:
        pytest.fail(f"{name} is not set: run these tests through CTest (tests/python/CMakeLists.txt)")
    return Path(value)


@pytest.fixture(scope="session")
def source_dir() -> Path:
    return _env_path("CHATTERLAB_SOURCE_DIR")


@pytest.fixture(scope="session")
def cli() -> Path:
    return _env_path("CHATTERLAB_CLI")


@pytest.fixture(scope="session")
def example_plugin() -> Path:
    return _env_path("CHATTERLAB_EXAMPLE_PLUGIN")


@pytest.fixture(scope="session")
def default_model(source_dir) -> dict:
    """The [model] table of studies/g8_speed_map.toml: the G8 grinder with the G1 model."""
    with open(source_dir / "studies" / "g8_speed_map.toml", "rb") as f:
        return tomllib.load(f)["model"]


def read_column(path: Path, name: str) -> np.ndarray:
    """Column `name` of a chatterlab data file ("#" comment lines, then a header line)."""
    with open(path, encoding="utf-8") as f:
        rows = [line for line in f.read().splitlines() if line and not line.startswith("#")]
    header = rows[0].split(",")
    column = header.index(name)
    return np.array([float(row.split(",")[column]) for row in rows[1:]])


@pytest.fixture(scope="session")
def henon(source_dir) -> np.ndarray:
    """5,000 iterations of the Henon map's x (studies/data/henon_x.csv)."""
    return read_column(source_dir / "studies" / "data" / "henon_x.csv", "x")


def run_cli(cli: Path, *args, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run([os.fspath(cli), *map(os.fspath, args)], capture_output=True, text=True, cwd=cwd)


def read_csv_rows(path: Path) -> list:
    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def toml_text(tables: dict) -> str:
    """A small study file from nested dicts (numbers, strings, booleans, lists, inline tables)."""
    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        return repr(float(v)) if isinstance(v, float) else str(v)

    lines = []
    for name, table in tables.items():
        scalars = {k: v for k, v in table.items() if not (isinstance(v, list) and v and isinstance(v[0], dict))}
        arrays = {k: v for k, v in table.items() if k not in scalars}
        lines.append(f"[{name}]")
        lines += [f'"{k}" = {value(v)}' if "." in k else f"{k} = {value(v)}" for k, v in scalars.items()]
        for key, items in arrays.items():
            for item in items:
                lines.append(f"[[{name}.{key}]]")
                lines += [f"{k} = {value(v)}" for k, v in item.items()]
        lines.append("")
    return "\n".join(lines)
