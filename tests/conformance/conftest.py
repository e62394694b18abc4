"""Collects the cells' results and, at the end of the session, writes docs/INTEROP.md's
matrix (and baseline.json when CONFORMANCE_WRITE_BASELINE=1)."""
import json
import os
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from matrix import NOT_RUNNABLE, write_docs  # noqa: E402

_results = {}


@pytest.fixture(scope="session")
def matrix_results():
    return _results


def pytest_sessionfinish(session, exitstatus):
    if not _results:
        return
    if os.environ.get("CONFORMANCE_NO_DOCS") != "1":
        write_docs(_results, NOT_RUNNABLE)
    if os.environ.get("CONFORMANCE_WRITE_BASELINE") == "1":
        path = Path(__file__).resolve().parent / "baseline.json"
        base = json.loads(path.read_text()) if path.exists() else {}
        for (master, rack), res in _results.items():
            base.setdefault(master, {})[rack] = {
                step: r["result"] for step, r in res["steps"].items()}
        path.write_text(json.dumps(base, indent=1, sort_keys=True) + "\n")
