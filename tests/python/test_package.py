"""The package's surface: every public name documented, the compiled module's stub
(_chatterlab.pyi) naming exactly what the module defines, with the same parameters."""

import ast
import re
import inspect
from pathlib import Path

import chatterlab
from chatterlab import _chatterlab


def stub_definitions():
    tree = ast.parse((Path(chatterlab.__file__).parent / "_chatterlab.pyi").read_text())
    return {node.name: node for node in tree.body if isinstance(node, (ast.FunctionDef, ast.ClassDef))}


def test_stub_names_what_the_module_defines():
    stub = stub_definitions()
    defined = {name for name in dir(_chatterlab) if not name.startswith("__")}
    assert set(stub) == defined
    for name, node in stub.items():
        if isinstance(node, ast.FunctionDef):
            # pybind11 writes the signature as the docstring's first line: name(arg: type, ...)
            first_line = getattr(_chatterlab, name).__doc__.splitlines()[0]
            compiled = re.findall(r"(?:\(|, )(\w+): ", first_line[len(name):])
            assert [a.arg for a in node.args.args] == compiled, name


def test_every_public_name_has_a_docstring():
    for name in chatterlab.__all__:
        value = getattr(chatterlab, name)
        if inspect.isfunction(value) or inspect.isclass(value):
            assert inspect.getdoc(value), name
    assert "certified rightmost characteristic root" in inspect.getdoc(chatterlab.rightmost_root)
    assert chatterlab.InputError.__module__ == "chatterlab" and issubclass(chatterlab.InputError, ValueError)
