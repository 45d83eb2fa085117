"""Shared pytest configuration: heavy finite-element cases are opt-in (--runslow); the
``shipped_client`` fixture (the app over the shipped data, one per test module); the
explorer's browser fixtures ``browser`` and ``watched`` (tests/explorer_browser.py; each
browser test module gives its own ``server``); ``no_curve_gps`` for the emulator file's
damage tests (a damage refused before any curve GP is factorised).

Named ``shipped_client``, not ``client``: several modules define their own ``client``
over fakes or a temporary database, and a conftest fixture of that name would be
shadowed there silently.
"""

import os

# before anything imports numpy (the explorer's fixtures below do): its OpenBLAS reads
# this when it loads, and the suite's subprocesses inherit it (pytest_configure)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import pytest  # noqa: E402
from explorer_browser import browser_fixture, watched_fixture  # noqa: E402,F401 - registered here

_BLAS_LIMIT = []


def pytest_configure(config: pytest.Config) -> None:
    """numpy's OpenBLAS on one thread for the run and its subprocesses: the suite's dense
    algebra is small (GP fits of <= 600 designs), and on a shared 2-core machine two
    OpenBLAS threads spin-wait for each other (a GP-fitting test took 117 s instead of 7 s
    while a precompute job used both cores). MKL (the solver's PARDISO) is left alone:
    limiting it after PARDISO has run on two threads crashes (benchmarks/RESULTS.md)."""
    from threadpoolctl import ThreadpoolController

    _BLAS_LIMIT.append(ThreadpoolController().select(internal_api="openblas").limit(limits=1))


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--runslow", action="store_true", default=False,
                     help="also run tests marked slow (heavy FE cases)")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if config.getoption("--runslow"):
        return
    skip = pytest.mark.skip(reason="slow FE case: run with --runslow")
    for item in items:
        # the marker, not the keyword: keywords hold the path's parts too, and a checkout
        # below a folder named "slow" skipped every test
        if item.get_closest_marker("slow") is not None:
            item.add_marker(skip)


@pytest.fixture(scope="module")
def shipped_client(tmp_path_factory):
    """A TestClient of the app over the shipped database, emulator and exponential file
    (service/data/), with its own temporary models directory."""
    from fastapi.testclient import TestClient
    from service_fakes import settings_for

    from service.app import create_app
    from service.settings import DATA_DIR

    tmp = tmp_path_factory.mktemp("shipped")
    app = create_app(settings_for(tmp, emulator_path=DATA_DIR / "emulator.json",
                                  db_path=DATA_DIR / "curves.h5",
                                  surrogate_path=DATA_DIR / "surrogate.json"))
    with TestClient(app) as c:
        yield c


@pytest.fixture(scope="session")
def shipped_emulator_saved_and_loaded(tmp_path_factory):
    """``(shipped, back)``: the shipped emulator, and the same saved with ``save_emulator``
    and loaded again from that file. One round trip per test process: each costs ~13 s
    (a 30 MB write, and a load that factorises every GP again)."""
    from service.settings import DATA_DIR
    from surrogate.emulator import load_emulator
    from surrogate.emulator.file import save_emulator

    shipped = load_emulator(DATA_DIR / "emulator.json")
    path = save_emulator(shipped, tmp_path_factory.mktemp("round_trip") / "e.json")
    return shipped, load_emulator(path)


@pytest.fixture(scope="session")
def shipped_records():
    """Every record of the shipped database (service/data/curves.h5), in key order, read
    once per test process: reading all 2403 takes ~30 s (~12 ms a record, most of it
    HDF5 attributes), which seven tests paid each before."""
    from service.settings import DATA_DIR
    from solver.store import CurveStore

    with CurveStore(DATA_DIR / "curves.h5") as db:
        return tuple(db.records())


@pytest.fixture
def no_curve_gps(monkeypatch):
    """``with no_curve_gps():`` -- inside the block ``emulator_from_dict`` may not build a
    pair's curve GPs (AssertionError, not SurrogateFileError): a damage the loader checks
    before that factorisation (~0.4-0.9 s a pair) is refused there, and at once."""
    import contextlib

    import surrogate.emulator.file as emulator_file

    def unbuilt(_):
        raise AssertionError("a pair's curve GPs were factorised before the damage was found")

    @contextlib.contextmanager
    def block():
        with monkeypatch.context() as m:
            m.setattr(emulator_file, "vector_gp_from_dict", unbuilt)
            yield

    return block
