#!/usr/bin/env bash
# Creates/refreshes the project's virtualenv (.venv) with the tested package versions
# (constraints.txt), and on Debian as root installs the few system libraries Qt needs for windows
# and for Xvfb.
# Sourced or run by scripts/start-demo and scripts/run-tests; safe to run again (it is quick
# when nothing changed: a stamp file records the pyproject.toml and constraints it installed).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$repo"

want_system=(libgl1 libegl1 libglib2.0-0 libfontconfig1 libdbus-1-3 libxkbcommon0
             xvfb xauth libxcb-cursor0 libxcb-icccm4 libxcb-image0 libxcb-keysyms1
             libxcb-render-util0 libxcb-shape0 libxcb-xkb1 libxkbcommon-x11-0)
if command -v dpkg-query >/dev/null 2>&1; then
  missing=()
  for pkg in "${want_system[@]}"; do
    dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
  done
  if ((${#missing[@]})); then
    if [ "$(id -u)" = 0 ]; then
      echo "setup: installing system packages: ${missing[*]}"
      export DEBIAN_FRONTEND=noninteractive
      apt-get update -qq >/dev/null
      apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
    else
      echo "setup: missing system packages (install them with sudo apt-get install): ${missing[*]}" >&2
    fi
  fi
fi

# The interpreter: $BADMINTON_PYTHON when set, else the newest supported one on PATH.
supported='import sys; sys.exit(not ((3, 11) <= sys.version_info[:2] <= (3, 13)))'
python=""
for candidate in ${BADMINTON_PYTHON:-} python3.13 python3.12 python3.11 python3; do
  if command -v "$candidate" >/dev/null 2>&1 && "$candidate" -c "$supported" 2>/dev/null; then
    python="$candidate"; break
  fi
done
if [ -n "${BADMINTON_PYTHON:-}" ] && [ "$python" != "$BADMINTON_PYTHON" ]; then
  echo "setup: BADMINTON_PYTHON=$BADMINTON_PYTHON is not a Python 3.11, 3.12 or 3.13" >&2
  exit 1
fi
if [ -z "$python" ]; then
  echo "setup: Python 3.11, 3.12 or 3.13 is required (none found on PATH; set BADMINTON_PYTHON)" >&2
  exit 1
fi

# A .venv made by another supported interpreter is kept unless BADMINTON_PYTHON asks for another.
if [ -x .venv/bin/python ] && [ -n "${BADMINTON_PYTHON:-}" ]; then
  want="$("$python" -c 'import sys; print(*sys.version_info[:2])')"
  have="$(.venv/bin/python -c 'import sys; print(*sys.version_info[:2])' 2>/dev/null || true)"
  if [ "$want" != "$have" ]; then
    echo "setup: replacing .venv (Python $have) with $($python --version)"
    rm -rf .venv
  fi
fi
if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv with $($python --version)"
  "$python" -m venv .venv
fi
stamp=.venv/.installed-requirements
if ! cat pyproject.toml constraints.txt | cmp -s - "$stamp" 2>/dev/null; then
  echo "setup: installing the tested package versions into .venv (first run takes a minute)"
  log=.venv/pip-install.log
  if ! { .venv/bin/python -m pip install --upgrade pip &&
         .venv/bin/python -m pip install -c constraints.txt -e ".[test]"; } >"$log" 2>&1; then
    tail -n 30 "$log" >&2
    echo "setup: installing the packages failed (full log: $log)" >&2
    exit 1
  fi
  .venv/bin/python -c "import badminton_gui, cv2, PySide6, pyqtgraph, serial"
  cat pyproject.toml constraints.txt >"$stamp"
fi
