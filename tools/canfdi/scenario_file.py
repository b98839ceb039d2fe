"""The parts of a scenario file (host_sim/SCENARIO.md) the Python tools need.

The C parser (``canfdi-sim --check -s FILE``) is the authority on the whole
format; this reader takes only ``duration``, ``seed``, ``fault``, ``expect``,
the ECU-side actions ``cycle``, ``clear`` and ``power_cycle`` and the tester's
``uds`` requests (which only the SIL rig performs: ``Scenario.sil_only``
names them) and ``profile`` (whose CSV file it reads and checks with
canfdi.profile_csv, the C reader's twin), checks what it takes with the same
file:line messages, and accepts every other known directive without looking
at it. ``check_with_c``
runs the C parser too when it has been built, so a file the HIL tools accept
is never one the simulator would refuse.

    scn = parse(Path("tests/sil/scenarios/tps1_open.scn"))
    scn.duration_us, scn.faults[0].name, scn.expects[0]   # 6000000, 'thr_tps1_open', Expect(...)
"""
from __future__ import annotations

import math
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

from . import REPO_ROOT
from .catalogue import MODES, dtc_by_code, fault_by_name
from .profile_csv import SUPPLIES, Profile, ProfileError
from .profile_csv import read as read_profile

MAX_DURATION_S = 100000.0
DIRECTIVES = ("duration", "seed", "noise", "init", "param", "speed", "angle", "load", "profile", "fault",
              "expect", "cycle", "clear", "power_cycle", "uds")
ACTIONS = ("cycle", "clear", "power_cycle")
# expect dtc_status bit names, bit 0 first (ISO 14229-1 DTC status byte)
STATUS_BITS = ("TF", "TFTOC", "PDTC", "CDTC", "TNCSLC", "TFSLC", "TNCTOC", "WIR")
# expect freeze signals (canfdi_dtc_ff_t; the SIL rig reads them from the ECU's memory)
FREEZE_SIGNALS = ("time", "dcm_speed", "dcm_ia", "dcm_ua", "thr_angle", "dcm_supply", "deg_dcm", "deg_thr")
MAX_ACTIONS = 64
MAX_UDS = 64
UDS_BYTES = 64
MAX_TOKENS = 100
SIM_BIN = REPO_ROOT / "build" / "bin" / "canfdi-sim"


class ScenarioError(ValueError):
    """'file:line: reason', as the C parser words it."""


def to_us(t_s: float) -> int:
    """Seconds -> whole µs, rounding half away from zero like C's llround."""
    return int(math.floor(abs(t_s) * 1e6 + 0.5)) * (1 if t_s >= 0 else -1)


@dataclass(frozen=True)
class FaultLine:
    line: int
    t_start_us: int
    name: str
    mode: str
    magnitude: float | None      # None = 'default'
    ramp_s: float = 0.0
    period_s: float = 0.0
    duty: float = 0.0


@dataclass(frozen=True)
class Expect:
    line: int
    t_s: float
    kind: str                    # dtc | no_dtc | degradation | dtc_status | occurrence | freeze
    arg1: str = ""               # code or subsystem
    arg2: str = ""               # pending|confirmed|'', the state, the bits as written, the signal
    mask: int = 0                # dtc_status: bits named
    value: int = 0               # dtc_status: their expected values
    lo: float = 0.0              # occurrence: n; freeze: min
    hi: float = 0.0              # occurrence: n; freeze: max

    @property
    def t_us(self) -> int:
        return to_us(self.t_s)


@dataclass(frozen=True)
class Action:
    """cycle / clear / power_cycle: an ECU-side action (SIL rig only)."""
    line: int
    t_us: int
    kind: str                    # cycle | clear | power_cycle
    code: str = ""               # clear: the trouble code, '' = all


@dataclass(frozen=True)
class UdsLine:
    """uds: a tester's request and the response it expects (SIL rig only)."""
    line: int
    t_us: int
    functional: bool
    request: bytes
    pattern: tuple[int | None, ...] = ()   # None = '..' (any byte)
    any_tail: bool = False                 # a final '*'
    none: bool = False                     # expect none
    judged: bool = False                   # an expect part was given

    def matches(self, resp: bytes) -> bool:
        if not self.judged:
            return True
        if self.none:
            return False
        n = len(self.pattern)
        if (len(resp) < n) if self.any_tail else (len(resp) != n):
            return False
        return all(p is None or p == b for p, b in zip(self.pattern, resp))


@dataclass
class Scenario:
    path: Path
    duration_s: float = 0.0
    seed: int = 1
    faults: list[FaultLine] = field(default_factory=list)
    expects: list[Expect] = field(default_factory=list)
    actions: list[Action] = field(default_factory=list)
    profile: Profile | None = None   # the `profile` file, read and checked
    profile_line: int = 0
    uds: list[UdsLine] = field(default_factory=list)

    @property
    def sil_only(self) -> list[str]:
        """'file:line: directive' of every line only the SIL rig can act on (none: HIL can run it)."""
        out = [f"{self.path}:{a.line}: {a.kind}" for a in self.actions]
        out += [f"{self.path}:{u.line}: uds" for u in self.uds]
        out += [f"{self.path}:{e.line}: expect freeze" for e in self.expects if e.kind == "freeze"]
        return sorted(out, key=lambda w: int(w.rsplit(":", 2)[1]))

    @property
    def duration_us(self) -> int:
        return to_us(self.duration_s)

    @property
    def steps(self) -> int:
        return round(self.duration_s * 1000.0)


def _num(where: str, tok: str, what: str, lo: float, hi: float) -> float:
    try:
        v = float(tok)
    except ValueError:
        raise ScenarioError(f"{where}: {what} '{tok}' is not a number") from None
    if not math.isfinite(v) or not lo <= v <= hi:
        raise ScenarioError(f"{where}: {what} {tok} out of range {lo:g}..{hi:g}")
    return v


def _fault(where: str, n: int, tok: list[str]) -> FaultLine:
    usage = ("fault <t_start> <name> abrupt <magnitude> | incipient <magnitude> <ramp_s> | "
             "intermittent <magnitude> <period_s> <duty>")
    if len(tok) < 5:
        raise ScenarioError(f"{where}: {usage}")
    t0 = _num(where, tok[1], "fault start time", 0.0, MAX_DURATION_S)
    f = fault_by_name().get(tok[2])
    if f is None:
        raise ScenarioError(f"{where}: unknown fault '{tok[2]}' (see dbc/faults.csv or canfdi-sim --list-faults)")
    mode = tok[3]
    if mode not in MODES:
        raise ScenarioError(f"{where}: unknown fault mode '{mode}' (abrupt, incipient, intermittent)")
    if mode not in f.modes:
        raise ScenarioError(f"{where}: fault {f.name} cannot be {mode} (allowed: {', '.join(f.modes)})")
    mag = None if tok[4] == "default" else _num(where, tok[4], "fault magnitude", -1e9, 1e9)
    want = {"abrupt": 5, "incipient": 6, "intermittent": 7}[mode]
    if len(tok) != want:
        raise ScenarioError(f"{where}: {usage}")
    ramp = _num(where, tok[5], "ramp_s", 1e-6, MAX_DURATION_S) if mode == "incipient" else 0.0
    period = _num(where, tok[5], "period_s", 2e-6, MAX_DURATION_S) if mode == "intermittent" else 0.0
    duty = 0.0
    if mode == "intermittent":
        duty = _num(where, tok[6], "duty", 0.0, 1.0)
        if duty <= 0.0:
            raise ScenarioError(f"{where}: duty '{tok[6]}' must be a number in (0, 1]")
    return FaultLine(n, to_us(t0), f.name, mode, mag, ramp, period, duty)


def parse_status_bits(where: str, text: str) -> tuple[int, int]:
    """'TF=1,PDTC=0,...' (any subset, each once) or '0xNN' (all eight) -> (mask, value)."""
    if text[:2] in ("0x", "0X"):
        h = text[2:]
        if not 1 <= len(h) <= 2 or any(c not in "0123456789abcdefABCDEF" for c in h):
            raise ScenarioError(f"{where}: status byte '{text}' must be 0x00..0xFF")
        return 0xFF, int(h, 16)
    mask = value = 0
    parts = text.split(",")
    for i, part in enumerate(parts):
        name, eq, v = part.partition("=")
        if not eq or name not in STATUS_BITS:
            raise ScenarioError(f"{where}: status bits '{text}': expected NAME=0|1[,NAME=0|1...] with NAME one of "
                                "TF, TFTOC, PDTC, CDTC, TNCSLC, TFSLC, TNCTOC, WIR (or a byte 0xNN)")
        if v not in ("0", "1") or (i == len(parts) - 2 and parts[-1] == ""):
            raise ScenarioError(f"{where}: status bits '{text}': {name} must be 0 or 1")
        b = STATUS_BITS.index(name)
        if mask & (1 << b):
            raise ScenarioError(f"{where}: status bits '{text}': {name} named twice")
        mask |= 1 << b
        value |= int(v) << b
    return mask, value


def bits_text(mask: int, v: int) -> str:
    """'TF=1,PDTC=0' for the bits in mask, values from v (bit order), as canfdi-sil prints."""
    return ",".join(f"{STATUS_BITS[b]}={(v >> b) & 1}" for b in range(8) if mask >> b & 1)


def _code(where: str, code: str) -> None:
    if code not in dtc_by_code():
        raise ScenarioError(f"{where}: unknown trouble code '{code}' (see dbc/dtcs.csv)")


def _expect(where: str, n: int, tok: list[str]) -> Expect:
    if not 3 <= len(tok) <= 7:
        raise ScenarioError(f"{where}: expect <t> dtc <code> [pending|confirmed] | expect <t> no_dtc"
                            " | expect <t> degradation <dcm|thr> <state> | expect <t> dtc_status <code> <bits>"
                            " | expect <t> occurrence <code> <n> | expect <t> freeze <code> <signal> <min> <max>")
    t = _num(where, tok[1], "expect time", 0.0, MAX_DURATION_S)
    kind = tok[2]
    extra: dict[str, float | int] = {}
    if kind == "dtc":
        if not 4 <= len(tok) <= 5:
            raise ScenarioError(f"{where}: expect <t> dtc <code> [pending|confirmed]")
        _code(where, tok[3])
        if len(tok) == 5 and tok[4] not in ("pending", "confirmed"):
            raise ScenarioError(f"{where}: dtc status '{tok[4]}' must be pending or confirmed")
    elif kind == "no_dtc":
        if len(tok) != 3:
            raise ScenarioError(f"{where}: expect <t> no_dtc")
    elif kind == "degradation":
        if len(tok) != 5:
            raise ScenarioError(f"{where}: expect <t> degradation <dcm|thr> <normal|degraded|fail_safe>")
        if tok[3] not in ("dcm", "thr"):
            raise ScenarioError(f"{where}: subsystem '{tok[3]}' must be dcm or thr")
        if tok[4] not in ("normal", "degraded", "fail_safe"):
            raise ScenarioError(f"{where}: degradation '{tok[4]}' must be normal, degraded or fail_safe")
    elif kind == "dtc_status":
        if len(tok) != 5:
            raise ScenarioError(f"{where}: expect <t> dtc_status <code> <NAME=0|1,...>")
        _code(where, tok[3])
        mask, value = parse_status_bits(where, tok[4])
        extra = {"mask": mask, "value": value}
    elif kind == "occurrence":
        if len(tok) != 5:
            raise ScenarioError(f"{where}: expect <t> occurrence <code> <n>")
        _code(where, tok[3])
        if not tok[4].isdigit() or int(tok[4]) > 255:
            raise ScenarioError(f"{where}: occurrence '{tok[4]}' must be an integer 0..255")
        extra = {"lo": float(int(tok[4])), "hi": float(int(tok[4]))}
    elif kind == "freeze":
        if len(tok) != 7:
            raise ScenarioError(f"{where}: expect <t> freeze <code> <signal> <min> <max>")
        _code(where, tok[3])
        if tok[4] not in FREEZE_SIGNALS:
            raise ScenarioError(f"{where}: unknown freeze-frame signal '{tok[4]}' ({', '.join(FREEZE_SIGNALS)})")
        lo = _num(where, tok[5], "freeze min", -1e9, 1e9)
        hi = _num(where, tok[6], "freeze max", -1e9, 1e9)
        if hi < lo:
            raise ScenarioError(f"{where}: freeze max ({hi:g}) below min ({lo:g})")
        extra = {"lo": lo, "hi": hi}
    else:
        raise ScenarioError(f"{where}: unknown expectation '{kind}' (dtc, no_dtc, degradation, dtc_status, "
                            "occurrence, freeze)")
    return Expect(n, t, kind, tok[3] if len(tok) > 3 else "", tok[4] if len(tok) > 4 else "", **extra)  # type: ignore[arg-type]


def _action(where: str, n: int, tok: list[str], prev: list[Action]) -> Action:
    kind = tok[0]
    if kind == "clear":
        if not 2 <= len(tok) <= 3:
            raise ScenarioError(f"{where}: clear <t> [<code>|all]")
    elif len(tok) != 2:
        raise ScenarioError(f"{where}: {kind} <t>")
    t = _num(where, tok[1], "action time", 0.0, MAX_DURATION_S)
    code = ""
    if len(tok) == 3 and tok[2] != "all":
        if tok[2] not in dtc_by_code():
            raise ScenarioError(f"{where}: unknown trouble code '{tok[2]}' (see dbc/dtcs.csv, or all)")
        code = tok[2]
    a = Action(n, to_us(t), kind, code)
    if prev and a.t_us < prev[-1].t_us:
        raise ScenarioError(f"{where}: {kind} at {t:g} s is before the previous cycle/clear/power_cycle line "
                            "(write them in time order)")
    if len(prev) >= MAX_ACTIONS:
        raise ScenarioError(f"{where}: too many cycle/clear/power_cycle lines (at most {MAX_ACTIONS})")
    return a


def _profile_path(scn_path: Path, tok: str) -> Path:
    """The C parser's join: the scenario's folder (as written) + a relative path."""
    text = str(scn_path)
    if tok.startswith("/") or "/" not in text:
        return Path(tok)
    return Path(text[:text.rindex("/") + 1] + tok)


def _hex_byte(tok: str) -> int | None:
    if len(tok) == 2 and all(c in "0123456789abcdefABCDEF" for c in tok):
        return int(tok, 16)
    return None


def _uds(where: str, n: int, tok: list[str], prev: list[UdsLine]) -> UdsLine:
    usage = "uds <t> <phys|func> <hex byte>... [expect <hex byte|..>... [*] | expect none]"
    if len(tok) < 4:
        raise ScenarioError(f"{where}: too few arguments: {usage}")
    if len(prev) >= MAX_UDS:
        raise ScenarioError(f"{where}: too many uds lines (at most {MAX_UDS})")
    t = _num(where, tok[1], "request time", 0.0, MAX_DURATION_S)
    if tok[2] not in ("phys", "func"):
        raise ScenarioError(f"{where}: addressing '{tok[2]}': phys (0x7E0) or func (0x7DF)")
    req: list[int] = []
    k = 3
    while k < len(tok) and tok[k] != "expect":
        if len(req) >= UDS_BYTES:
            raise ScenarioError(f"{where}: request longer than {UDS_BYTES} bytes")
        b = _hex_byte(tok[k])
        if b is None:
            raise ScenarioError(f"{where}: '{tok[k]}' is not a hex byte (two digits, e.g. 19 or 0A)")
        req.append(b)
        k += 1
    if not req:
        raise ScenarioError(f"{where}: uds: no request bytes")
    functional = tok[2] == "func"
    if functional and len(req) > 7:
        raise ScenarioError(f"{where}: a functional request is one single frame: at most 7 bytes")
    pattern: list[int | None] = []
    any_tail = none = judged = False
    if k < len(tok):
        judged = True
        rest = tok[k + 1:]
        if rest[:1] == ["none"]:
            if len(rest) != 1:
                raise ScenarioError(f"{where}: nothing may follow 'expect none'")
            none = True
        elif not rest:
            raise ScenarioError(f"{where}: expect what? hex bytes, '..' (any byte), a final '*' (any rest), or none")
        for i, p in enumerate(rest if not none else []):
            if p == "*" and i == len(rest) - 1:
                any_tail = True
            elif len(pattern) >= UDS_BYTES:
                raise ScenarioError(f"{where}: expected response longer than {UDS_BYTES} bytes")
            elif p == "..":
                pattern.append(None)
            elif _hex_byte(p) is not None:
                pattern.append(_hex_byte(p))
            else:
                raise ScenarioError(f"{where}: '{p}' is not a hex byte, '..' or a final '*'")
    u = UdsLine(n, to_us(t), functional, bytes(req), tuple(pattern), any_tail, none, judged)
    if prev and u.t_us < prev[-1].t_us:
        raise ScenarioError(f"{where}: uds at {t:g} s is before the previous uds line (write them in time order)")
    return u


def parse(path: Path) -> Scenario:
    """Read a scenario; ScenarioError 'file:line: reason' on the first problem."""
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as e:
        raise ScenarioError(f"{path}: cannot read: {e}") from None
    scn = Scenario(path)
    have_duration = False
    params: set[str] = set()
    for n, raw in enumerate(text.splitlines(), 1):
        where = f"{path}:{n}"
        tok = raw.split("#", 1)[0].split()
        if not tok:
            continue
        d = tok[0]
        if len(tok) > MAX_TOKENS:
            raise ScenarioError(f"{where}: too many tokens (at most {MAX_TOKENS})")
        if d not in DIRECTIVES:
            raise ScenarioError(f"{where}: unknown directive '{d}' ({', '.join(DIRECTIVES)})")
        if d == "duration":
            if have_duration:
                raise ScenarioError(f"{where}: duplicate duration")
            if len(tok) != 2:
                raise ScenarioError(f"{where}: duration <s>")
            scn.duration_s = _num(where, tok[1], "duration", 0.001, MAX_DURATION_S)
            have_duration = True
        elif d == "seed" and len(tok) == 2 and tok[1].isdigit():
            scn.seed = int(tok[1])
        elif d == "fault":
            scn.faults.append(_fault(where, n, tok))
        elif d == "expect":
            scn.expects.append(_expect(where, n, tok))
        elif d in ACTIONS:
            scn.actions.append(_action(where, n, tok, scn.actions))
        elif d == "param" and len(tok) == 3:
            params.add(tok[1])
        elif d == "profile":
            if len(tok) != 2:
                raise ScenarioError(f"{where}: too {'few' if len(tok) < 2 else 'many'} arguments to "
                                    "'profile <file.csv>' (usage: profile <file.csv>)")
            if scn.profile is not None:
                raise ScenarioError(f"{where}: duplicate profile (one file per scenario)")
            try:
                scn.profile = read_profile(_profile_path(path, tok[1]))
            except ProfileError as e:
                raise ScenarioError(f"{e} (profile of {where})") from None
            scn.profile_line = n
        elif d == "uds":
            scn.uds.append(_uds(where, n, tok, scn.uds))
    if not have_duration:
        raise ScenarioError(f"{path}: no duration (required)")
    for f in scn.faults:
        if f.t_start_us >= scn.duration_us:
            raise ScenarioError(f"{path}:{f.line}: fault starts at or after the end of the scenario")
    for a in scn.actions:
        if a.t_us >= scn.duration_us:
            raise ScenarioError(f"{path}:{a.line}: action at or after the end of the scenario "
                                f"(duration {scn.duration_s:g} s)")
    for u in scn.uds:
        if u.t_us >= scn.duration_us:
            raise ScenarioError(f"{path}:{u.line}: uds request at or after the end of the scenario "
                                f"(duration {scn.duration_s:g} s)")
    for e in scn.expects:
        if e.t_s > scn.duration_s:
            raise ScenarioError(f"{path}:{e.line}: expectation after the end of the scenario "
                                f"(duration {scn.duration_s:g} s)")
    if scn.profile is not None:
        where = f"{path}:{scn.profile_line}"
        p = scn.profile
        if p.t_last_us * 1e-6 < scn.duration_s:
            raise ScenarioError(f"{where}: profile {p.path} ends at {p.t_last_us * 1e-6:g} s, before the end of "
                                f"the scenario (duration {scn.duration_s:g} s)")
        for name in SUPPLIES:
            if name in p.columns and name in params:
                raise ScenarioError(f"{where}: profile {p.path} has a {name} column and the scenario sets param "
                                    f"{name}: give the supply once")
    return scn


def check_with_c(path: Path, sim: Path = SIM_BIN) -> str | None:
    """Run the C parser when built: its message if it refuses the file (exit 2), else None.

    Any other failure (not built, cannot run here — e.g. an ASan build inside
    User-Mode Linux) leaves the verdict to the Python reader: the sim itself
    will refuse a bad file again when it starts.
    """
    if not sim.is_file():
        return None
    try:
        r = subprocess.run([str(sim), "--check", "-s", str(path)], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return None
    if r.returncode != 2:
        return None
    msg = [ln for ln in r.stderr.splitlines() if ln.startswith("canfdi-sim:")]
    return msg[-1] if msg else f"canfdi-sim --check refused {path} (exit 2)"


def load(path: Path, sim: Path = SIM_BIN) -> Scenario:
    """parse() + the C parser's verdict; ScenarioError on either's refusal."""
    scn = parse(path)
    err = check_with_c(path, sim)
    if err is not None:
        raise ScenarioError(err.removeprefix("canfdi-sim: "))
    return scn
