"""``hydroarm fmu --check FILE.fmu``: can this machine run an exported FMU? (issue 33)

The FMU is loaded in a fresh process (FMPy as the master, this Python as the FMU's
interpreter): instantiated, initialised and stepped once. What the target lacks is reported
one line each (a problem); what it has, and what other hosts need, as facts. A missing
hydroarm is found before the FMU is loaded: pythonfmu 0.7's runtime crashes its host after
the FMI error when the slave cannot be imported, and a crash of the fresh process is reported
as a problem too (never the checker's own).
"""

from __future__ import annotations

import json
import os
import platform
import re
import signal
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

CHECK_TIMEOUT_S = 600  # a cold first run compiles hydroarm's kernels (numba): minutes at most

# FMI 2.0 binaries folders (FMI 2.0 standard, section 2.1: platform names)
PLATFORMS = {
    ("Linux", "64bit"): "linux64",
    ("Windows", "64bit"): "win64",
    ("Darwin", "64bit"): "darwin64",
}

_CHILD = r"""
import json, os, sys
def emit(kind, text):
    print(json.dumps([kind, text]), flush=True)
path = sys.argv[1]
try:
    import fmpy
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
except Exception as e:
    emit("problem", f"FMPy cannot be imported ({e}): pip install 'hydroarm[fmu]'")
    sys.exit(0)
try:
    import hydroarm
except Exception as e:
    emit("problem", f"this Python ({sys.executable}) cannot import hydroarm, which the "
         f"FMU's slave runs ({type(e).__name__}: {e}): pip install hydroarm there")
    sys.exit(0)
emit("fact", f"host: FMPy {fmpy.__version__}; hydroarm {hydroarm.__version__} in "
     f"{sys.executable}")
md = read_model_description(path)
folder = extract(path)
fmu = FMU2Slave(guid=md.guid, unzipDirectory=folder,
                modelIdentifier=md.coSimulation.modelIdentifier, instanceName="check")
log = []
fmu.instantiate(loggingOn=True)
emit("stage", "instantiated")
fmu.setupExperiment(startTime=0.0)
fmu.enterInitializationMode()
fmu.exitInitializationMode()
emit("stage", "initialised")
fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=1e-3)
emit("ok", "stepped 1 ms")
sys.stdout.flush()
os._exit(0)  # no teardown: pythonfmu 0.7 may corrupt the heap at exit (docs/fmu.md)
"""


def _read(path: Path) -> tuple[list[str], list[str], ET.Element | None, list[str]]:
    """Problems, facts, the model description and the archive's names."""
    problems: list[str] = []
    facts: list[str] = []
    if not path.exists():
        return ["no such file"], facts, None, []
    if path.is_dir():
        return ["is a folder, not an .fmu file"], facts, None, []
    if not zipfile.is_zipfile(path):
        return ["is not an FMU (not a zip archive)"], facts, None, []
    with zipfile.ZipFile(path) as z:
        names = z.namelist()
        if "modelDescription.xml" not in names:
            return ["is not an FMU (no modelDescription.xml)"], facts, None, names
        try:
            md = ET.fromstring(z.read("modelDescription.xml"))
        except ET.ParseError as exc:
            return [f"modelDescription.xml is not XML ({exc})"], facts, None, names
    return problems, facts, md, names


def _libpython() -> str | None:
    """This Python's shared library, if it has one (what a non-Python host must preload)."""
    name = str(
        sysconfig.get_config_var("INSTSONAME") or sysconfig.get_config_var("LDLIBRARY") or ""
    )
    libdir = sysconfig.get_config_var("LIBDIR")
    shared = name.endswith((".so", ".dylib", ".dll")) or ".so." in name
    if not shared or not libdir:
        return None  # a static build (libpython3.x.a): no library to preload
    p = Path(libdir) / name
    return str(p) if p.exists() else None


def check_fmu(path, python: str | None = None, timeout: float = CHECK_TIMEOUT_S):
    """Check that ``path`` (an FMU of ``hydroarm fmu``) runs here. Returns ``(problems,
    facts)``: lines saying what the target lacks (empty when it runs) and what was found.
    ``python`` is the interpreter that hosts the check (default: this one)."""
    p = Path(path)
    problems, facts, md, names = _read(p)
    if md is None:
        return problems, facts
    version = md.get("fmiVersion", "?")
    tool = md.get("generationTool", "?")
    cs = md.find("CoSimulation")
    facts.append(
        f"{p.name}: {md.get('modelName', '?')}, FMI {version} "
        f"{'co-simulation' if cs is not None else 'model exchange'}, made by {tool}"
    )
    if version != "2.0":
        problems.append(f"FMI {version}: hydroarm's FMUs are FMI 2.0")
    if cs is None:
        problems.append("no co-simulation interface (hydroarm's FMUs are co-simulation)")
        return problems, facts
    here = PLATFORMS.get((platform.system(), platform.architecture()[0]))
    folders = sorted({n.split("/")[1] for n in names if n.startswith("binaries/") and "/" in n[9:]})
    if here not in folders:
        problems.append(
            f"no binary for this platform ({here or platform.system()}): the FMU has "
            f"{', '.join(folders) or 'none'}"
        )
        return problems, facts
    if "pythonfmu" in tool.lower() or any(n.startswith("resources/slavemodule") for n in names):
        facts.append(
            "the FMU runs Python: its host needs a Python with hydroarm installed (the FMU "
            "bundles pythonfmu's runtime; pythonfmu itself is not needed)"
        )
        lib = _libpython()
        facts.append(
            "a host that is not Python (OpenModelica, Dymola, Simulink) must preload "
            + (
                f"{lib} (e.g. LD_PRELOAD={lib})"
                if lib
                else "a libpython3 shared library: this Python has none (built without "
                "--enable-shared), so such hosts cannot use it"
            )
        )
    m = re.search(r"exported by hydroarm ([\w.+-]+)", _slave_text(p, names))
    if m:
        facts.append(f"exported by hydroarm {m.group(1).rstrip('.')}")
    problems += _run_child(p, python or sys.executable, timeout, facts)
    return problems, facts


def _slave_text(path: Path, names: list[str]) -> str:
    with zipfile.ZipFile(path) as z:
        return "\n".join(
            z.read(n).decode("utf-8", "replace")
            for n in names
            if n.startswith("resources/") and n.endswith(".py")
        )


def _run_child(path: Path, python: str, timeout: float, facts: list[str]) -> list[str]:
    env = dict(os.environ, MPLBACKEND="Agg")
    try:
        r = subprocess.run(
            [python, "-c", _CHILD, str(path.resolve())],
            capture_output=True,
            text=True,
            timeout=timeout,
            env=env,
        )
    except subprocess.TimeoutExpired:
        return [f"the FMU did not finish its first step within {timeout:g} s"]
    except OSError as exc:
        return [f"cannot start {python}: {exc.strerror or exc}"]
    problems: list[str] = []
    stage, ok = "loading", False
    for line in r.stdout.splitlines():
        try:
            kind, text = json.loads(line)
        except (ValueError, TypeError):
            continue
        if kind == "problem":
            problems.append(text)
        elif kind == "fact":
            facts.append(text)
        elif kind == "stage":
            stage = text
        elif kind == "ok":
            ok = True
            facts.append(f"the FMU was instantiated, initialised and {text} in a fresh process")
    if problems or ok:
        return problems
    err = [ln.strip() for ln in r.stderr.splitlines() if ln.strip()]
    last = next(
        (ln for ln in reversed(err) if "Error" in ln or "error" in ln), err[-1] if err else ""
    )
    if r.returncode < 0:
        how = f"crashed its host process ({signal.Signals(-r.returncode).name})"
    else:
        how = f"failed (exit status {r.returncode})"
    after = {
        "loading": "while loading",
        "instantiated": "after instantiation",
        "initialised": "in its first step",
    }.get(stage, stage)
    return [f"the FMU {how} {after}" + (f": {last[:200]}" if last else "")]
