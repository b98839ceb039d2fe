#!/usr/bin/env python3
"""tests/pil/sizes.py — the struct sizes the firmware's headers and docs state,
checked against the Cortex-M build (`make size-check`, mk/pil.mk).

A header's contract includes the memory its state takes ("Memory:
sizeof(canfdi_rls_t) = 352 bytes on a 32-bit target"); a firmware engineer
sizes RAM from those lines, so a struct that grows must not leave them
behind. Every statement `sizeof(canfdi_..._t) = N` (N a plain number, digits
grouped by spaces allowed; a formula such as `32 + 20 * ...` is not
checked) in firmware/**/*.h and docs/*.md is compared with sizeof on each
core given (arm-none-eabi-gcc, the firmware's flags): one C file
that defines `const unsigned canfdi_size_<type> = sizeof(<type>)` per type,
compiled to assembly, whose `.word` values are the sizes. Exit 1 with one
line per stale statement (file:line, stated, built), 2 on a setup error.

Usage: sizes.py --cc arm-none-eabi-gcc --cflags "..." --core cortex-m4 [--core cortex-m0] [--root DIR]
"""
import argparse
import glob
import os
import re
import shlex
import subprocess
import sys
import tempfile

STATED = re.compile(r"sizeof\((canfdi_\w+_t)\)`?\s*(?:is\s+)?=\s*([0-9][0-9 ]*[0-9]|[0-9])(?![0-9 ]*[+*/-])")


def statements(root):
    """[(path, line, type, stated size)] of every plain-number statement."""
    out = []
    files = sorted(glob.glob(os.path.join(root, "firmware", "**", "*.h"), recursive=True))
    files += sorted(glob.glob(os.path.join(root, "docs", "*.md")))
    for path in files:
        with open(path, encoding="utf-8") as f:
            text = f.read()
        for m in STATED.finditer(text):
            line = text.count("\n", 0, m.start()) + 1
            out.append((os.path.relpath(path, root), line, m.group(1), int(m.group(2).replace(" ", ""))))
    return out


def header_of(root, typ):
    """The firmware header that defines typ (`} typ;`), relative to firmware/."""
    pat = re.compile(r"^\}\s*" + re.escape(typ) + r"\s*;", re.M)
    for path in sorted(glob.glob(os.path.join(root, "firmware", "**", "*.h"), recursive=True)):
        with open(path, encoding="utf-8") as f:
            if pat.search(f.read()):
                return os.path.relpath(path, os.path.join(root, "firmware"))
    return None


def built_sizes(cc, cflags, core, root, types):
    """{type: sizeof} on core, from the assembly of a probe file."""
    heads = sorted({header_of(root, t) for t in types} - {None})
    missing = [t for t in types if header_of(root, t) is None]
    if missing:
        raise RuntimeError("no firmware header defines " + ", ".join(missing))
    src = "".join(f'#include "{h}"\n' for h in heads)
    src += "".join(f"const unsigned canfdi_size_{t} = sizeof({t});\n" for t in types)
    with tempfile.TemporaryDirectory() as tmp:
        c = os.path.join(tmp, "sizes.c")
        s = os.path.join(tmp, "sizes.s")
        with open(c, "w") as f:
            f.write(src)
        cmd = [cc, f"-mcpu={core}", "-mthumb", *shlex.split(cflags), "-S", "-o", s, c]
        r = subprocess.run(cmd, cwd=root, capture_output=True, text=True)
        if r.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)}:\n{r.stderr}")
        with open(s) as f:
            asm = f.read()
    sizes = {}
    for t in types:
        m = re.search(r"^canfdi_size_" + re.escape(t) + r":\s*\n\s*\.word\s+(\d+)", asm, re.M)
        if m is None:
            raise RuntimeError(f"no size of {t} in the probe's assembly")
        sizes[t] = int(m.group(1))
    return sizes


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cc", required=True)
    ap.add_argument("--cflags", default="")
    ap.add_argument("--core", action="append", required=True)
    ap.add_argument("--root", default=".")
    a = ap.parse_args()
    st = statements(a.root)
    if not st:
        print("size-check: no sizeof statement found", file=sys.stderr)
        return 2
    types = sorted({t for _, _, t, _ in st})
    stale = []
    try:
        for core in a.core:
            got = built_sizes(a.cc, a.cflags, core, a.root, types)
            for path, line, t, n in st:
                if got[t] != n:
                    stale.append(f"{path}:{line}: states sizeof({t}) = {n}, {core} build: {got[t]}")
    except RuntimeError as e:
        print(f"size-check: {e}", file=sys.stderr)
        return 2
    for s in stale:
        print("size-check: " + s)
    print(f"size-check: {'FAIL' if stale else 'pass'}: {len(st)} statements of {len(types)} types "
          f"against {', '.join(a.core)}" + (f", {len(stale)} stale" if stale else ""))
    return 1 if stale else 0


if __name__ == "__main__":
    sys.exit(main())
