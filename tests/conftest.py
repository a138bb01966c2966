import pytest

import hydroarm as ha
from hydroarm.paper.reproduce import reproduce


@pytest.fixture(scope="session")
def printed():
    return ha.parameter_set("paper-printed")


@pytest.fixture(scope="session")
def calibrated():
    return ha.parameter_set("paper-calibrated")


@pytest.fixture(scope="session")
def repro(tmp_path_factory):
    """One full `hydroarm reproduce` run (output folder, returned data), shared by tests."""
    out = tmp_path_factory.mktemp("repro") / "reproduction"
    out.mkdir()
    (out / "notes.txt").write_text("mine")  # a user's file: must survive
    data = reproduce(out)
    return out, data
