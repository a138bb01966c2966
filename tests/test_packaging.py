"""The built wheel carries what an installed hydroarm needs: its data files, ``py.typed``, the
example files (``hydroarm examples``), the LICENSE, and one version (written in pyproject.toml
only, read from the package metadata); installed in a fresh virtual environment, the README's
commands run from it outside the repository (issue 33)."""

import json
import os
import site
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

import hydroarm

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_version_from_metadata_only():
    assert hydroarm.__version__ == PYPROJECT["project"]["version"]
    written = [
        p
        for p in (ROOT / "hydroarm").rglob("*.py")
        if PYPROJECT["project"]["version"] in p.read_text()
    ]
    assert not written, f"the version is written in {written}"


@pytest.mark.slow
def test_wheel_contents(tmp_path):
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--quiet",
            "--no-deps",
            "-w",
            str(tmp_path),
            str(ROOT),
        ],
        check=True,
        capture_output=True,
    )
    (wheel,) = tmp_path.glob("hydroarm-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    examples = {f"hydroarm/examples/{p.name}" for p in (ROOT / "examples").iterdir() if p.is_file()}
    assert examples <= names, examples - names
    data = ROOT / "hydroarm" / "data"
    expected = {"hydroarm/py.typed"} | {
        f"hydroarm/data/{p.relative_to(data)}"
        for p in data.rglob("*")
        if p.suffix in (".toml", ".csv")
    }
    assert expected <= names, expected - names
    metadata = next(n for n in names if n.endswith(".dist-info/METADATA"))
    text = zipfile.ZipFile(wheel).read(metadata).decode()
    assert f"Version: {PYPROJECT['project']['version']}" in text
    assert "License-Expression: BSD-3-Clause" in text
    assert "Classifier: Topic :: Scientific/Engineering" in text
    (license,) = [n for n in names if n.endswith(".dist-info/licenses/LICENSE")]
    assert zipfile.ZipFile(wheel).read(license) == (ROOT / "LICENSE").read_bytes()


def test_license_is_bsd_3_clause():
    text = (ROOT / "LICENSE").read_text()
    assert PYPROJECT["project"]["license"] == "BSD-3-Clause"
    assert PYPROJECT["project"]["license-files"] == ["LICENSE"]
    assert text.startswith("BSD 3-Clause License")
    assert "Copyright (c) the hydroarm developers" in text
    assert "Neither the name of the copyright holder" in text  # clause 3


def test_every_package_is_listed():
    """pyproject.toml lists the packages (the examples folder is mapped in as
    hydroarm.examples): every folder of hydroarm/ with Python or data files must be there."""
    listed = set(PYPROJECT["tool"]["setuptools"]["packages"])
    on_disk = {
        ".".join(d.relative_to(ROOT).parts)
        for d in [ROOT / "hydroarm", *(ROOT / "hydroarm").rglob("*")]
        if d.is_dir()
        and d.name != "__pycache__"
        and any(f.suffix in (".py", ".toml", ".csv") for f in d.iterdir())
    }
    assert on_disk | {"hydroarm.examples"} == listed
    assert PYPROJECT["tool"]["setuptools"]["package-dir"] == {"hydroarm.examples": "examples"}


@pytest.mark.slow
@pytest.mark.skipif(
    os.environ.get("HYDROARM_WHEEL_CHECKED") == "1",
    reason="CI's wheel step (.ci/wheel) ran these commands from the wheel it built",
)
def test_wheel_in_a_fresh_venv_runs_the_readme_commands(tmp_path):
    """pip install the wheel into a fresh venv (no download: --no-deps, the dependencies are
    this environment's, by a path file), then from a folder outside the repository
    `hydroarm examples --copy ex` and `hydroarm simulate --config ex/position_servo.toml
    --metrics`. About a minute of CPU, most of it numba compiling the servo's kernels for the
    new install; `.ci/run` runs the same commands in its wheel step (`.ci/wheel`) and then
    skips this copy."""
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(tmp_path), str(ROOT)],
        check=True,
        capture_output=True,
    )
    (wheel,) = tmp_path.glob("hydroarm-*.whl")
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], check=True)
    py = venv / "bin" / "python"
    purelib = subprocess.run(
        [py, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        check=True,
        env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"},
        capture_output=True,
        text=True,
    ).stdout.strip()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}  # no checkout on the path
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "numba-cache")
    subprocess.run(
        [py, "-m", "pip", "install", "-q", "--no-deps", "--no-index", str(wheel)],
        check=True,
        capture_output=True,
        env=env,
    )
    # then this environment's packages (numpy, numba, ...) after the venv's own: a plain path
    # line, so that an editable hydroarm there (its finder is installed by a .pth) is not used
    (Path(purelib) / "_hydroarm_test_deps.pth").write_text(site.getsitepackages()[0] + "\n")
    work = tmp_path / "elsewhere"
    work.mkdir()
    hydroarm = str(venv / "bin" / "hydroarm")

    def run(*args):
        return subprocess.run(
            args, cwd=work, env=env, capture_output=True, text=True, check=False, timeout=300
        )

    where = run(str(py), "-c", "import hydroarm; print(hydroarm.__file__, hydroarm.__version__)")
    assert where.stdout.split() == [
        f"{purelib}/hydroarm/__init__.py",
        PYPROJECT["project"]["version"],
    ], where.stderr
    r = run(hydroarm, "examples", "--copy", "ex")
    assert r.returncode == 0, r.stderr
    assert (work / "ex" / "position_servo.toml").read_bytes() == (
        ROOT / "examples" / "position_servo.toml"
    ).read_bytes()
    r = run(hydroarm, "simulate", "--config", "ex/position_servo.toml", "--metrics")
    assert r.returncode == 0, r.stderr
    # the file steps the reference to 0.7 m; it ends 8 mm past it (0.708 m with this version:
    # the run under its load), so 10 mm says it ran and followed the step
    assert abs(json.loads(r.stdout)["final_position_m"] - 0.7) < 0.01


def test_hydroarm_imported_from_where_ci_says():
    """.ci/wheel runs tests from the unpacked sdist twice: against the wheel installed in a
    fresh venv and against the sdist's own source; HYDROARM_IMPORTED_FROM names the folder
    (site-packages, or the unpacked sdist) whose hydroarm this session must have imported."""
    where = os.environ.get("HYDROARM_IMPORTED_FROM")
    if not where:
        pytest.skip("HYDROARM_IMPORTED_FROM is set by .ci/wheel only")
    assert Path(hydroarm.__file__).resolve() == Path(where).resolve() / "hydroarm" / "__init__.py"
