"""tools/run-each, the runner make test uses for the unit programs, the SIL scenarios and the
reference programs: every item run, failures counted and named, each run's output printed whole
even when runs go side by side, bad usage refused."""
from __future__ import annotations

import subprocess
from pathlib import Path

from canfdi import REPO_ROOT

RUN_EACH = REPO_ROOT / "tools" / "run-each"


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(RUN_EACH), *args], capture_output=True, text=True, timeout=60)


def test_all_pass() -> None:
    r = run("demo", "2", "echo", "item", "--", "a", "b c", "d")
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[-1] == "demo: 3 passed, 0 failed"
    for item in ("a", "b c", "d"):
        assert f"ok    {item}\n      item {item}\n" in r.stdout


def test_a_failure_is_counted_named_and_fails_the_run(tmp_path: Path) -> None:
    prog = tmp_path / "prog.sh"
    prog.write_text('#!/bin/sh\necho "ran $1"\n[ "$1" != bad ] || exit 3\n')
    prog.chmod(0o755)
    r = run("demo", "2", str(prog), "--", "good", "bad", "good2")
    assert r.returncode == 1
    assert "FAIL  bad (exit status 3)\n      ran bad\n" in r.stdout
    assert "demo: 2 passed, 1 failed" in r.stdout
    assert r.stdout.rstrip().endswith("  failed: bad")


def test_outputs_side_by_side_do_not_mix(tmp_path: Path) -> None:
    prog = tmp_path / "slow.sh"
    prog.write_text('#!/bin/sh\nfor i in 1 2 3 4 5; do echo "$1 line $i"; sleep 0.05; done\n')
    prog.chmod(0o755)
    r = run("demo", "3", str(prog), "--", "x", "y", "z")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    for item in ("x", "y", "z"):
        at = lines.index(f"ok    {item}")
        assert lines[at + 1:at + 6] == [f"      {item} line {i}" for i in range(1, 6)]


def test_bad_usage() -> None:
    assert run("demo", "0", "--", "a").returncode == 2
    assert run("demo", "x", "--", "a").returncode == 2
    r = run("demo", "2", "echo")
    assert r.returncode == 2 and "usage" in r.stderr
