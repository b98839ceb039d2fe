"""canfdi-replay --map FILE: another bus's frames and signals onto the supervisor's inputs.

A vehicle whose bus carries the same physical quantities in other frames
(another DBC) can be diagnosed when a map says where each input is. The
map file, one statement per line, '#' starts a comment:

    dbc = vehicle.dbc                       # the other bus's DBC, relative to this file
    # input      = Message.Signal  [scale S] [offset O] unit U [rate MS]
    DcmUa        = MotorFb.ArmVoltage             unit V
    DcmIa        = MotorFb.ArmCurrent  scale 0.001 unit A
    DcmOmega     = MotorFb.SpeedRpm    scale 0.10471976 unit rad/s
    DcmUsupply   = const 48                       unit V       # known, not on that bus

An input is a signal of DcmSensor, ThrSensor, SetpointDcm, SetpointThr
(the supervisor's inputs) or DcmActuator, ThrActuator (the commands the
ECU applied, which the models need) in dbc/canfdi.dbc, without the E2E
fields. Its value is S x (the signal decoded by the other DBC) + O, in the
unit U, which must be the input's unit in dbc/canfdi.dbc (the map author
states the conversion; nothing is converted silently). `const V` gives a
value the other bus does not carry (reported as assumed). Every data
signal of a frame that is mapped at all must be mapped or const. `rate`
(ms) is the period of the source message, by default its GenMsgCycleTime
in the other DBC.

How it is judged. A frame of the supervisor is made each time the message
of its first mapped signal (its trigger) arrives, from the latest value of
every mapped signal, once each has been received; it carries the trigger's
time stamp and channel. The other bus has no E2E protection: the frames
made here get a valid counter and CRC (every frame dbc/canfdi.dbc
protects, the setpoints too), so the counter, CRC and length checks
(U1A10/U1A11, U1A20/U1A21, U1A30/U1A31; for mapped setpoints that part of
U1A51, whose range check still applies) are not applied and say so;
timeouts are judged at the mapped rate (the same number of missed frames)
and ranges as always. Setpoints the map does not give leave the setpoint
checks (U1A50, U1A51) not judged: they are not in the recording. The models need a sample every 1 ms: a frame mapped
at another rate leaves its plant's models not judged, with the reason.
Frames of the other bus are decoded with cantools; those of the
supervisor are encoded with cantools from dbc/canfdi.dbc. A frame made
from a message goes into the core's pipe on that message's line of the
file (its number in BLF and MF4; tools/canfdi/replay_input.py), so the
lines the report names are the file's; a line of a candump log that is no
frame is reported with its number.
"""
from __future__ import annotations

import functools
import hashlib
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator, TextIO

import cantools
from cantools.database.can import Database

from .e2e import protect, protected_ids
from .replay_input import PlacedWriter, Problems, candump_line, numbered_messages
from .timeline import load_db

#: The supervisor's frames a map may fill, and which plant's models use them.
TARGET_FRAMES = ("DcmSensor", "ThrSensor", "SetpointDcm", "SetpointThr", "DcmActuator", "ThrActuator")
#: The frames made here that carry E2E protection (the DBC's CanfdiE2E).
E2E_FRAMES = tuple(sorted(n for n in protected_ids(load_db()).values() if n in TARGET_FRAMES))
PLANT_OF = {"DcmSensor": "dcm", "ThrSensor": "thr", "DcmActuator": "dcm", "ThrActuator": "thr"}
NOT_APPLIED = {
    "DcmSensor": {"U1A10": "counter", "U1A20": "CRC", "U1A30": "length"},
    "ThrSensor": {"U1A11": "counter", "U1A21": "CRC", "U1A31": "length"},
}
LINE = re.compile(r"^\s*(\w+)\s*=\s*(.*?)\s*$")


class MapError(ValueError):
    """A map file that cannot be used; str() names the file and line."""


@dataclass
class Mapping:
    target: str          # signal name in dbc/canfdi.dbc
    frame: str           # its message
    source_msg: str = ""  # message in the other DBC ('' for const)
    source_sig: str = ""
    scale: float = 1.0
    offset: float = 0.0
    const: float | None = None
    unit: str = ""
    rate_ms: float | None = None
    line: int = 0


@dataclass
class _FrameState:
    name: str
    mappings: list[Mapping] = field(default_factory=list)
    trigger: int = -1    # frame id in the other DBC
    rate_ms: float = 0.0
    values: dict[str, float] = field(default_factory=dict)
    counter: int = 0


@functools.lru_cache(maxsize=8)
def _load_dbc(path: Path, mtime_ns: int, size: int, inode: int) -> Any:
    """The other bus's DBC, parsed once while the file is unchanged (its time stamp, size and inode
    are part of the key). The databases are only read (decode, look-ups), never changed, so one
    parse can serve every map that names the file."""
    del mtime_ns, size, inode  # the cache key only
    return cantools.database.load_file(str(path))


class Mapper:
    """A loaded map: writes a log of the other bus as candump text of the supervisor's frames."""

    def __init__(self, path: Path, other: Database, other_path: Path, mappings: list[Mapping]) -> None:
        self.path = path
        self.other = other
        self.other_path = other_path
        self.mappings = mappings
        self.db = load_db()
        self.frames: dict[str, _FrameState] = {}
        for m in mappings:
            self.frames.setdefault(m.frame, _FrameState(m.frame)).mappings.append(m)
        self.by_source: dict[int, list[tuple[_FrameState, Mapping]]] = {}
        for fs in self.frames.values():
            for m in fs.mappings:
                if m.const is not None:
                    continue
                sid = self.other.get_message_by_name(m.source_msg).frame_id
                if fs.trigger < 0:
                    fs.trigger = sid
                    fs.rate_ms = float(m.rate_ms or 0.0)
                self.by_source.setdefault(sid, []).append((fs, m))

    # ------------------------------------------------------------ loading
    @classmethod
    def load(cls, path: Path) -> "Mapper":
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as e:
            raise MapError(f"{path}: cannot read the map: {e}") from e
        ours = load_db()
        dbc_path: Path | None = None
        mappings: list[Mapping] = []
        seen: dict[str, int] = {}
        for no, raw in enumerate(text.splitlines(), 1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            m = LINE.match(line)
            if not m:
                raise MapError(f"{path}:{no}: expected 'NAME = ...', got {raw.strip()!r}")
            key, rest = m.group(1), m.group(2)
            if key == "dbc":
                try:
                    dbc_path = (path.parent / rest).resolve()
                except (OSError, ValueError) as e:  # a NUL byte, a loop of links
                    raise MapError(f"{path}:{no}: bad DBC path {rest!r}: {e}") from e
                continue
            if key in seen:
                raise MapError(f"{path}:{no}: {key} is mapped twice (first on line {seen[key]})")
            seen[key] = no
            mappings.append(cls._parse_mapping(path, no, key, rest, ours))
        if dbc_path is None:
            raise MapError(f"{path}: no 'dbc = FILE' line: the other bus's database is needed")
        try:
            st = dbc_path.stat()
            other = _load_dbc(dbc_path, st.st_mtime_ns, st.st_size, st.st_ino)
        except Exception as e:  # noqa: BLE001 — any DBC error becomes a message with the file
            raise MapError(f"{path}: cannot load the other DBC {dbc_path}: {e}") from e
        if not isinstance(other, Database):
            raise MapError(f"{path}: {dbc_path} is not a CAN database")
        if not mappings:
            raise MapError(f"{path}: no input is mapped")
        for mp in mappings:
            if mp.const is not None:
                continue
            try:
                msg = other.get_message_by_name(mp.source_msg)
            except KeyError:
                raise MapError(f"{path}:{mp.line}: no message {mp.source_msg!r} in {dbc_path.name}") from None
            if mp.source_sig not in [s.name for s in msg.signals]:
                raise MapError(f"{path}:{mp.line}: message {mp.source_msg} of {dbc_path.name} has no signal "
                               f"{mp.source_sig!r}")
            if mp.rate_ms is None:
                if msg.cycle_time is None:
                    raise MapError(f"{path}:{mp.line}: {mp.source_msg} has no cycle time in {dbc_path.name}: "
                                   f"give 'rate MS'")
                mp.rate_ms = float(msg.cycle_time)
        by_frame: dict[str, list[Mapping]] = {}
        for mp in mappings:
            by_frame.setdefault(mp.frame, []).append(mp)
        for frame, mps in by_frame.items():
            want = [s.name for s in ours.get_message_by_name(frame).signals if not re.search(r"(Crc|Counter)$", s.name)]
            missing = [w for w in want if w not in {x.target for x in mps}]
            if missing:
                raise MapError(f"{path}: {frame} is mapped but not {', '.join(missing)}: map "
                               f"{'them' if len(missing) > 1 else 'it'} too, or give 'const VALUE' if the "
                               f"vehicle's value is known")
            if all(x.const is not None for x in mps):
                raise MapError(f"{path}: every signal of {frame} is const: nothing of it is on the bus")
        return cls(path, other, dbc_path, mappings)

    @staticmethod
    def _parse_mapping(path: Path, no: int, key: str, rest: str, ours: Database) -> Mapping:
        frame = None
        unit = ""
        for msg in ours.messages:
            if msg.name in TARGET_FRAMES:
                for s in msg.signals:
                    if s.name == key and not re.search(r"(Crc|Counter)$", s.name):
                        frame, unit = msg.name, s.unit or ""
        if frame is None:
            raise MapError(f"{path}:{no}: {key!r} is not an input of the supervisor (a signal of "
                           f"{', '.join(TARGET_FRAMES)} in dbc/canfdi.dbc, without Crc/Counter)")
        tok = rest.split()
        if not tok:
            raise MapError(f"{path}:{no}: nothing after '='")
        mp = Mapping(target=key, frame=frame, line=no)
        i = 1
        if tok[0] == "const":
            if len(tok) < 2:
                raise MapError(f"{path}:{no}: 'const' needs a value")
            mp.const = _num(path, no, "const", tok[1])
            i = 2
        elif "." in tok[0]:
            mp.source_msg, mp.source_sig = tok[0].split(".", 1)
        else:
            raise MapError(f"{path}:{no}: expected 'Message.Signal' or 'const VALUE', got {tok[0]!r}")
        while i < len(tok):
            word = tok[i]
            if i + 1 >= len(tok):
                raise MapError(f"{path}:{no}: {word!r} needs a value")
            val = tok[i + 1]
            if word == "scale":
                mp.scale = _num(path, no, word, val)
            elif word == "offset":
                mp.offset = _num(path, no, word, val)
            elif word == "unit":
                mp.unit = val
            elif word == "rate":
                mp.rate_ms = _num(path, no, word, val)
                if not 0.1 <= mp.rate_ms <= 60000:
                    raise MapError(f"{path}:{no}: rate must be 0.1..60000 ms")
            else:
                raise MapError(f"{path}:{no}: unknown word {word!r} (scale, offset, unit, rate)")
            i += 2
        if mp.unit != unit:
            raise MapError(f"{path}:{no}: {key} is in {unit or 'no unit'!r} in dbc/canfdi.dbc; the map says "
                           f"{mp.unit or 'nothing'!r} (state 'unit {unit}' with the scale and offset that give it)")
        return mp

    # ------------------------------------------------------------ judgement
    def info(self) -> dict[str, Any]:
        na: dict[str, str] = {}
        for frame in self.frames:
            for code, what in NOT_APPLIED.get(frame, {}).items():
                na[code] = f"{frame}: no {what} on the mapped bus (its frames are made here, no E2E protection)"
        return {
            "path": str(self.path), "sha256": hashlib.sha256(self.path.read_bytes()).hexdigest(),
            "dbc": str(self.other_path), "dbc_sha256": hashlib.sha256(self.other_path.read_bytes()).hexdigest(),
            "inputs": {m.target: (f"const {m.const:g} {m.unit} (assumed by the map)" if m.const is not None else
                                  f"{m.source_msg}.{m.source_sig} x {m.scale:g} + {m.offset:g} {m.unit}, "
                                  f"every {m.rate_ms:g} ms") for m in self.mappings},
            "codes_not_applied": na,
            "models_not_judged": {p: why for p, why in self._models_not_judged().items()},
        }

    def _models_not_judged(self) -> dict[str, str]:
        out: dict[str, str] = {}
        for fs in self.frames.values():
            plant = PLANT_OF.get(fs.name)
            if plant and fs.rate_ms and abs(fs.rate_ms - 1.0) > 1e-9:
                out[plant] = (f"{fs.name} is mapped at {fs.rate_ms:g} ms; the models need a sample every 1 ms")
        return out

    def core_args(self) -> list[str]:
        args: list[str] = []
        for fs in self.frames.values():
            if fs.name in ("DcmSensor", "ThrSensor", "SetpointDcm", "SetpointThr") and fs.rate_ms:
                args += ["--rx-rate", f"{fs.name}={max(1, math.ceil(fs.rate_ms))}"]
        mnj = self._models_not_judged()
        if mnj:
            args += ["--no-models", ",".join(sorted(mnj)), "--no-models-why", "; ".join(mnj[k] for k in sorted(mnj))]
        return args

    def min_gap_ms(self) -> int:
        """No frame for three periods of the slowest mapped message is the shortest gap."""
        rates = [fs.rate_ms for fs in self.frames.values() if fs.rate_ms]
        return math.ceil(3 * max(rates)) if rates else 0

    # ------------------------------------------------------------ conversion
    def write(self, path: Path, fmt: str, out: TextIO, problems: Problems) -> int:
        """The log of the other bus as candump text of the supervisor's frames."""
        import can  # noqa: PLC0415 — only a map needs Message objects here
        n = 0
        undecodable = 0
        w = PlacedWriter(out)
        src = _candump_numbered(path, problems) if fmt == "candump" else numbered_messages(path, fmt, problems)
        for pos, msg in src:
            if msg.is_error_frame or msg.is_remote_frame:
                continue
            pairs = self.by_source.get(msg.arbitration_id)
            if not pairs:
                continue
            try:
                dec = self.other.decode_message(msg.arbitration_id, bytes(msg.data), decode_choices=False)
            except Exception as e:  # noqa: BLE001 — a frame the other DBC cannot decode is counted
                undecodable += 1
                if undecodable <= 20:
                    problems.add(path, -1, f"frame 0x{msg.arbitration_id:X} at {msg.timestamp:.6f} s does not "
                                 f"decode with {self.other_path.name}: {e}")
                continue
            for fs, mp in pairs:
                v = dec.get(mp.source_sig)
                if isinstance(v, (int, float)):
                    fs.values[mp.target] = mp.scale * float(v) + mp.offset
            for fs in {id(f): f for f, _ in pairs}.values():
                if fs.trigger != msg.arbitration_id:
                    continue
                frame = self._make(fs)
                if frame is None:
                    continue
                line = candump_line(can.Message(timestamp=msg.timestamp, arbitration_id=frame[0],
                                                is_extended_id=False, data=frame[1], channel=msg.channel))
                if line is not None:
                    w.write(pos, line)
                    n += 1
        return n

    def _make(self, fs: _FrameState) -> tuple[int, bytes] | None:
        msg = self.db.get_message_by_name(fs.name)
        raw: dict[str, int] = {}
        for s in msg.signals:
            if re.search(r"(Crc|Counter)$", s.name):
                raw[s.name] = 0
                continue
            mp = next(m for m in fs.mappings if m.target == s.name)
            v = mp.const if mp.const is not None else fs.values.get(s.name)
            if v is None:
                return None  # not every signal received yet
            r = round((v - s.offset) / s.scale)
            lo = -(1 << (s.length - 1)) if s.is_signed else 0
            hi = (1 << (s.length - 1)) - 1 if s.is_signed else (1 << s.length) - 1
            raw[s.name] = min(max(r, lo), hi)  # beyond the DBC's range it stays implausible
        data = bytearray(msg.encode(raw, scaling=False, strict=False))
        if fs.name in E2E_FRAMES:
            protect(msg.frame_id, data, fs.counter)
            fs.counter = (fs.counter + 1) & 0x0F
        return msg.frame_id, bytes(data)


def _candump_numbered(path: Path, problems: Problems) -> Iterator[tuple[int, Any]]:
    """The frames of a candump log (also .gz) with their line numbers; a bad line is reported with
    its number and skipped."""
    import gzip  # noqa: PLC0415

    from .logio import parse_candump_line  # noqa: PLC0415
    opener: Any = gzip.open if path.suffix.lower() == ".gz" else open
    n = 0
    try:
        with opener(path, "rt", encoding="ascii", errors="replace") as f:
            for n, line in enumerate(f, 1):
                if line.startswith("#"):
                    continue
                try:
                    msg = parse_candump_line(line)
                except (ValueError, OverflowError) as e:
                    problems.add(path, n, f"not a candump frame ({e}); skipped", line)
                    continue
                if msg is not None:
                    yield n, msg
    except (OSError, EOFError) as e:
        problems.add(path, n + 1, f"read error, the rest of the file is lost: {e}")


def _num(path: Path, no: int, word: str, val: str) -> float:
    try:
        x = float(val)
    except ValueError:
        raise MapError(f"{path}:{no}: {word} {val!r} is not a number") from None
    if not math.isfinite(x):
        raise MapError(f"{path}:{no}: {word} {val!r} is not finite")
    return x

