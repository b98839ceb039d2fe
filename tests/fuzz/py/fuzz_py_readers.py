#!/usr/bin/env python3
"""Atheris harness of the Python readers of outside files (tests/fuzz/README.md).

    .venv/bin/python tests/fuzz/py/fuzz_py_readers.py [libFuzzer options] [corpus dirs]

The first input byte picks the reader, the rest is the file's content:
  0  canfdi-replay --map (tools/canfdi/replay_map.py, Mapper.load), the
     file beside a copy of tests/replay/data/vehicle.dbc;
  1  the scenario parser of the Python tools (tools/canfdi/scenario_file.py);
  2  the log readers of canfdi-replay (tools/canfdi/replay_input.py,
     messages()) for .asc, .trc, .csv and .blf (second byte picks).
Invariants: the map loader raises only MapError, the scenario parser only
ScenarioError; the log readers raise nothing ("problems reported, never
raised"). Any other exception is a finding (atheris keeps the input).
"""
import os
import shutil
import sys
import tempfile
from pathlib import Path

import atheris

with atheris.instrument_imports():
    from canfdi import replay_input, replay_map, scenario_file

HERE = Path(__file__).resolve().parent
TMP = Path(tempfile.mkdtemp(prefix="canfdi-fuzz-py-"))
shutil.copy(HERE.parent.parent / "replay" / "data" / "vehicle.dbc", TMP / "vehicle.dbc")
LOG_SUFFIX = (".asc", ".trc", ".csv", ".blf")


def one(data: bytes) -> None:
    if not data:
        return
    which, body = data[0] % 3, data[1:]
    if which == 0:
        p = TMP / "in.map"
        p.write_bytes(body)
        try:
            replay_map.Mapper.load(p)
        except replay_map.MapError:
            pass
    elif which == 1:
        p = TMP / "in.scn"
        p.write_bytes(body)
        try:
            scenario_file.parse(p)
        except scenario_file.ScenarioError:
            pass
    else:
        suf = LOG_SUFFIX[body[0] % len(LOG_SUFFIX)] if body else ".asc"
        p = TMP / ("in" + suf)
        p.write_bytes(body[1:])
        problems = replay_input.Problems()
        for _ in replay_input.messages(p, replay_input.log_format(p), problems):
            pass


def main() -> None:
    atheris.Setup(sys.argv, one)
    try:
        atheris.Fuzz()
    finally:
        shutil.rmtree(TMP, ignore_errors=True)


if __name__ == "__main__":
    main()
