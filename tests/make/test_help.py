"""`make help` against README.md and the Makefile (run by `make help-test`).

Every `make X` that README.md documents, in a code span or a code block,
must be listed by `make help` and be a target of the Makefile (its own or
of a fragment); every target `make help` lists must exist too.
"""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

SPAN = re.compile(r"`([^`\n]+)`")
FENCE = re.compile(r"^```.*?^```", re.S | re.M)
HELP_LINE = re.compile(r"^\s+make ([A-Za-z0-9_.%-]+)")


def make_targets_in(command: str) -> list[str]:
    """Targets of one shell command line: the words after `make` that are
    neither options nor VAR=value assignments."""
    out: list[str] = []
    words = command.split()
    for i, w in enumerate(words):
        if w != "make" or (i > 0 and words[i - 1] not in ("$", "&&", ";", "||", "|")):
            continue
        skip = False
        for arg in words[i + 1:]:
            if arg.startswith("#") or arg in ("&&", ";", "||", "|"):
                break
            if skip:
                skip = False
            elif arg in ("-C", "-f", "-I", "-o", "-W"):
                skip = True  # the option's argument follows
            elif not arg.startswith("-") and "=" not in arg:
                out.append(arg)
    return out


def documented_targets(markdown: str) -> set[str]:
    """`make X` in code spans and in fenced code blocks."""
    found: set[str] = set()
    for block in FENCE.findall(markdown):
        for line in block.splitlines()[1:-1]:
            found.update(make_targets_in(line.strip()))
    for span in SPAN.findall(FENCE.sub("", markdown)):
        found.update(make_targets_in(span.strip()))
    return found


def help_targets() -> set[str]:
    res = subprocess.run(["make", "-s", "--no-print-directory", "-C", str(ROOT), "help"],
                         capture_output=True, text=True, timeout=120, check=True)
    return {m.group(1) for line in res.stdout.splitlines() if (m := HELP_LINE.match(line))}


def makefile_targets() -> tuple[set[str], list[re.Pattern[str]]]:
    """Explicit targets and pattern rules of make's database (make -p;
    -r leaves out make's built-in rules, which would match any name)."""
    res = subprocess.run(["make", "-p", "-r", "-s", "--no-print-directory", "-C", str(ROOT), "print-CC"],
                         capture_output=True, text=True, timeout=120, check=True)
    names: set[str] = set()
    patterns: list[re.Pattern[str]] = []
    # The rules section ("# Implicit Rules" .. the Files' stats) holds one
    # block per target, ended by a blank line. A target is real when make
    # can do something for it: it has prerequisites or a recipe (a name
    # that is only .PHONY would "do nothing" and succeed).
    rules = False
    block: list[str] = []

    def flush() -> None:
        if not block:
            return
        head = next((ln for ln in block if not ln.startswith("#")), "")
        m = re.match(r"^([^\s#=:][^:=]*?)::?(?!=)(.*)$", head)
        not_target = any(ln.startswith("# Not a target:") for ln in block)
        has_recipe = any(ln.startswith("#  recipe to execute") for ln in block)
        if m and not not_target and (m.group(2).strip() or has_recipe):
            for name in m.group(1).split():
                if "%" in name:
                    patterns.append(re.compile("^" + re.escape(name).replace("%", ".+") + "$"))
                else:
                    names.add(name)
        block.clear()

    for line in res.stdout.splitlines():
        if line.startswith("# Implicit Rules"):
            rules = True
        elif line.startswith("# files hash-table stats"):
            flush()
            rules = False
        if not rules:
            continue
        if line.strip():
            block.append(line)
        else:
            flush()
    flush()
    return names, patterns


def is_target(name: str, names: set[str], patterns: list[re.Pattern[str]]) -> bool:
    return name in names or any(p.match(name) for p in patterns)


def test_the_parser_finds_documented_targets() -> None:
    text = ("Run `make demo` or `make bench MODEL_LONGRUN_H=1`, `make -C dir x-y`; "
            "the tools make it a check.\n\n```sh\nmake all    # build\n"
            "make format FILES=\"a.c\" && make help\n```\n")
    assert documented_targets(text) == {"demo", "bench", "x-y", "all", "format", "help"}


def test_a_missing_target_would_be_reported() -> None:
    names, patterns = makefile_targets()
    assert not is_target("no-such-target", names, patterns)
    assert "no-such-target" not in help_targets()
    assert is_target("print-HOST_CFLAGS", names, patterns)


def test_readme_targets_are_in_help_and_in_the_makefile() -> None:
    documented = documented_targets((ROOT / "README.md").read_text())
    # the README documents at least its table's targets
    assert {"deps", "demo", "test", "firmware", "bench", "all", "clean", "help"} <= documented
    listed = help_targets()
    names, patterns = makefile_targets()
    assert sorted(documented - listed) == [], "documented in README.md, missing from make help"
    assert sorted(t for t in documented if not is_target(t, names, patterns)) == [], \
        "documented in README.md, not a target of the Makefile"


def test_help_lists_only_real_targets() -> None:
    names, patterns = makefile_targets()
    missing = sorted(t for t in help_targets() if not is_target(t, names, patterns))
    assert missing == [], "listed by make help, not a target of the Makefile"


def test_help_lists_every_test_step() -> None:
    res = subprocess.run(["make", "-s", "--no-print-directory", "-C", str(ROOT), "print-TEST_STEPS"],
                         capture_output=True, text=True, timeout=120, check=True)
    steps = set(res.stdout.split())
    assert steps, "TEST_STEPS is empty"
    assert sorted(steps - help_targets()) == [], "a step of make test is missing from make help"
