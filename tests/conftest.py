import copy
import fcntl
import os
import pickle
import shutil

import pytest

import hydroarm as ha
import hydroarm.paper.validate as validate_module
from hydroarm.paper.reproduce import reproduce


@pytest.fixture(scope="session")
def printed():
    return ha.parameter_set("paper-printed")


@pytest.fixture(scope="session")
def calibrated():
    return ha.parameter_set("paper-calibrated")


_VALIDATION = []  # what reproduce's validation step returned in the `repro` run


def _reproduce_recorded(out):
    """`reproduce` into ``out``, its validation step's call recorded in `_VALIDATION`."""
    real = getattr(validate_module, "compute", None)

    def recording(*args, **kwargs):
        result = real(*args, **kwargs)
        _VALIDATION.append((args, kwargs, result))
        return result

    # the run is unchanged: the validation is computed as always, its result only recorded
    with pytest.MonkeyPatch.context() as mp:
        if real is not None:
            mp.setattr(validate_module, "compute", recording)
        return reproduce(out)


@pytest.fixture(scope="session")
def repro(tmp_path_factory):
    """One full `hydroarm reproduce` run (output folder, returned data), shared by tests.

    Under pytest-xdist the run is made once for all workers (a full reproduce is ~40 s of one
    core; the tests that use it land on both workers): the first worker to need it runs it,
    under a lock, and leaves its folder and pickled data (with the validation call recorded)
    in the run's shared temporary folder; another worker waits for the lock and starts from a
    copy of that folder (its own: tests write into it) and the unpickled data."""
    out = tmp_path_factory.mktemp("repro") / "reproduction"
    if "PYTEST_XDIST_WORKER" not in os.environ:
        out.mkdir()
        (out / "notes.txt").write_text("mine")  # a user's file: must survive
        return out, _reproduce_recorded(out)
    shared = tmp_path_factory.getbasetemp().parent / "repro-shared"
    with open(f"{shared}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file is closed
        if (shared / "data.pickle").exists():
            shutil.copytree(shared / "reproduction", out)
            data, validation = pickle.loads((shared / "data.pickle").read_bytes())
            _VALIDATION.extend(validation)
            return out, data
        out.mkdir()
        (out / "notes.txt").write_text("mine")  # a user's file: must survive
        data = _reproduce_recorded(out)
        shutil.copytree(out, shared / "reproduction")
        (shared / "data.pickle").write_bytes(pickle.dumps((data, _VALIDATION)))
        return out, data


@pytest.fixture(scope="session")
def reproduce_validation(repro):
    """The result of reproduce's validation step (measured arm against Table I, stall, what-ifs,
    about half of a reproduce's time) in the `repro` run, or None if reproduce no longer makes
    that one call (with ``leave_one_out=False``, validate's refits left out). Tests of what
    reproduce does *around* its computations (failures, signals, reruns) reuse it instead of
    computing it again; the numbers themselves are tested through `repro`."""
    if len(_VALIDATION) == 1 and _VALIDATION[0][:2] == ((), {"leave_one_out": False}):
        return _VALIDATION[0][2]
    return None


@pytest.fixture
def reuse_validation(reproduce_validation, monkeypatch):
    """In this test, reproduce's validation step returns (a copy of) the `repro` run's result
    at once."""
    if reproduce_validation is not None:
        monkeypatch.setattr(
            validate_module,
            "compute",
            lambda **kw: copy.deepcopy(reproduce_validation),
        )
    return reproduce_validation


# the compile notice (one stderr line when numba compiles a kernel its cache lacks) is
# silenced for the suite: on a fresh clone's cold cache it would land in the stderr that the
# error-contract tests check line by line; tests/test_compile_notice.py turns it on itself
os.environ.setdefault("HYDROARM_COMPILE_NOTICE", "0")

#: set to 1 to run the tests marked ``long`` (minutes each: statistical coverage studies)
LONG_TESTS = os.environ.get("HYDROARM_LONG_TESTS") == "1"


def pytest_collection_modifyitems(config, items):
    """A test that needs a full reproduce (`repro`, ~40 s, once per process) is slow; a test
    marked ``long`` (minutes: a coverage study of many fits) runs only with
    HYDROARM_LONG_TESTS=1, so that the suite stays within its 10 minutes on the 2-core
    machine (docs/fit.md says how each was measured)."""
    skip_long = pytest.mark.skip(reason="minutes long: run with HYDROARM_LONG_TESTS=1")
    for item in items:
        if "repro" in item.fixturenames:
            item.add_marker(pytest.mark.slow)
        if "long" in item.keywords and not LONG_TESTS:
            item.add_marker(skip_long)
