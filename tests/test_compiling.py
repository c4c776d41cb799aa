"""A first run says that it compiles: on the terminal through the CLI, on the log from Python."""

import logging
import time

import numba
import numpy as np

from visviva import _compiling


def _wait_until_done(lines: list[str], timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while not any(line.startswith("compiled ") for line in lines):
        assert time.monotonic() < deadline, lines
        time.sleep(0.05)


def _quiet() -> None:
    """Wait until a burst of compilations (another test's) has ended: a new one starts here."""
    deadline = time.monotonic() + 60.0
    while _compiling._WATCH.ticker is not None:
        assert time.monotonic() < deadline
        time.sleep(0.05)


def test_a_compilation_is_announced_counted_and_logged(caplog):
    _compiling.watch_compiles()
    _quiet()
    lines: list[str] = []
    transient: list[str] = []
    _compiling.watch_compiles()
    _compiling.tell(lambda line, passing: (transient if passing else lines).append(line))
    try:
        with caplog.at_level(logging.INFO, logger="visviva"):

            @numba.njit(cache=False)
            def inner(x):
                return x * 2.0

            @numba.njit(cache=False)
            def outer(x):
                return inner(x) + 1.0

            assert outer(np.float64(1.5)) == 4.0  # compiles outer, and inner inside it
            _wait_until_done(lines)
    finally:
        _compiling.tell(None)
    # The first burst of the process says why it waits; later ones (other tests') say more.
    assert lines[0] in (_compiling.STARTED + "…", "compiling more kernels…")
    # Both functions were compiled in one burst: the callee inside its caller.
    assert lines[-1].startswith("compiled 2 functions in ")
    logged = [r.getMessage() for r in caplog.records if r.name == "visviva"]
    assert logged == lines  # the log says what the terminal says, without the ticking line


def test_without_a_writer_the_python_api_only_logs(caplog):
    _compiling.watch_compiles()
    _quiet()
    _compiling.tell(None)  # a script: nothing on the terminal, INFO lines on "visviva"
    with caplog.at_level(logging.INFO, logger="visviva"):

        @numba.njit(cache=False)
        def square(x):
            return x * x

        assert square(np.int64(3)) == 9
        deadline = time.monotonic() + 30.0
        while not any(r.getMessage().startswith("compiled ") for r in caplog.records):
            assert time.monotonic() < deadline
            time.sleep(0.05)
