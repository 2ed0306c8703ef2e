"""What is registered: models, machines, suppressions, analyses and study kinds, built in or
loaded from plugin libraries."""

from __future__ import annotations

import os
from typing import List, Union

from . import _chatterlab

__all__ = ["plugins", "describe", "load_plugin"]


def plugins() -> List[dict]:
    """Every registered plugin and study kind (``chatterlab list``): dicts of registry ("model",
    "kinematics", "suppression", "analysis", "study kind"), name, description, origin ("built-in"
    or the library), models_md_ids, thread_safety, params (each key's kind, unit, limits, default,
    description) and example_params."""
    return _chatterlab.plugins("")


def describe(name: str) -> str:
    """``chatterlab describe NAME``: a plugin's or study kind's parameters and a TOML example.
    Raises chatterlab.InputError listing the valid names for an unknown one."""
    return _chatterlab.describe(name)


def load_plugin(path: Union[str, os.PathLike]) -> List[dict]:
    """Loads an out-of-tree plugin library (built with ``chatterlab new-plugin`` and
    ``chatterlab_add_plugin``), as a study's ``plugins = [...]`` does, and returns what it
    registered (as plugins()). Loading the same library again does nothing. Raises
    chatterlab.InputError for a file that is not a plugin of this chatterlab version, or whose
    names clash with registered ones."""
    return _chatterlab.load_plugin(os.fspath(path))
