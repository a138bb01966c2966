import pytest

import hydroarm as ha


@pytest.fixture(scope="session")
def printed():
    return ha.parameter_set("paper-printed")


@pytest.fixture(scope="session")
def calibrated():
    return ha.parameter_set("paper-calibrated")
