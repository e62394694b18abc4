"""pytest plugin (entry point pytest11): the fixture `rackcat_line`, a fresh VirtualLine per
test, and the options --rackcat BIN / --rackcat-config FILE (RACKCAT_BIN, RACKCAT_CONFIG)."""
from __future__ import annotations

import os
from typing import Iterator

import pytest

from rackcat_line.line import LineError, VirtualLine


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("rackcat_line", "rackcat virtual line")
    group.addoption("--rackcat", default=None,
                    help="the rackcat binary (default: RACKCAT_BIN or rackcat on PATH)")
    group.addoption("--rackcat-config", default=None,
                    help="rack file for the line (default: RACKCAT_CONFIG or the built-in rack)")


@pytest.fixture
def rackcat_line(request: pytest.FixtureRequest) -> Iterator[VirtualLine]:
    """A running rackcat on a virtual line; `.master_iface` is the master's interface,
    `.control` the control API. Skips when not root."""
    if os.geteuid() != 0:
        pytest.skip("rackcat_line needs root (network namespace and veth pair)")
    # Read when the fixture runs, so a conftest.py may still set the environment.
    line = VirtualLine(
        rackcat=request.config.getoption("--rackcat") or os.environ.get("RACKCAT_BIN", "rackcat"),
        config=request.config.getoption("--rackcat-config") or os.environ.get("RACKCAT_CONFIG"))
    try:
        line.start()
    except LineError as e:
        pytest.fail(str(e))
    try:
        yield line
    finally:
        line.close()
