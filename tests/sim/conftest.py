"""Fixtures for the canfdi-sim command-line tests (tests/sim)."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import Callable, Sequence

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "host_sim" / "scenarios"
DBC = ROOT / "dbc" / "canfdi.dbc"


def _cli_path() -> Path:
    env = os.environ.get("CANFDI_SIM")
    return Path(env) if env else ROOT / "build" / "bin" / "canfdi-sim"


@pytest.fixture(scope="session")
def cli() -> Path:
    path = _cli_path()
    if not path.exists():
        pytest.fail(f"{path} not built (run `make {path.relative_to(ROOT)}`)")
    return path


RunFn = Callable[..., subprocess.CompletedProcess]


@pytest.fixture(scope="session")
def run(cli: Path) -> RunFn:
    """Runs canfdi-sim with arguments; returns the completed process."""

    def _run(args: Sequence[str], check: bool = True) -> subprocess.CompletedProcess:
        proc = subprocess.run([str(cli), *args], cwd=ROOT, capture_output=True, text=True,
                              timeout=300)
        # Never a crash: sanitizer reports or signals are failures whatever
        # the exit status.
        assert proc.returncode >= 0, f"killed by signal {-proc.returncode}: {proc.stderr}"
        assert "runtime error" not in proc.stderr and "AddressSanitizer" not in proc.stderr, \
            proc.stderr
        if check:
            assert proc.returncode == 0, proc.stderr
        return proc

    return _run


@pytest.fixture(scope="session")
def python() -> str:
    return sys.executable
