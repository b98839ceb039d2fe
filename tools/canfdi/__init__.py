"""canfdi Python tools.

Modules:
  catalogue      the fault catalogue (dbc/faults.csv) and DTC table (dbc/dtcs.csv)
  e2e            CRC-8 SAE J1850 and rolling-counter protection of 1 ms frames
  plot           PNG of a canfdi-sil trace (CSV)
  logplot        PNG of a recorded bus log, from its frames alone
  busargs        -i/-c/-b bus options and defaults, as python-can's tools
  logio          tolerant reading of recorded logs (candump .log and can.LogReader)
  timeline       frames -> diagnostic events on simulated time
  scenario_file  duration/fault/expect lines of a scenario (host_sim/SCENARIO.md)
  profile_csv    profile files (`profile <file.csv>`): read and checked like the simulator
  profile_plot   PNG of a profile file
  expect         canfdi-sil's judgement of expect lines, on a timeline
  hil            ECU/sim processes and the bus recorder of a HIL run
  replay         canfdi-replay: the supervisor over recorded logs (C core tools/replay)
  replay_input   every python-can format as candump text, bad lines reported
  replay_report  the replay's events folded into findings, not judged, data quality, JSON
  replay_html    the self-contained HTML report
  replay_map     --map: another DBC's signals onto the supervisor's inputs
Console commands: canfdi-inject (inject), canfdi-watch (watch),
canfdi-scenario (scenario_run), canfdi-plot (logplot), canfdi-profile-plot
(profile_plot), canfdi-replay (replay).
"""
from pathlib import Path

__version__ = "0.1.0"

#: Repository root when running from a checkout (tools/canfdi/__init__.py -> ../..).
REPO_ROOT = Path(__file__).resolve().parent.parent.parent
#: The CAN database, single source of truth for every frame.
DBC_PATH = REPO_ROOT / "dbc" / "canfdi.dbc"
