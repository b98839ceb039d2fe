"""HIL tests: canfdi-ecu and canfdi-sim as processes on vcan0, driven by the
Python tools, with the scenario files the SIL tests use.

They need a SocketCAN vcan0. `make hil-test` runs this directory inside the
vcan sandbox (tools/vcan-run: User-Mode Linux where the host kernel has no
SocketCAN) with CANFDI_HIL_REQUIRED=1, so a missing vcan0 fails there
instead of skipping. By hand:

    tools/vcan-run .venv/bin/python -m pytest tests/hil -q

Inside the sandbox starting Python costs seconds, so everything runs in this
one pytest process: canfdi-scenario, canfdi-watch and canfdi-inject are
called in-process (their main(argv)); only the C programs and can-utils are
spawned. Recordings go to build/hil/test/. Helpers: hilutil.py.
"""
from __future__ import annotations

import os

import pytest

from hilutil import ECU, OUT, SIL, SIM, have_vcan


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    why = have_vcan()
    if why is None:
        return
    if os.environ.get("CANFDI_HIL_REQUIRED") == "1":
        raise pytest.UsageError(f"tests/hil: {why} (CANFDI_HIL_REQUIRED=1)")
    skip = pytest.mark.skip(reason=why)
    for item in items:
        if "tests/hil" in str(item.fspath):
            item.add_marker(skip)


@pytest.fixture(scope="session", autouse=True)
def built() -> None:
    for p in (ECU, SIM, SIL):
        if not p.is_file():
            pytest.fail(f"{p} is not built: run `make hil-test`")
    OUT.mkdir(parents=True, exist_ok=True)
