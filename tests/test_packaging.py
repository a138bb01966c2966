"""The built wheel carries what an installed hydroarm needs: its data files, ``py.typed``, and
one version (written in pyproject.toml only, read from the package metadata)."""

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
