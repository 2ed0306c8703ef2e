"""Progress of a study run: a tqdm bar (a widget in Jupyter) when tqdm is installed, else a text
line redrawn on stderr, which terminals and notebooks both show."""

from __future__ import annotations

import sys
import time
from typing import Callable, Optional, Union

ProgressCallback = Callable[[int, int], None]
Progress = Union[None, bool, ProgressCallback]


def _in_notebook() -> bool:
    return "ipykernel" in sys.modules


class _TextBar:
    def __init__(self, label: str) -> None:
        self._label = label
        self._start = time.monotonic()
        self._shown = None

    def __call__(self, done: int, total: int) -> None:
        if (done, total) == self._shown:  # the study's plots are being drawn
            return
        self._shown = (done, total)
        elapsed = time.monotonic() - self._start
        fraction = done / total if total else 1.0
        filled = int(30 * fraction)
        eta = f"{elapsed / done * (total - done):.0f} s" if done else "?"
        sys.stderr.write(f"\r{self._label} [{'#' * filled}{'.' * (30 - filled)}] {100 * fraction:3.0f}%  "
                         f"{done}/{total} points  {elapsed:.0f} s elapsed  ETA {eta}")
        sys.stderr.flush()

    def close(self) -> None:
        if self._shown is None:
            return
        sys.stderr.write("\n")
        sys.stderr.flush()


class _TqdmBar:
    def __init__(self, tqdm, label: str) -> None:
        self._tqdm = tqdm
        self._label = label
        self._bar = None

    def __call__(self, done: int, total: int) -> None:
        if self._bar is None:
            self._bar = self._tqdm(total=total, desc=self._label, unit="point")
        self._bar.update(done - self._bar.n)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()


def progress_reporter(progress: Progress, label: str) -> Optional[ProgressCallback]:
    """The callable run_study reports (points done, points to compute) to, or None.

    progress: None shows a bar in a notebook or on a terminal, True always, False never; a
    callable receives (done, total) itself."""
    if callable(progress) and not isinstance(progress, bool):
        return progress
    show = progress if progress is not None else (_in_notebook() or sys.stderr.isatty())
    if not show:
        return None
    try:
        from tqdm.auto import tqdm  # noqa: PLC0415 (optional dependency)
    except ImportError:
        return _TextBar(label)
    return _TqdmBar(tqdm, label)


def close(reporter: Optional[ProgressCallback]) -> None:
    closer = getattr(reporter, "close", None)
    if closer is not None:
        closer()
