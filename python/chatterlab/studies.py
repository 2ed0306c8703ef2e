"""Studies: the same files (or dicts of the same tables) and the same runner as ``chatterlab run``:
grid, threads, results.csv, meta.json, per-point files and plots in an output directory."""

from __future__ import annotations

import json
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Tuple, Union

from . import _chatterlab, _progress
from ._tables import TableKind, read_npy_table, read_table, table_from_columns

__all__ = ["Study", "RunResult", "load_study", "run_study", "init_study", "shipped_studies",
           "feed_plan", "feed_risk"]

StudySource = Union[str, os.PathLike, Mapping[str, Any], "Study"]


class Study:
    """A validated study: what ``chatterlab validate`` checks (plugins, [study], the kind's tables
    with defaults filled in, every grid value against its limits)."""

    def __init__(self, loaded: Any, source: StudySource) -> None:
        self._study = loaded
        self._source = source

    @property
    def file(self) -> str:
        """The study file (for a dict: the name messages use, "run_study")."""
        return self._study.file

    @property
    def kind(self) -> str:
        return self._study.kind

    @property
    def document(self) -> dict:
        """The resolved study: every table with defaults, data files by absolute path."""
        return self._study.document

    @property
    def point_count(self) -> int:
        return self._study.point_count

    @property
    def grid(self) -> List[dict]:
        """The grid axes in order (the last varies fastest): dicts of key, path, values."""
        return self._study.grid

    def point_document(self, point: int) -> dict:
        """The study with grid point ``point``'s values written in (what that point computes)."""
        return self._study.point_document(point)

    def __repr__(self) -> str:
        return f"Study(kind={self.kind!r}, file={self.file!r}, points={self.point_count})"


def load_study(study: StudySource, *, allow_large: bool = False) -> Study:
    """Reads and validates a study: a TOML file (path), or a dict of the same tables
    (``{"study": {"kind": "stability_map"}, "model": {...}, "grid": {...}}``) whose relative paths
    (data files, plugins) are taken relative to the working directory.

    Raises chatterlab.InputError with the command line's message: "<file>:<line>: <key> = <value>:
    <what is wrong>" for a file, "run_study: ..." for a dict."""
    if isinstance(study, Study):
        return study
    if isinstance(study, Mapping):
        return Study(_chatterlab.load_study_dict(dict(study), "run_study", allow_large), study)
    return Study(_chatterlab.load_study_file(os.fspath(study), allow_large), study)


@dataclass
class RunResult:
    """The outcome of run_study: the summary, the results table and the output directory.

    Attributes:
        out_dir: where results.csv, meta.json, plots and per-point files are.
        points, failed, resumed: grid points in all, failed (their reasons in ``meta``), and taken
            over from an earlier run (resume=True).
        exit_code: what ``chatterlab run`` would exit with: 0 every point ok, 1 some failed.
        results: the results table (a pandas DataFrame, or a numpy record array without
            pandas): the grid keys, the kind's outputs and ``status`` per point, from
            results.csv or, for ``[output] format = "hdf5"`` (or "auto" above 100,000 points),
            results.h5, read by the compiled module into the same columns.
        meta: meta.json (the resolved study, versions, timings, failed points, plot errors).
    """

    out_dir: Path
    points: int
    failed: int
    resumed: int
    exit_code: int
    results: Any = field(repr=False)
    meta: dict = field(repr=False)
    table_kind: TableKind = field(default="auto", repr=False)

    def point_dir(self, point: int = 0) -> Path:
        """A point's files: the output directory itself for a study without a grid, else
        points/<6-digit index>/ (written only by kinds that write per-point files)."""
        return self.out_dir if self.points == 1 else self.out_dir / "points" / f"{point:06d}"

    def tables(self, point: int = 0) -> List[str]:
        """Names of the tables a point wrote (e.g. "timeseries", "pulses", "segments"): its CSV
        files and NumPy files (a simulation's ``timeseries_format = "npy"``)."""
        directory = self.point_dir(point)
        files = list(directory.glob("*.csv")) + list(directory.glob("*.npy"))
        return sorted({p.stem for p in files if p.name != "results.csv"})

    def table(self, name: str, point: int = 0) -> Any:
        """A point's table <name>.csv or <name>.npy as a DataFrame or record array (as ``results``)."""
        directory = self.point_dir(point)
        if (directory / f"{name}.npy").is_file():
            return read_npy_table(directory / f"{name}.npy", self.table_kind)
        path = directory / f"{name}.csv"
        if not path.is_file():
            raise FileNotFoundError(f"{path}: no such table; this point wrote: {', '.join(self.tables(point)) or 'none'}")
        return read_table(path, self.table_kind)

    def summary(self, point: int = 0) -> dict:
        """A point's summary.json (kinds that write one: simulate, feed_plan, feed_risk, ...)."""
        return json.loads((self.point_dir(point) / "summary.json").read_text(encoding="utf-8"))

    @property
    def plots(self) -> List[Path]:
        """The PNG figures of the run (study-wide and the first point's)."""
        found = set(self.out_dir.glob("*.png")) | set(self.point_dir(0).glob("*.png"))
        return sorted(found)


def run_study(study: StudySource, out: Union[str, os.PathLike, None] = None, *, threads: int = 0,
              resume: bool = False, plots: bool = True, progress: _progress.Progress = None,
              table: TableKind = "auto", allow_large: bool = False) -> RunResult:
    """Runs a study (a file, a dict of its tables, or a Study) as ``chatterlab run`` does.

    out: output directory; default ``out/<file stem>`` for a file (as the command line) and a new
        temporary directory for a dict.
    threads: OpenMP threads (0: all cores). resume: keep the points an interrupted run finished.
    plots: False writes results.csv and meta.json only.
    progress: None shows a progress bar in a notebook or on a terminal, True always, False never;
        a callable receives (points done, points to compute) every 0.2 s.
    table: "auto" (a pandas DataFrame when pandas is installed), "pandas" or "numpy".

    The computation runs without the GIL. Raises chatterlab.InputError (nothing written) for a
    study that does not validate or an unusable output directory; failed points do not raise:
    see ``failed`` and the ``status`` column. The runner cannot be interrupted midway: a
    KeyboardInterrupt is raised when the run has finished.
    """
    loaded = load_study(study, allow_large=allow_large)
    if out is None:
        if isinstance(study, (str, os.PathLike)):
            out = Path("out") / Path(os.fspath(study)).stem
        else:
            out = tempfile.mkdtemp(prefix=f"chatterlab-{loaded.kind}-")
    out_dir = Path(out).absolute()
    reporter = _progress.progress_reporter(progress, f"{loaded.kind}")
    try:
        summary = _chatterlab.run_study(loaded._study, os.fspath(out_dir), threads, resume, plots, reporter)
    finally:
        _progress.close(reporter)
    meta = json.loads((out_dir / "meta.json").read_text(encoding="utf-8"))
    return RunResult(out_dir=out_dir, results=_results_table(loaded, out_dir, meta, table), meta=meta,
                     table_kind=table, **summary)


def _results_table(study: Study, out_dir: Path, meta: dict, kind: TableKind) -> Any:
    """results.csv or results.h5 (meta.json's results_file) as one table, with the same columns
    and values either way: results.h5 through the library's own reader, so no HDF5 package is
    needed in Python."""
    if meta.get("results_file") == "results.h5":
        header, columns = _chatterlab.read_results_h5(study._study, os.fspath(out_dir / "results.h5"))
        return table_from_columns(header, columns, kind)
    return read_table(out_dir / "results.csv", kind)


@dataclass(frozen=True)
class StudyTemplate:
    """``chatterlab init``'s study: the TOML text, whether the kind accepts it (``error`` says why
    not) and the shipped study it started from (kinds that need a data file)."""

    toml: str
    validated: bool
    error: str
    based_on: Optional[str]

    def write(self, path: Union[str, os.PathLike]) -> Path:
        target = Path(path)
        target.write_text(self.toml, encoding="utf-8")
        return target


def init_study(kind: str, *, example: str = "", name: str = "", model: str = "", machine: str = "",
               suppression: str = "") -> StudyTemplate:
    """A complete, commented study for a study kind (``chatterlab init KIND``): every key it
    reads, at its default or example value. example: start from this shipped study of the kind
    (shipped_studies()); model/machine/suppression: the plugin for that component table."""
    components = {table: plugin for table, plugin in (("model", model), ("machine", machine),
                                                      ("suppression", suppression)) if plugin}
    return StudyTemplate(**_chatterlab.init_study(kind, example, name, components))


def shipped_studies() -> List[Tuple[str, str]]:
    """(file, kind) of every study shipped with chatterlab, by file name."""
    return _chatterlab.shipped_studies()


def _run_kind(kind: str, tables: Dict[str, Any], name: Optional[str], out, run_options) -> RunResult:
    document: Dict[str, Any] = {"study": {"kind": kind}}
    if name:
        document["study"]["name"] = name
    document.update({key: value for key, value in tables.items() if value is not None})
    return run_study(document, out, **run_options)


def feed_plan(machine: Mapping[str, Any], part: Mapping[str, Any], wheel: Mapping[str, Any],
              plan: Optional[Mapping[str, Any]] = None, *, name: Optional[str] = None,
              out: Union[str, os.PathLike, None] = None, **run_options: Any) -> RunResult:
    """A certified time-optimal feed plan (MODELS.md P, ``feed_plan`` study kind; docs/planner.md):
    the [machine], [part], [wheel] and [plan] tables as dicts. The result's ``results`` row has the
    plan's totals; ``table("pulses")``, ``table("segments")`` and ``summary()`` the schedule. Its
    ``out_dir`` is a saved plan that feed_risk(plan=...) reads. run_options: as run_study."""
    return _run_kind("feed_plan", {"machine": machine, "part": part, "wheel": wheel, "plan": plan or {}},
                     name, out, run_options)


def feed_risk(model: Mapping[str, Any], feed_risk: Mapping[str, Any], *,
              plan: Union[RunResult, str, os.PathLike, None] = None,
              machine: Optional[Mapping[str, Any]] = None, part: Optional[Mapping[str, Any]] = None,
              wheel: Optional[Mapping[str, Any]] = None, plan_settings: Optional[Mapping[str, Any]] = None,
              name: Optional[str] = None, out: Union[str, os.PathLike, None] = None,
              **run_options: Any) -> RunResult:
    """Chatter risk along a feed plan (``feed_risk`` study kind, docs/feed_risk.md): every
    segment's conditions mapped onto ``model``, the rightmost root per segment, the accumulated
    amplification, a simulation along the schedule and optionally a chatter-aware re-plan.

    plan: a feed_plan() result or a saved plan directory; or None and the machine, part, wheel
    and plan_settings tables to plan here. feed_risk: the [feed_risk] table.
    run_options: as run_study."""
    settings = dict(feed_risk)
    tables: Dict[str, Any] = {"model": model}
    if plan is not None:
        settings["plan_dir"] = os.fspath(plan.out_dir if isinstance(plan, RunResult) else Path(plan).absolute())
    tables.update({"machine": machine, "part": part, "wheel": wheel, "plan": plan_settings,
                   "feed_risk": settings})
    return _run_kind("feed_risk", tables, name, out, run_options)
