"""Tables that chatterlab writes (results.csv or results.h5, a point's time series, a plan's
pulses) as a pandas DataFrame when pandas is installed, else a numpy record array with the same
columns."""

from __future__ import annotations

import csv
import os
from typing import Any, Literal

import numpy as np

TableKind = Literal["auto", "pandas", "numpy"]


def _pandas():
    try:
        import pandas  # noqa: PLC0415 (optional dependency)
    except ImportError:
        return None
    return pandas


def _column(cells: list[str]) -> np.ndarray:
    """Numbers (empty cells: NaN), booleans ("true"/"false", as results.csv writes them), or text."""
    present = [c for c in cells if c != ""]
    if present and all(c in ("true", "false") for c in present) and len(present) == len(cells):
        return np.array([c == "true" for c in cells], dtype=bool)
    try:
        return np.array([float(c) if c != "" else np.nan for c in cells], dtype=np.float64)
    except ValueError:
        return np.array(cells, dtype=object)


def _read_columns(path: str | os.PathLike) -> tuple[list[str], list[np.ndarray]]:
    with open(path, newline="", encoding="utf-8") as f:
        rows = [row for row in csv.reader(f) if row and not row[0].startswith("#")]
    if not rows:
        raise ValueError(f"{os.fspath(path)}: no header line")
    header, body = rows[0], rows[1:]
    columns = [_column([row[i] if i < len(row) else "" for row in body]) for i in range(len(header))]
    return header, columns


def _pandas_for(kind: TableKind):
    if kind not in ("auto", "pandas", "numpy"):
        raise ValueError(f"table kind {kind!r}: expected 'auto', 'pandas' or 'numpy'")
    pandas = _pandas() if kind != "numpy" else None
    if kind == "pandas" and pandas is None:
        raise ImportError("table kind 'pandas' needs pandas (Debian: python3-pandas)")
    return pandas


def read_table(path: str | os.PathLike, kind: TableKind = "auto") -> Any:
    """The CSV file at `path` as a pandas DataFrame (kind "pandas", or "auto" with pandas
    installed) or a numpy record array (kind "numpy", or "auto" without pandas). Numbers are
    float64 (empty cells NaN), true/false columns bool, anything else text; the values are the
    file's exactly (chatterlab writes the shortest text that reads back as the same double)."""
    _pandas_for(kind)
    header, columns = _read_columns(path)
    return table_from_columns(header, columns, kind)


def table_from_columns(header: list[str], columns: list[np.ndarray], kind: TableKind = "auto") -> Any:
    """Named columns (typed as read_table types them) as read_table's DataFrame or record array."""
    pandas = _pandas_for(kind)
    if pandas is not None:
        return pandas.DataFrame({name: column for name, column in zip(header, columns)})
    if not header:
        return np.rec.array(np.empty(0, dtype=[]))
    return np.rec.fromarrays(columns, names=header)


def read_npy_table(path: str | os.PathLike, kind: TableKind = "auto") -> Any:
    """A NumPy structured array file (one float64 field per column, as a simulation's
    ``timeseries_format = "npy"`` writes it) as ``read_table`` returns a CSV file."""
    pandas = _pandas_for(kind)
    array = np.load(path, allow_pickle=False)
    if pandas is not None:
        return pandas.DataFrame({name: array[name] for name in array.dtype.names})
    return array.view(np.recarray)
