import pytest

from taichi_granular import runtime


@pytest.fixture(scope="session", autouse=True)
def ti_cpu():
    """One Taichi runtime for the whole session: CPU, double precision, seed 0."""
    runtime.init("cpu", "f64")
    yield
