#!/usr/bin/env python3
"""check_layers.py — the include layers of firmware/ (firmware/layers.txt).

    tools/check_layers.py [--root DIR] [--layers FILE]

Reads every `#include "..."` in DIR/**/*.c and *.h (default: the
repository's firmware/), resolves the file it names the way the compiler
does for a quoted include (the including file's folder first, then DIR,
which every build passes as -I), and checks the folder of that file against
the ranks of the layers file (default DIR/layers.txt):

  - a file may include its own folder and any folder of a lower rank;
  - folders on the same rank may not include each other;
  - a folder that the table does not name (a listed X/gen aside, whose
    unlisted X/gen belongs to X) is an error, for a source file in it and
    for an include that names it, so the table stays complete;
  - an include that leaves DIR or names no file under DIR is an error: its
    layer cannot be known.

System headers (<...>) and computed includes (#include MACRO) are not
checked. Prints one line per violation (file:line, the include, both
folders with their ranks, the rule) and exits 1; otherwise prints a
one-line summary and exits 0. Exit 2: the layers file itself is wrong.
Python 3 standard library only.
"""
from __future__ import annotations

import argparse
import posixpath
import re
import sys
from dataclasses import dataclass
from pathlib import Path

INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')
SOURCE_SUFFIXES = (".c", ".h")


class LayersFileError(Exception):
    """The layers file cannot be used (syntax, duplicates, missing folders)."""


@dataclass(frozen=True)
class Layers:
    """Folder (relative to the firmware root, "." for the root) -> rank."""

    rank: dict[str, int]
    path: str

    def layer_of(self, folder: str) -> str | None:
        """The table's entry a folder belongs to, or None if it has none.

        A listed folder is its own entry; an unlisted X/gen belongs to X.
        """
        if folder in self.rank:
            return folder
        parent, name = posixpath.split(folder)
        if name == "gen" and parent:
            return self.layer_of(parent)
        return None


def shown_path(p: Path) -> str:
    """p relative to the working directory where it lies below it."""
    try:
        return p.resolve().relative_to(Path.cwd().resolve()).as_posix()
    except ValueError:
        return str(p)


def read_layers(path: Path, root: Path, shown: str) -> Layers:
    rank: dict[str, int] = {}
    problems: list[str] = []
    n = 0
    for lineno, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        for w in words:
            folder = posixpath.normpath(w.strip("/")) if w != "." else "."
            if folder.startswith("..") or posixpath.isabs(w):
                problems.append(f"{shown}:{lineno}: {w}: not a folder inside {root}")
            elif folder in rank:
                problems.append(f"{shown}:{lineno}: {folder} is already on rank {rank[folder]}")
            elif not (root / folder).is_dir():
                problems.append(f"{shown}:{lineno}: {folder}: no such folder {root / folder}")
            else:
                rank[folder] = n
        n += 1
    if not rank and not problems:
        problems.append(f"{shown}: names no folder")
    if problems:
        raise LayersFileError("\n".join(problems))
    return Layers(rank, shown)


def folder_of(rel_file: str) -> str:
    d = posixpath.dirname(rel_file)
    return d if d else "."


def resolve(root: Path, rel_from: str, name: str) -> str | None:
    """The file a quoted include names, relative to root, or None.

    Searched like the compiler: the including file's folder, then root
    (-I firmware). A path that leaves root resolves to None.
    """
    for base in (folder_of(rel_from), "."):
        cand = posixpath.normpath(posixpath.join(base, name))
        if cand == ".." or cand.startswith("../") or posixpath.isabs(cand):
            continue
        if (root / cand).is_file():
            return cand
    return None


def describe(layers: Layers, entry: str) -> str:
    return f"{entry} (rank {layers.rank[entry]})"


def check(root: Path, layers: Layers, display: str) -> tuple[list[str], int, int]:
    """Returns (violations, files, includes checked)."""
    violations: list[str] = []
    files = sorted(p for p in root.rglob("*") if p.is_file() and p.suffix in SOURCE_SUFFIXES)
    n_includes = 0
    unknown_reported: set[str] = set()
    for path in files:
        rel = path.relative_to(root).as_posix()
        shown = f"{display}/{rel}"
        src_folder = folder_of(rel)
        src = layers.layer_of(src_folder)
        if src is None:
            if src_folder not in unknown_reported:
                unknown_reported.add(src_folder)
                violations.append(
                    f"{shown}: folder {src_folder} is not in {layers.path}: "
                    f"add it to a rank (every firmware folder has one)")
            continue
        text = path.read_text(encoding="utf-8", errors="replace")
        for lineno, line in enumerate(text.splitlines(), 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            n_includes += 1
            name = m.group(1)
            where = f'{shown}:{lineno}: #include "{name}"'
            target = resolve(root, rel, name)
            if target is None:
                violations.append(
                    f"{where}: names no file under {display}/: "
                    f"the layer of a header outside the firmware cannot be checked")
                continue
            dst_folder = folder_of(target)
            dst = layers.layer_of(dst_folder)
            if dst is None:
                violations.append(
                    f"{where}: {describe(layers, src)} -> folder {dst_folder}, "
                    f"which is not in {layers.path}: add it to a rank")
            elif dst == src or layers.rank[dst] < layers.rank[src]:
                continue
            elif layers.rank[dst] == layers.rank[src]:
                violations.append(
                    f"{where}: {describe(layers, src)} -> {describe(layers, dst)}: "
                    f"folders on the same rank may not include each other")
            else:
                violations.append(
                    f"{where}: {describe(layers, src)} -> {describe(layers, dst)}: "
                    f"a layer may include only its own folder and lower ranks")
    return violations, len(files), n_includes


def main(argv: list[str] | None = None) -> int:
    repo = Path(__file__).resolve().parent.parent
    ap = argparse.ArgumentParser(
        description="Check the #include layers of the firmware against its layers file.")
    ap.add_argument("--root", type=Path, default=repo / "firmware",
                    help="the firmware folder (default: %(default)s)")
    ap.add_argument("--layers", type=Path, default=None,
                    help="the layers file (default: ROOT/layers.txt)")
    args = ap.parse_args(argv)
    root: Path = args.root
    layers_path: Path = args.layers if args.layers is not None else root / "layers.txt"
    display = shown_path(root)
    if not root.is_dir():
        print(f"check_layers: {root}: no such folder", file=sys.stderr)
        return 2
    try:
        layers = read_layers(layers_path, root, shown_path(layers_path))
    except (OSError, LayersFileError) as e:
        print(f"check_layers: {e}", file=sys.stderr)
        return 2
    violations, n_files, n_includes = check(root, layers, display)
    for v in violations:
        print(v)
    n_ranks = max(layers.rank.values()) + 1
    if violations:
        print(f"check_layers: {len(violations)} violation(s) in {n_files} files "
              f"({n_includes} includes; rules: {layers.path})")
        return 1
    print(f"check_layers: {n_files} files, {n_includes} includes checked against "
          f"{len(layers.rank)} folders on {n_ranks} ranks: no violation")
    return 0


if __name__ == "__main__":
    sys.exit(main())
