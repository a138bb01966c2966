"""``hydroarm fmu --check FILE.fmu`` (issue 33): what a target lacks, one line each, exit 2;
an FMU that runs here, exit 0. The FMU is loaded in a fresh process, so a missing hydroarm is
reported instead of crashing the checker."""

import zipfile
from pathlib import Path

import pytest

from hydroarm.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _errors(capsys):
    return [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]


def test_not_an_fmu_is_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.fmu"
    bad.write_text("not a zip")
    assert main(["fmu", "--check", str(bad)]) == 2
    assert _errors(capsys) == [f"hydroarm: error: {bad}: is not an FMU (not a zip archive)"]
    assert main(["fmu", "--check", str(tmp_path / "nope.fmu")]) == 2
    assert _errors(capsys) == [f"hydroarm: error: {tmp_path / 'nope.fmu'}: no such file"]
    empty = tmp_path / "empty.fmu"
    with zipfile.ZipFile(empty, "w") as z:
        z.writestr("readme.txt", "x")
    assert main(["fmu", "--check", str(empty)]) == 2
    assert _errors(capsys) == [f"hydroarm: error: {empty}: is not an FMU (no modelDescription.xml)"]


def test_check_and_config_together_are_refused(tmp_path, capsys):
    assert main(["fmu", "--check", "x.fmu", "--config", str(EXAMPLES / "load6_raise.toml")]) == 2
    (line,) = _errors(capsys)
    assert line.startswith("hydroarm: error: --check: ")


def test_fmu_without_config_or_check_is_one_line(capsys):
    assert main(["fmu"]) == 2
    (line,) = _errors(capsys)
    assert line.startswith("hydroarm: error: --config: is required")


@pytest.fixture(scope="module")
def joint_fmu(tmp_path_factory):
    pytest.importorskip("fmpy")
    pytest.importorskip("pythonfmu")
    import hydroarm as ha

    out = tmp_path_factory.mktemp("fmucheck") / "servo.fmu"
    ha.export_fmu(EXAMPLES / "load6_raise.toml", out)
    return out


@pytest.mark.slow
def test_an_fmu_that_runs_here(joint_fmu, capsys):
    assert main(["fmu", "--check", str(joint_fmu)]) == 0
    out = capsys.readouterr()
    assert out.err == ""
    assert "HydroarmJoint, FMI 2.0 co-simulation" in out.out
    assert "instantiated, initialised and stepped 1 ms in a fresh process" in out.out
    assert "must preload" in out.out  # what a non-Python host needs
    assert out.out.rstrip().endswith(f"{joint_fmu}: runs on this machine")


@pytest.mark.slow
def test_hydroarm_missing_is_reported_not_a_crash(joint_fmu, tmp_path, monkeypatch):
    """The fresh process cannot import hydroarm (hidden by a sitecustomize): one problem line,
    found before the FMU is loaded."""
    from hydroarm.fmu.check import check_fmu

    hide = tmp_path / "hide"
    hide.mkdir()
    (hide / "sitecustomize.py").write_text(
        "import sys\n"
        "class _Hide:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] == 'hydroarm':\n"
        "            raise ImportError('no hydroarm here')\n"
        "sys.meta_path.insert(0, _Hide())\n"
    )
    import os

    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(hide), os.environ.get("PYTHONPATH", "")]))
    problems, facts = check_fmu(joint_fmu)
    assert len(problems) == 1
    assert "cannot import hydroarm" in problems[0] and "no hydroarm here" in problems[0]


def test_no_binary_for_this_platform(joint_fmu, tmp_path, capsys):
    other = tmp_path / "win.fmu"
    with zipfile.ZipFile(joint_fmu) as src, zipfile.ZipFile(other, "w") as dst:
        for item in src.infolist():
            name = item.filename
            if name.startswith("binaries/linux64/"):
                name = "binaries/win64/" + name.split("/", 2)[2]
            elif name.startswith("binaries/") and not name.startswith("binaries/win64/"):
                continue
            dst.writestr(name, src.read(item))
    assert main(["fmu", "--check", str(other)]) == 2
    (line,) = _errors(capsys)
    assert "no binary for this platform" in line and "win64" in line
