#!/usr/bin/env python3
"""tests/pil/footprint.py — flash, RAM and worst-case stack of the application
image (`make footprint`, mk/pil.mk).

The image is the port's real loop (firmware/port/cortexm/canfdi_cortexm_main.c)
on the empty board (canfdi_board_none.c), linked like the firmware
(newlib-nano, no system calls, --gc-sections) with each board's linker
script. Per module: the bytes of .text/.rodata (flash), .data (flash and RAM)
and .bss (RAM) that the linker kept, from its map. Stack: the deepest call
chain from main in the call graph the compiler wrote (-fcallgraph-info=su:
one frame size per function, static or dynamic; ASM_FRAMES for the
functions in assembly), plus LIBGCC_FRAME bytes for
a libgcc helper at the end of a chain (their frames are not in the graph: the
integer helpers push at most a few registers). Fails (exit 1) when the graph
has recursion, a dynamic or unbounded frame, an indirect call whose targets
it cannot name (INDIRECT below), or when the worst case does not fit the stack the linker script reserves
(__stack_size__), and when static data plus that stack do not fit the RAM.

Usage: footprint.py --machine NAME --elf ELF --map MAP --ci-dir DIR --ld LD
                    [--json OUT] [--budget-flash N --budget-ram N]
"""
import argparse
import glob
import json
import os
import re
import sys

LIBGCC_FRAME = 32
# The firmware's functions written in assembly (naked: the compiler writes
# 0 bytes for their frames) and the bytes their own PUSH takes: the ARMv6-M
# products of firmware/core/canfdi_fixp.c. Elsewhere they are C, and the
# compiler's figure is used when larger.
ASM_FRAMES = {"canfdi_smull32_h16": 8, "canfdi_mul_s56_q31_rnd_h16": 16}


def parse_map(path):
    """{module: {"flash": n, "ram": n}} from the input-section lines of a GNU ld map."""
    mods = {}
    sec_re = re.compile(r"^ (\.(?:text|rodata|data|bss)[^\s]*)\s*$")
    line_re = re.compile(r"^ (\.(?:text|rodata|data|bss)[^\s]*)?\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S+)$")
    pending = None
    in_mem = False
    with open(path) as f:
        for line in f:
            if line.startswith("Linker script and memory map"):
                in_mem = True
                continue
            if not in_mem:
                continue
            line = line.rstrip("\n")
            m = sec_re.match(line)
            if m:
                pending = m.group(1)
                continue
            m = line_re.match(line)
            if m and (m.group(1) or pending):
                sec = m.group(1) or pending
                pending = None
                size = int(m.group(3), 16)
                addr = int(m.group(2), 16)
                obj = m.group(4)
                if size == 0 or addr == 0 and not sec.startswith(".text"):
                    continue
                mod = module_of(obj)
                d = mods.setdefault(mod, {"flash": 0, "ram": 0})
                if sec.startswith((".text", ".rodata")):
                    d["flash"] += size
                elif sec.startswith(".data"):
                    d["flash"] += size
                    d["ram"] += size
                else:
                    d["ram"] += size
            else:
                pending = None
    return mods


def module_of(obj):
    m = re.search(r"lib(gcc|c_nano|c|nosys)\.a\(", obj)
    if m:
        return "lib" + m.group(1)
    m = re.search(r"(firmware/.*|tests/.*)\.o$", obj)
    return m.group(1) if m else os.path.basename(obj)


def parse_ci(ci_dir):
    nodes = {}
    edges = {}
    node_re = re.compile(r'node: \{ title: "([^"]+)" label: "([^"]*)"')
    edge_re = re.compile(r'edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"')
    for path in glob.glob(os.path.join(ci_dir, "**", "*.ci"), recursive=True):
        with open(path) as f:
            for line in f:
                m = node_re.search(line)
                if m:
                    title, label = m.group(1), m.group(2)
                    st = re.search(r"\\n(\d+) bytes \(([^)]*)\)", label)
                    if st:
                        nodes[title] = (int(st.group(1)), st.group(2))
                    elif title not in nodes:
                        nodes[title] = None  # external or built-in: no frame here
                    continue
                m = edge_re.search(line)
                if m:
                    edges.setdefault(m.group(1), set()).add(m.group(2))
    return nodes, edges


# The firmware's indirect calls and where their possible targets are read
# from, so the worst case covers every one of them: caller -> (source file,
# regex whose group 1 is a target's name). An indirect call of any other
# function fails the report.
INDIRECT = {
    # the service table: the handler is the last field of each row
    "canfdi_uds_step": ("firmware/uds/canfdi_uds.c", r"\{CANFDI_UDS_SID_\w+,[^{}]*,\s*(svc_\w+)\}"),
    # the seed/key function: the default (a replaced key_fn is the
    # integrator's, and its frame is theirs to add)
    "canfdi_uds_sec_request": ("firmware/uds/canfdi_uds_sec.c", r"\b(canfdi_uds_sec_key_default)\b"),
}
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def resolve_indirect(nodes, edges):
    """Replace the INDIRECT callers' __indirect_call edges by edges to their
    targets (node titles are "name" or "file.c:name" for static functions)."""
    by_name = {}
    for title in nodes:
        by_name.setdefault(title.split(":")[-1], []).append(title)
    for caller, (src, pattern) in INDIRECT.items():
        for title in by_name.get(caller, []):
            if "__indirect_call" not in edges.get(title, ()):
                continue
            with open(os.path.join(ROOT, src)) as f:
                names = set(re.findall(pattern, f.read()))
            targets = [t for n in sorted(names) for t in by_name.get(n, [])]
            if targets:
                edges[title].discard("__indirect_call")
                edges[title].update(targets)


def worst_stack(nodes, edges, root):
    problems = []
    memo = {}

    def frame(n):
        info = nodes.get(n)
        if info is None:
            return LIBGCC_FRAME, "libgcc/newlib (allowance)"
        if info[1] != "static":
            problems.append("%s: %s frame" % (n, info[1]))
        return max(info[0], ASM_FRAMES.get(n.split(":")[-1], 0)), info[1]

    def visit(n, stack):
        if n in memo:
            return memo[n]
        if n in stack:
            problems.append("recursion through %s" % n)
            return 0, [n]
        if n == "__indirect_call":
            problems.append("indirect call of a function that INDIRECT does not resolve")
        own, _ = frame(n)
        best, path = 0, []
        for t in sorted(edges.get(n, ())):
            d, p = visit(t, stack | {n})
            if d > best:
                best, path = d, p
        memo[n] = (own + best, [n] + path)
        return memo[n]

    depth, path = visit(root, frozenset())
    return depth, path, problems


def stack_size_of(ld):
    with open(ld) as f:
        m = re.search(r"__stack_size__\s*:\s*(0x[0-9a-fA-F]+|\d+)", f.read())
    return int(m.group(1), 0) if m else None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--machine", required=True)
    ap.add_argument("--elf", required=True)
    ap.add_argument("--map", required=True)
    ap.add_argument("--ci-dir", required=True)
    ap.add_argument("--ld", required=True)
    ap.add_argument("--ram-size", type=int, required=True)
    ap.add_argument("--json")
    a = ap.parse_args()
    mods = parse_map(a.map)
    nodes, edges = parse_ci(a.ci_dir)
    resolve_indirect(nodes, edges)
    depth, path, problems = worst_stack(nodes, edges, "main")
    reserved = stack_size_of(a.ld)
    flash = sum(d["flash"] for d in mods.values())
    ram = sum(d["ram"] for d in mods.values())
    ok = True
    print("footprint %s (%s): flash %d B, static RAM %d B, worst-case stack %d B (reserved %s B), "
          "RAM with the worst-case stack %d B" % (a.machine, os.path.basename(a.elf), flash, ram, depth, reserved,
                                                  ram + depth))
    print("  %-44s %8s %8s" % ("module", "flash", "RAM"))
    for mod, d in sorted(mods.items(), key=lambda kv: -(kv[1]["flash"] + kv[1]["ram"])):
        print("  %-44s %8d %8d" % (mod, d["flash"], d["ram"]))
    print("  deepest chain: " + " > ".join(p.split(":")[-1] + "(%s)" % (nodes[p][0] if nodes.get(p) else "~%d" % LIBGCC_FRAME)
                                       for p in path))
    for p in problems:
        print("  FAIL: %s" % p)
        ok = False
    if reserved is not None and depth > reserved:
        print("  FAIL: the worst-case stack %d B exceeds the %d B the linker script reserves" % (depth, reserved))
        ok = False
    if reserved is not None and ram + reserved > a.ram_size:
        print("  FAIL: static RAM %d B + stack %d B exceed the RAM (%d B)" % (ram, reserved, a.ram_size))
        ok = False
    if a.json:
        doc = {}
        if os.path.exists(a.json):
            with open(a.json) as f:
                doc = json.load(f)
        doc[a.machine] = {"flash": flash, "ram_static": ram, "stack_worst": depth, "stack_reserved": reserved,
                          "ram_with_stack": ram + depth, "deepest_chain": path, "modules": mods,
                          "note": "application image: port loop + empty board, -Os, newlib-nano; stack from "
                                  "-fcallgraph-info=su, libgcc frames counted as %d B" % LIBGCC_FRAME}
        with open(a.json, "w") as f:
            json.dump(doc, f, indent=1)
            f.write("\n")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
