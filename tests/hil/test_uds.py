"""The diagnostic server over the bus: a udsoncan client (standard_version
2020) over can-isotp on vcan0 against canfdi-ecu in lockstep with canfdi-sim,
as a workshop scan tool would use it; the ECU's 1 ms cadence while it
answers; SecurityAccess's lock-out across an ECU restart; canfdi-uds."""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import can
import pytest

from hilutil import CHANNEL, ECU, OUT, SIM

from canfdi import uds
from canfdi.hil import Proc, start_ecu, start_sim

SCN = Path(__file__).resolve().parent / "uds_bench.scn"
P0122 = 0x012200


def args(*extra: str) -> argparse.Namespace:
    return uds.build_parser().parse_args(["-i", "socketcan", "-c", CHANNEL, "--timeout", "5", *extra])


class Bench:
    """canfdi-ecu (lockstep, NVM, stats) + canfdi-sim on uds_bench.scn."""

    def __init__(self, nvm: Path, stats: Path) -> None:
        self.stats = stats
        self.ecu = start_ecu(ECU, CHANNEL, lockstep=True, nvm=nvm, extra=("--stats", str(stats)))
        self.step_bus = can.Bus(interface="socketcan", channel=CHANNEL,
                                can_filters=[{"can_id": 0x611, "can_mask": 0x7FF}])
        self.sim = start_sim(SIM, CHANNEL, SCN, lockstep=True)

    def wait_sim_s(self, t_s: float, timeout_s: float = 120.0) -> None:
        t_end = time.monotonic() + timeout_s
        while True:
            m = self.step_bus.recv(0.5)
            assert self.sim.poll() is None, f"canfdi-sim ended: {self.sim.tail()}"
            assert time.monotonic() < t_end, "the bench does not advance"
            if m is not None and int.from_bytes(bytes(m.data[:4]), "little") >= int(t_s * 1000):
                return

    def stop(self) -> dict:
        self.sim.kill()
        assert self.ecu.stop() == 0, self.ecu.tail()
        return json.loads(self.stats.read_text())

    def close(self) -> None:
        self.sim.kill()
        self.ecu.kill()
        self.step_bus.shutdown()


@pytest.fixture()
def bench_files() -> tuple[Path, Path]:
    nvm, stats = OUT / "uds.nvm", OUT / "uds-ecu.json"
    nvm.unlink(missing_ok=True)
    stats.unlink(missing_ok=True)
    return nvm, stats


def test_workshop_session_over_udsoncan(bench_files: tuple[Path, Path],
                                        capsys: pytest.CaptureFixture[str]) -> None:
    nvm, stats = bench_files
    b = Bench(nvm, stats)
    try:
        b.wait_sim_s(2.5)
        with uds.connect(args("dtc")) as t:
            c = t.c
            # the codes, their status, freeze frame and extended data
            r = uds.check(c.get_dtc_by_status_mask(0x08), "0x19 0x02")
            codes = {d.id: d.status.get_byte_as_int() for d in r.service_data.dtcs}
            assert P0122 in codes and codes[P0122] & 0x08, codes
            assert uds.check(c.get_number_of_dtc_by_status_mask(0x08), "0x19 0x01").service_data.dtc_count == len(codes)
            r = uds.check(c.get_dtc_snapshot_by_dtc_number(P0122, record_number=1), "0x19 0x04")
            snap = {s.did: s.data for s in r.service_data.dtcs[0].snapshots}
            assert list(snap) == [0xDF00, 0xD100, 0xD101, 0xD102, 0xD110, 0xD103, 0xD400, 0xD401]
            assert 1000 <= snap[0xDF00] <= 1100, snap          # the fault at 1 s
            assert 40.0 < snap[0xD103] < 56.0, snap             # the 48 V supply
            r = uds.check(c.get_dtc_extended_data_by_dtc_number(P0122, record_number=0xFF, data_size=1), "0x19 0x06")
            ext = {e.record_number: e.raw_data for e in r.service_data.dtcs[0].extended_data}
            assert ext == {1: b"\x01", 2: b"\x00"}, ext
            # live data, decoded with units
            r = uds.check(c.read_data_by_identifier([0xD103, 0xD110, 0xD400, 0xD500, 0xF195]), "0x22")
            v = r.service_data.values
            assert 40.0 < v[0xD103] < 56.0 and abs(v[0xD110] - 0.1745) < 0.07 and v[0xD500] > 2000, v
            assert v[0xF195].startswith("canfdi"), v
            # clear, then nothing confirmed
            uds.check(c.clear_dtc(0xFFFFFF), "0x14")
            r = uds.check(c.get_dtc_by_status_mask(0x08), "0x19 0x02")
            assert not r.service_data.dtcs, r.service_data.dtcs
        # an ECU reset: the throttle's degradation (latched for the power
        # cycle) is gone, so the plant is in the safe state for the tests
        assert uds.main(["-i", "socketcan", "-c", CHANNEL, "--timeout", "5", "reset"]) == 0
        b.wait_sim_s(6.0)
        with uds.connect(args("dtc")) as t:
            c = t.c
            # the actuator test and the spring check, unlocked
            t.unlock()
            uds.check(c.io_control(0xD115, control_param=3, values=[0.5236]), "0x2F")
            t.keep_alive(1.0)
            r = uds.check(c.read_data_by_identifier([0xD110]), "0x22")
            assert abs(r.service_data.values[0xD110] - 0.5236) < 0.07, r.service_data.values
            uds.check(c.io_control(0xD115, control_param=0), "0x2F return")
            t.keep_alive(1.0)
        # canfdi-uds, the command line, on the same bench
        assert uds.main(["-i", "socketcan", "-c", CHANNEL, "--timeout", "5", "live"]) == 0
        out = capsys.readouterr().out
        assert "dcm_supply" in out and " V" in out and "deg)" in out, out
        assert uds.main(["-i", "socketcan", "-c", CHANNEL, "--timeout", "5", "routine", "spring-check"]) == 0
        assert "spring check: passed" in capsys.readouterr().out
        b.wait_sim_s(12.0)
        st = b.stop()
    finally:
        b.close()
    # the loop kept its cadence: every SimStep stepped once, none missed
    assert st["deadline_misses"] == 0 and st["lockstep_gaps"] == 0 and st["stale_steps"] == 0, st
    assert st["ecu_resets"] == 1 and st["steps"] >= 11000, st


def test_security_lockout_survives_a_restart(bench_files: tuple[Path, Path]) -> None:
    nvm, stats = bench_files
    b = Bench(nvm, stats)
    try:
        b.wait_sim_s(0.5)
        with uds.connect(args("dtc")) as t:
            c = t.c
            uds.check(c.change_session(3), "0x10")
            got = []
            for _ in range(3):
                uds.check(c.request_seed(1), "requestSeed")
                got.append(c.send_key(2, b"\x00\x00\x00\x00").code)
            assert got == [0x35, 0x35, 0x36], got
            assert c.request_seed(1).code == 0x37
        b.stop()
    finally:
        b.close()
    b = Bench(nvm, stats)
    try:
        b.wait_sim_s(0.5)
        with uds.connect(args("dtc")) as t:
            t.c.change_session(3)
            assert t.c.request_seed(1).code == 0x37  # the delay runs again after power-up
            r = uds.check(t.c.read_data_by_identifier([0xD509]), "0x22")
            assert r.service_data.values[0xD509] == 3
        assert b.stop()["deadline_misses"] == 0
    finally:
        b.close()
