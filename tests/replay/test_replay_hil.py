"""canfdi-replay on lockstep HIL recordings (canfdi-scenario on vcan0 in the
sandbox, made by `make replay-test`: tests/replay/record_hil.sh): stepped on
the SimStep frames as canfdi-ecu --lockstep steps, the replay from power-up
is the recorded ECU frame for frame; a cut of the recording mid-run finds
the codes the recorded ECU had failing once they are judged: the frame and
range checks from the cut, the models after the settling time."""
from __future__ import annotations

from pathlib import Path

import pytest

from conftest import (HIL_OUT, HIL_SCENARIOS, NO_SETTLING, ROOT, recorded_active_after, recorded_first_failed,
                      run_replay)


def _logs() -> list[Path]:
    logs = [HIL_OUT / f"{Path(s).stem}.log" for s in HIL_SCENARIOS]
    missing = [str(p) for p in logs if not p.exists()]
    assert not missing, f"HIL recordings missing (make replay-test records them in the vcan sandbox): {missing}"
    return logs


@pytest.mark.parametrize("scn", HIL_SCENARIOS)
def test_hil_recording_from_power_up(scn: str, tmp_path: Path) -> None:
    log = HIL_OUT / f"{Path(scn).stem}.log"
    assert log in _logs()
    rc, doc, out, err = run_replay([str(log)], tmp_path)
    assert doc is not None, err
    lg = doc["logs"][0]
    assert lg["clock"] == "simstep" and lg["start"] == "power-up"
    ecu = lg["recorded_ecu"]
    assert ecu["frames"] > 10000 and ecu["identical"] == ecu["frames"] and ecu["replay_only"] == 0
    want = recorded_first_failed(log)
    assert want, "the scenario's fault must show in the recording"
    got = {f["code"]: f["first_failed_s"] for f in doc["dtcs"]}
    assert got == pytest.approx(want)
    assert rc == 1


@pytest.mark.parametrize("scn", HIL_SCENARIOS)
def test_hil_recording_cut_mid_run(scn: str, tmp_path: Path) -> None:
    """The recording from SimStep(400) on (its wall-clock time stamp): a mid-drive start."""
    log = HIL_OUT / f"{Path(scn).stem}.log"
    lines = log.read_text().splitlines(keepends=True)
    k0 = next(i for i, line in enumerate(lines) if " 611#90010000" in line)  # SimStep index 400
    cut = tmp_path / "cut.log"
    cut.write_text("".join(lines[k0 + 1:]))
    rc, doc, out, err = run_replay([str(cut)], tmp_path)
    assert doc is not None, err
    lg = doc["logs"][0]
    assert lg["clock"] == "simstep" and lg["start"] == "mid-drive"
    settled = lg["settled_from_s"]
    assert settled == pytest.approx(0.401 + doc["settle_s"])
    from canfdi.replay_report import CODE_MONITORS

    def judged_from(code: str) -> float:
        return 0.401 if set(CODE_MONITORS[code]) <= NO_SETTLING else settled

    found = {f["code"]: f["first_failed_s"] for f in doc["dtcs"]}
    assert found and all(t >= judged_from(c) - 1e-9 for c, t in found.items()), found
    want = {c for c in recorded_first_failed(log) if recorded_active_after(log, judged_from(c), c)}
    assert set(found) == want
    assert (ROOT / scn).exists()
