"""The README and docs stay true to the code: their Python blocks run, their example files and
scripts work, and every package path or file they name exists."""

import importlib
import os
import re
import runpy
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"```(\w*)\n(.*?)```", re.S)


def python_blocks(path: Path) -> list[str]:
    return [body for lang, body in FENCE.findall(path.read_text()) if lang == "python"]


def block_ids(path: Path) -> list[str]:
    return [f"{path.name}:{i}" for i, _ in enumerate(python_blocks(path))]


README_BLOCKS = python_blocks(ROOT / "README.md")


@pytest.mark.slow
@pytest.mark.parametrize("index", range(len(README_BLOCKS)), ids=block_ids(ROOT / "README.md"))
def test_readme_python_block_runs(index, tmp_path, monkeypatch):
    """Each ```python block of the README runs as written, from a folder that has `examples/`."""
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    monkeypatch.chdir(tmp_path)
    exec(compile(README_BLOCKS[index], f"README.md block {index}", "exec"), {})


def test_readme_has_python_blocks():
    assert len(README_BLOCKS) >= 2


# `hydroarm/...`, `docs/...`, `examples/...`, `benchmarks/...`, `tests/...` in backticks
PATH_REF = re.compile(r"`((?:hydroarm|docs|examples|benchmarks|tests|\.ci)/[\w./-]*)`")
# hydroarm.module.name in backticks (modules and attributes)
DOTTED_REF = re.compile(r"`(hydroarm(?:\.\w+)+)")


@pytest.mark.parametrize("doc", DOCS, ids=[d.name for d in DOCS])
def test_docs_name_only_paths_that_exist(doc):
    missing = [p for p in PATH_REF.findall(doc.read_text()) if not (ROOT / p).exists()]
    assert not missing, f"{doc.name} names paths that do not exist: {missing}"


@pytest.mark.parametrize("doc", DOCS, ids=[d.name for d in DOCS])
def test_docs_name_only_modules_that_exist(doc):
    missing = []
    for ref in set(DOTTED_REF.findall(doc.read_text())):
        parts = ref.split(".")
        # the longest importable module prefix, then attributes
        for i in range(len(parts), 0, -1):
            try:
                obj = importlib.import_module(".".join(parts[:i]))
            except ImportError:
                continue
            try:
                for name in parts[i:]:
                    obj = getattr(obj, name)
            except AttributeError:
                missing.append(ref)
            break
        else:
            missing.append(ref)
    assert not missing, f"{doc.name} names modules or attributes that do not exist: {missing}"


@pytest.mark.slow
def test_tolerance_histogram_example(tmp_path):
    """examples/tolerance_study.toml → sweep → examples/tolerance_histogram.py → a PNG
    (the study cut to 24 scenarios and 0.3 s so that it runs in seconds)."""
    text = (ROOT / "examples" / "tolerance_study.toml").read_text()
    small = re.sub(r"(?m)^n = \d+", "n = 24", text)
    small = re.sub(r'(?m)^duration = "[^"]+"', 'duration = "0.3 s"', small)
    assert small != text
    config = tmp_path / "study.toml"
    config.write_text(small)
    csv, png = tmp_path / "tolerance.csv", tmp_path / "tolerance.png"
    env = {**os.environ, "MPLBACKEND": "Agg"}
    cmd = [sys.executable, "-m", "hydroarm.cli", "sweep", "--config", str(config)]
    subprocess.run([*cmd, "--out", str(csv)], check=True, env=env, capture_output=True)
    argv = sys.argv
    try:
        sys.argv = ["tolerance_histogram.py", str(csv), str(png)]
        runpy.run_path(str(ROOT / "examples" / "tolerance_histogram.py"), run_name="__main__")
    finally:
        sys.argv = argv
    assert png.stat().st_size > 10_000
