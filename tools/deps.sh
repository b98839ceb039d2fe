#!/usr/bin/env bash
# Install what canfdi needs and nothing else; idempotent.
#   1. Debian packages (only those missing; apt-get runs only if one is).
#   2. A project-local Python venv (.venv) with the pinned requirements.txt,
#      reinstalled only when requirements.txt changes; the editable tools
#      package (console commands canfdi-*) reinstalled when requirements.txt
#      or tools/pyproject.toml changes.
# A second run on a ready machine does no network access and takes ~1 s.
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PACKAGES=(
  build-essential pkg-config check libeigen3-dev valgrind
  gcc-arm-none-eabi libnewlib-arm-none-eabi binutils-arm-none-eabi qemu-system-arm
  can-utils user-mode-linux kmod iproute2
  python3 python3-venv
)

missing=()
for p in "${APT_PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q '^install ok installed$'; then
    missing+=("$p")
  fi
done
if ((${#missing[@]})); then
  echo "deps: installing Debian packages: ${missing[*]}"
  SUDO=()
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null; then SUDO=(sudo); else
      echo "deps: error: need root (or sudo) to install: ${missing[*]}" >&2; exit 1
    fi
  fi
  export DEBIAN_FRONTEND=noninteractive
  "${SUDO[@]}" apt-get update -q </dev/null
  "${SUDO[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}" </dev/null
else
  echo "deps: Debian packages present (${#APT_PACKAGES[@]})"
fi

# Debian's interpreter, not a pyenv shim: the venv must start fast, also
# inside the User-Mode Linux sandbox.
PY=/usr/bin/python3
VENV=.venv
stamp="$VENV/.requirements.sha256"
want=$(sha256sum requirements.txt | cut -d' ' -f1)
if [ ! -x "$VENV/bin/python" ] || [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "deps: creating Python venv $VENV from requirements.txt"
  [ -x "$VENV/bin/python" ] || "$PY" -m venv "$VENV"
  "$VENV/bin/pip" install -q --disable-pip-version-check -r requirements.txt </dev/null
  echo "$want" > "$stamp"
else
  echo "deps: Python venv up to date ($VENV)"
fi

# The editable install writes the console scripts from tools/pyproject.toml:
# a new [project.scripts] entry needs a reinstall even though no code moved.
tools_stamp="$VENV/.tools.sha256"
if [ -f tools/pyproject.toml ]; then
  tools_want=$(cat requirements.txt tools/pyproject.toml | sha256sum | cut -d' ' -f1)
  if [ "$(cat "$tools_stamp" 2>/dev/null)" != "$tools_want" ]; then
    echo "deps: installing the canfdi tools package (editable, tools/pyproject.toml)"
    "$VENV/bin/pip" install -q --disable-pip-version-check --no-deps --no-build-isolation -e tools </dev/null
    echo "$tools_want" > "$tools_stamp"
  fi
fi
