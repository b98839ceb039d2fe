#!/usr/bin/env bash
# Install what canfdi needs and nothing else; idempotent.
#   1. Debian packages (only those missing; apt-get runs only if one is;
#      clang with its libFuzzer/sanitizer runtimes, cppcheck and clang-tidy
#      for `make fuzz-test` and `make static-check`),
#      some of them for i386 (the 32-bit unit tests, `make unit-m32`): the
#      i386 architecture is added to dpkg once.
#   2. The i386 libcheck: Debian's `check` is not Multi-Arch, so check:i386
#      cannot be installed beside check:amd64; its .deb is downloaded
#      (apt-get download) and its static library unpacked into
#      .deps/check-i386/ (the headers are the same for both).
#   3. A project-local Python venv (.venv) with the pinned requirements.txt,
#      reinstalled only when requirements.txt changes; the editable tools
#      package (console commands canfdi-*) reinstalled when requirements.txt
#      or tools/pyproject.toml changes.
#   4. The source distributions of python-can and cantools at the pinned
#      versions (pip download into .deps/sdist/, once): tests/replay reads
#      their own test logs, files no one here wrote.
# A second run on a ready machine does no network access and takes ~1 s.
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PACKAGES=(
  build-essential pkg-config check libeigen3-dev valgrind
  gcc-multilib libsubunit-dev:i386
  gcc-arm-none-eabi libnewlib-arm-none-eabi binutils-arm-none-eabi qemu-system-arm
  can-utils user-mode-linux kmod iproute2
  python3 python3-venv
  zlib1g-dev chromium-headless-shell
  clang libclang-rt-14-dev cppcheck clang-tidy
)

# Extra package groups a make target asks for (`tools/deps.sh GROUP...`),
# not needed by `make test`: format (clang-format, `make format`).
for group in "$@"; do
  case "$group" in
    format) APT_PACKAGES+=(clang-format) ;;
    *) echo "deps: error: unknown package group: $group" >&2; exit 2 ;;
  esac
done

SUDO=()
need_root() { # what-for
  if [ "$(id -u)" -ne 0 ] && ((${#SUDO[@]} == 0)); then
    if command -v sudo >/dev/null; then SUDO=(sudo); else
      echo "deps: error: need root (or sudo) to $1" >&2; exit 1
    fi
  fi
}
export DEBIAN_FRONTEND=noninteractive
# A failing index (e.g. a mirror in the middle of a sync) does not stop the
# install: apt-get install says so if a package is really not to be had.
apt_update() {
  "${SUDO[@]}" apt-get update -q </dev/null || echo "deps: warning: apt-get update reported errors (above); going on"
}

updated=no
if ! dpkg --print-foreign-architectures | grep -qx i386; then
  need_root "add the i386 architecture to dpkg"
  echo "deps: adding the i386 architecture to dpkg (32-bit unit tests)"
  "${SUDO[@]}" dpkg --add-architecture i386
  apt_update
  updated=yes
fi

missing=()
for p in "${APT_PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q '^install ok installed$'; then
    missing+=("$p")
  fi
done
if ((${#missing[@]})); then
  echo "deps: installing Debian packages: ${missing[*]}"
  need_root "install: ${missing[*]}"
  [ "$updated" = yes ] || apt_update
  updated=yes
  "${SUDO[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}" </dev/null
else
  echo "deps: Debian packages present (${#APT_PACKAGES[@]})"
fi

# The i386 libcheck, unpacked from the Debian package of the amd64 one's
# version (mk/flags.mk: CHECK_I386_DIR).
CHECK_I386_DIR=.deps/check-i386
check_version=$(dpkg-query -W -f='${Version}' check)
if [ "$(cat "$CHECK_I386_DIR/version" 2>/dev/null)" != "$check_version" ] || \
   [ ! -f "$CHECK_I386_DIR/libcheck_pic.a" ]; then
  echo "deps: unpacking libcheck $check_version for i386 into $CHECK_I386_DIR"
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
  # apt-get download run by root fetches as the user _apt
  if [ "$(id -u)" -eq 0 ] && id _apt >/dev/null 2>&1; then chown _apt "$tmp"; fi
  if ! (cd "$tmp" && apt-get download -q "check:i386=$check_version" </dev/null >/dev/null); then
    need_root "refresh the package lists"
    [ "$updated" = yes ] || apt_update
    (cd "$tmp" && apt-get download -q "check:i386=$check_version" </dev/null >/dev/null)
  fi
  dpkg-deb -x "$tmp"/check_*_i386.deb "$tmp/x"
  rm -rf "$CHECK_I386_DIR"
  mkdir -p "$CHECK_I386_DIR"
  cp "$tmp"/x/usr/lib/i386-linux-gnu/libcheck.a "$tmp"/x/usr/lib/i386-linux-gnu/libcheck_pic.a "$CHECK_I386_DIR/"
  echo "$check_version" > "$CHECK_I386_DIR/version"
  rm -rf "$tmp"
  trap - EXIT
else
  echo "deps: i386 libcheck present ($CHECK_I386_DIR)"
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

# The sdists whose test data tests/replay reads (step 4 above). pip checks
# an sdist's version by building its metadata; both take their version from
# git (setuptools-scm), which an sdist does not have, hence the pretend.
SDIST_DIR=.deps/sdist
for name in python-can cantools; do
  ver=$(sed -n "s/^$name==//p" requirements.txt)
  if [ ! -f "$SDIST_DIR/${name//-/_}-$ver.tar.gz" ] && [ ! -f "$SDIST_DIR/$name-$ver.tar.gz" ]; then
    echo "deps: downloading the $name $ver source distribution into $SDIST_DIR (its test logs)"
    mkdir -p "$SDIST_DIR"
    SETUPTOOLS_SCM_PRETEND_VERSION="$ver" "$VENV/bin/pip" download -q --disable-pip-version-check --no-deps \
      --no-binary :all: --no-build-isolation "$name==$ver" -d "$SDIST_DIR" </dev/null
  fi
done
