"""docs/python.md's session, run as written (doctest: every output shown there is checked), in a
fresh directory where `studies/` is the shipped studies."""

import doctest
import os


def test_docs_python_md(source_dir, tmp_path, monkeypatch):
    (tmp_path / "studies").symlink_to(source_dir / "studies")
    monkeypatch.chdir(tmp_path)
    result = doctest.testfile(os.fspath(source_dir / "docs" / "python.md"), module_relative=False,
                              optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 40
    assert result.failed == 0
    assert (tmp_path / "lobes.png").stat().st_size > 10_000
