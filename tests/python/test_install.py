"""The installed package (`cmake --install <build> --component python`, what quickstart.sh run
does into the user site-packages) is self-contained: imported from another directory with only
the install prefix on sys.path, it finds its libchatterlab, SUNDIALS and the shipped studies."""

import os
import subprocess
import sys
from pathlib import Path

import pytest


def test_installed_package_works_from_any_directory(tmp_path):
    build = os.environ.get("CHATTERLAB_BUILD_DIR")
    cmake = os.environ.get("CMAKE_COMMAND")
    if not build or not cmake:
        pytest.fail("CHATTERLAB_BUILD_DIR / CMAKE_COMMAND are not set: run through CTest")
    prefix = tmp_path / "site-packages"
    install = subprocess.run([cmake, "--install", build, "--component", "python", "--prefix", str(prefix)],
                             capture_output=True, text=True)
    assert install.returncode == 0, install.stderr
    script = "\n".join([
        "import pathlib, chatterlab",
        "print(chatterlab.__file__)",
        "studies = chatterlab.shipped_studies()",
        "print(len(studies), all(pathlib.Path(f).is_file() for f, _ in studies))",
        "[band] = [f for f, _ in studies if f.endswith('thompson_band.toml')]",
        "run = chatterlab.run_study(band, 'out', threads=1, plots=False, progress=False)",
        "print(run.exit_code, run.points)",
    ])
    environment = {key: value for key, value in os.environ.items() if key not in ("PYTHONPATH", "LD_LIBRARY_PATH")}
    environment["PYTHONPATH"] = str(prefix)
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=tmp_path,
                         env=environment)
    assert run.returncode == 0, run.stderr
    file, studies, result = run.stdout.splitlines()
    assert Path(file).parent == prefix / "chatterlab"
    count, all_exist = studies.split()
    assert int(count) > 20 and all_exist == "True"
    assert result.split()[0] == "0" and int(result.split()[1]) > 1
