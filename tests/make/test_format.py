"""`make format FILES=...` (mk/format.mk) touches exactly the files named."""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

UGLY = "int f(int a){if(a){return 1;}return 0;}\n"
# The firmware's style (.clang-format): function braces on their own line,
# control statement braces attached, two-space indent.
PRETTY = "int f(int a)\n{\n  if (a) {\n    return 1;\n  }\n  return 0;\n}\n"


def make_format(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["make", "-s", "--no-print-directory", "-C", str(ROOT), "format", *args],
                          capture_output=True, text=True, timeout=600)


def test_without_files_it_refuses() -> None:
    res = make_format()
    assert res.returncode != 0
    assert "name the files to format" in res.stderr


def test_it_refuses_what_is_not_c(tmp_path: Path) -> None:
    doc = tmp_path / "notes.md"
    doc.write_text("# notes\n")
    res = make_format(f"FILES={doc}")
    assert res.returncode != 0
    assert "not a C/C++ source or header" in res.stderr
    assert doc.read_text() == "# notes\n"


@pytest.mark.skipif(shutil.which("clang-format") is None,
                    reason="clang-format is not installed (make format installs it on first use)")
def test_formats_only_the_named_file(tmp_path: Path) -> None:
    named = tmp_path / "named.c"
    other = tmp_path / "other.c"
    named.write_text(UGLY)
    other.write_text(UGLY)
    res = make_format(f"FILES={named}")
    assert res.returncode == 0, res.stdout + res.stderr
    assert named.read_text() == PRETTY
    assert other.read_text() == UGLY
