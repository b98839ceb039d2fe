"""Every frame is packed and unpacked by the codecs cantools generates from
dbc/canfdi.dbc, never by hand: a hand decoder does not follow a DBC change
(a signal moved or resized decodes wrongly, silently).

The product's C code (firmware/, host_sim/ and the replay core in
tools/replay/, generated files excluded) is
scanned for the shapes a hand codec takes: a frame byte shifted into a
wider integer (`data[1] << 8`), bytes OR-ed together from `data[...]`, or a
value shifted right into a frame byte (`data[2] = (uint8_t)(x >> 16)`).
Byte-wise loops that copy or compare payloads are not codecs and pass.
"""
from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCANNED = ("firmware", "host_sim", "tools/replay")

# data[<index>] shifted left, or OR-ed with another data[...] byte.
SHIFT_IN = re.compile(r"data\s*\[\s*\w+\s*\]\s*\)?\s*<<")
OR_BYTES = re.compile(r"data\s*\[\s*\d+\s*\][^;]*\|[^;|]*data\s*\[\s*\d+\s*\]")
# data[<index>] = ... >> ...
SHIFT_OUT = re.compile(r"data\s*\[\s*\d+\s*\]\s*=[^;]*>>")


def _sources() -> list[Path]:
    out = []
    for top in SCANNED:
        for p in sorted((ROOT / top).rglob("*.[ch]")):
            if "gen" in p.relative_to(ROOT).parts:
                continue
            out.append(p)
    return out


def hand_codec_lines(text: str) -> list[int]:
    # join continuation lines of one statement so a split expression is seen whole
    hits = []
    stmt = ""
    first = 0
    for no, line in enumerate(text.splitlines(), start=1):
        code = line.split("//")[0]
        if not stmt:
            first = no
        stmt += " " + code
        if ";" in code or "{" in code or "}" in code:
            if SHIFT_IN.search(stmt) or OR_BYTES.search(stmt) or SHIFT_OUT.search(stmt):
                hits.append(first)
            stmt = ""
    return hits


def test_patterns_catch_a_hand_decoder():
    decoder = ("const uint32_t k = (uint32_t)f->data[0] | ((uint32_t)f->data[1] << 8) |\n"
               "                   ((uint32_t)f->data[2] << 16);\n")
    encoder = "out->data[2] = (uint8_t)(v >> 16);\n"
    copy = "for (i = 0U; i < 8U; i++) { rf.data[i] = f->data[i]; }\n"
    assert hand_codec_lines(decoder) == [1]
    assert hand_codec_lines(encoder) == [1]
    assert hand_codec_lines(copy) == []


def test_no_hand_codec_in_product_code():
    found = []
    for p in _sources():
        for no in hand_codec_lines(p.read_text(encoding="utf-8", errors="replace")):
            found.append(f"{p.relative_to(ROOT)}:{no}")
    assert not found, ("hand-packed or hand-decoded frame bytes (use the generated codec "
                       "from dbc/canfdi.dbc): " + ", ".join(found))
