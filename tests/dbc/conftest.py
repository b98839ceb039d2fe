"""Shared fixtures of the CAN database checks (run by `make dbc-test`)."""
from __future__ import annotations

import logging
import os
import shlex
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
# The tools package is installed editable by `make deps`; fall back to the
# checkout so the checks also run before the venv has been refreshed.
try:
    import canfdi  # noqa: F401
except ImportError:
    sys.path.insert(0, str(ROOT / "tools"))
sys.path.insert(0, str(ROOT / "dbc"))

DBC = ROOT / "dbc" / "canfdi.dbc"


def make_flags(name: str) -> list[str]:
    """A flag set of mk/flags.mk (`make -s print-NAME`), as arguments."""
    res = subprocess.run(["make", "-s", "--no-print-directory", "-C", str(ROOT), f"print-{name}"],
                         capture_output=True, text=True, check=True)
    return shlex.split(res.stdout)


def load_strict(path: Path = DBC):
    """Load the DBC in strict mode with every warning promoted to an error."""
    import cantools

    class _Fail(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            raise AssertionError(f"cantools logged: {record.getMessage()}")

    handler = _Fail(level=logging.WARNING)
    logger = logging.getLogger("cantools")
    logger.addHandler(handler)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            return cantools.database.load_file(str(path), strict=True)
    finally:
        logger.removeHandler(handler)


@pytest.fixture(scope="session")
def db():
    return load_strict()


def build_harness(tmp_path_factory, extra: list[str]):
    out = tmp_path_factory.mktemp("harness") / "harness"
    cc = os.environ.get("CC", "gcc")
    # The host build of the firmware (warnings, ASan/UBSan, asserts): the
    # generated codecs must compile under it unchanged. Its include folders
    # are relative to the repository.
    cmd = [cc, *make_flags("HOST_CFLAGS"), *extra, "-I" + str(ROOT / "host_sim" / "gen"),
           str(ROOT / "tests/dbc/harness.c"), str(ROOT / "firmware/comm/canfdi_e2e.c"),
           str(ROOT / "firmware/comm/gen/canfdi_msg.c"), str(ROOT / "host_sim/gen/canfdi_sim_msg.c"),
           "-o", str(out)]
    subprocess.run(cmd, check=True, capture_output=True, text=True, cwd=ROOT)

    def run(lines: list[str]) -> list[str]:
        res = subprocess.run([str(out)], input="\n".join(lines) + "\n", capture_output=True,
                             text=True, check=True)
        return res.stdout.splitlines()
    return run


@pytest.fixture(scope="session")
def harness(tmp_path_factory):
    """tests/dbc/harness.c built with the project's flags; returns a runner."""
    return build_harness(tmp_path_factory, [])


@pytest.fixture(scope="session")
def harness_bitwise(tmp_path_factory):
    """The same with the table-free CRC (CANFDI_CFG_E2E_CRC_TABLE 0)."""
    return build_harness(tmp_path_factory, ["-DCANFDI_CFG_E2E_CRC_TABLE=0"])
