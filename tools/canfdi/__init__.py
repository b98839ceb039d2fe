"""canfdi Python tools.

Modules:
  catalogue  the fault catalogue (dbc/faults.csv) and DTC table (dbc/dtcs.csv)
  e2e        CRC-8 SAE J1850 and rolling-counter protection of 1 ms frames
"""
from pathlib import Path

__version__ = "0.1.0"

#: Repository root when running from a checkout (tools/canfdi/__init__.py -> ../..).
REPO_ROOT = Path(__file__).resolve().parent.parent.parent
#: The CAN database, single source of truth for every frame.
DBC_PATH = REPO_ROOT / "dbc" / "canfdi.dbc"
