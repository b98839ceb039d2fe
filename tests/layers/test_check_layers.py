"""tools/check_layers.py on small synthetic firmware trees (and the real one).

Each test writes a tree and its layers.txt into a temporary folder and runs
the checker as `make layer-check` does, as a program: its exit status and
its lines are the contract.
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CHECKER = ROOT / "tools" / "check_layers.py"

LAYERS = """\
# a small table: rank 0 .. 4
.
core
comm/gen          # generated, its own folder
comm detect       # same rank
app
"""

CLEAN = {
    "config.h": "#define CFG 1\n",
    "core/fixp.h": '#include "config.h"\n#include <stdint.h>\n',
    "core/fixp.c": '#include "core/fixp.h"\n#include "fixp.h"\n',
    "comm/gen/msg.h": '#include "core/fixp.h"\n',
    "comm/gen/msg.c": '#include "msg.h"\n',
    "comm/rx.h": '#include "comm/gen/msg.h"\n#include "core/fixp.h"\n',
    "comm/rx.c": '#include "comm/rx.h"\n#include "../core/fixp.h"\n',
    "detect/limit.h": '#include "core/fixp.h"\n',
    # an unlisted X/gen belongs to X
    "detect/gen/tab.h": '#include "detect/limit.h"\n',
    "detect/limit.c": '#include "detect/limit.h"\n#include "detect/gen/tab.h"\n',
    "app/app.c": ('#include "comm/rx.h"\n#include "detect/limit.h"\n'
                  '#include CFG_HEADER\n#  include "config.h"\n'),
}


def make_tree(tmp: Path, files: dict[str, str], layers: str = LAYERS) -> Path:
    root = tmp / "firmware"
    for rel, text in files.items():
        p = root / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
    (root / "layers.txt").write_text(layers)
    return root


def run(root: Path, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(CHECKER), "--root", str(root)],
                          cwd=cwd, capture_output=True, text=True, timeout=60)


def violations(res: subprocess.CompletedProcess[str]) -> list[str]:
    return [ln for ln in res.stdout.splitlines() if not ln.startswith("check_layers:")]


def test_clean_tree_passes(tmp_path: Path) -> None:
    root = make_tree(tmp_path, CLEAN)
    res = run(root, tmp_path)
    assert res.returncode == 0, res.stdout + res.stderr
    # 11 files, 16 quoted includes (the computed one is not counted)
    assert res.stdout.strip() == ("check_layers: 11 files, 16 includes checked against "
                                  "6 folders on 5 ranks: no violation")


def test_upward_include_fails(tmp_path: Path) -> None:
    files = dict(CLEAN)
    files["core/fixp.h"] = '#include "config.h"\n\n#include "comm/rx.h"\n'
    res = run(make_tree(tmp_path, files), tmp_path)
    assert res.returncode == 1, res.stdout + res.stderr
    assert violations(res) == [
        'firmware/core/fixp.h:3: #include "comm/rx.h": core (rank 1) -> comm (rank 3): '
        'a layer may include only its own folder and lower ranks']


def test_upward_include_by_relative_path_fails(tmp_path: Path) -> None:
    files = dict(CLEAN)
    files["comm/gen/msg.c"] = '#include "msg.h"\n#include "../rx.h"\n'
    res = run(make_tree(tmp_path, files), tmp_path)
    assert res.returncode == 1
    assert violations(res) == [
        'firmware/comm/gen/msg.c:2: #include "../rx.h": comm/gen (rank 2) -> comm (rank 3): '
        'a layer may include only its own folder and lower ranks']


def test_same_rank_include_fails(tmp_path: Path) -> None:
    files = dict(CLEAN)
    files["detect/limit.c"] = '#include "detect/limit.h"\n#include "comm/rx.h"\n'
    res = run(make_tree(tmp_path, files), tmp_path)
    assert res.returncode == 1
    assert violations(res) == [
        'firmware/detect/limit.c:2: #include "comm/rx.h": detect (rank 3) -> comm (rank 3): '
        'folders on the same rank may not include each other']


def test_unknown_folder_fails(tmp_path: Path) -> None:
    files = dict(CLEAN)
    files["newmod/thing.c"] = '#include "core/fixp.h"\n'
    files["app/app.c"] = CLEAN["app/app.c"] + '#include "newmod/thing.h"\n'
    files["newmod/thing.h"] = "\n"
    res = run(make_tree(tmp_path, files), tmp_path)
    assert res.returncode == 1
    lines = violations(res)
    assert ('firmware/app/app.c:5: #include "newmod/thing.h": app (rank 4) -> folder newmod, '
            'which is not in firmware/layers.txt: add it to a rank') in lines
    # the folder is named once, not once per file
    assert [ln for ln in lines if ln.startswith("firmware/newmod/")] == [
        "firmware/newmod/thing.c: folder newmod is not in firmware/layers.txt: "
        "add it to a rank (every firmware folder has one)"]
    assert len(lines) == 2


def test_unlisted_subfolder_other_than_gen_is_unknown(tmp_path: Path) -> None:
    files = dict(CLEAN)
    files["core/extra/sat.h"] = '#include "core/fixp.h"\n'
    res = run(make_tree(tmp_path, files), tmp_path)
    assert res.returncode == 1
    assert violations(res) == [
        "firmware/core/extra/sat.h: folder core/extra is not in firmware/layers.txt: "
        "add it to a rank (every firmware folder has one)"]


def test_include_outside_the_firmware_fails(tmp_path: Path) -> None:
    files = dict(CLEAN)
    files["core/fixp.c"] = '#include "core/fixp.h"\n#include "../../host_sim/plant.h"\n'
    (tmp_path / "host_sim").mkdir()
    (tmp_path / "host_sim" / "plant.h").write_text("\n")
    res = run(make_tree(tmp_path, files), tmp_path)
    assert res.returncode == 1
    assert violations(res) == [
        'firmware/core/fixp.c:2: #include "../../host_sim/plant.h": names no file under '
        'firmware/: the layer of a header outside the firmware cannot be checked']


def test_bad_layers_file_is_an_error(tmp_path: Path) -> None:
    root = make_tree(tmp_path, CLEAN, LAYERS + "core\nmissing\n")
    res = run(root, tmp_path)
    assert res.returncode == 2
    assert "core is already on rank 1" in res.stderr
    assert "missing: no such folder" in res.stderr


def test_the_repository_passes() -> None:
    res = subprocess.run([sys.executable, str(CHECKER)], cwd=ROOT,
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stdout + res.stderr
    assert res.stdout.startswith("check_layers: ")
    assert "no violation" in res.stdout
