#!/usr/bin/env bash
# One entry point that does all set-up itself on a fresh Debian/Ubuntu machine:
#   ./quickstart.sh demo   the main job (see README)
#   ./quickstart.sh test   the whole test suite (CI runs this)
#   ./quickstart.sh setup  only the set-up (ends by compiling the planner's kernels once)
#   ./quickstart.sh shell  a shell with the project's environment
# Set-up is idempotent: a stamp file records what was installed, so a second run is fast.
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
VENV="${DAP_VENV:-$HERE/.venv}"
PY="$VENV/bin/python"

log() { printf '[quickstart] %s\n' "$*" >&2; }

as_root() {
  if [ "$(id -u)" = 0 ]; then "$@"; elif command -v sudo >/dev/null; then sudo "$@"; else
    log "need root for: $*"; return 1; fi
}

apt_install() {
  # Install Debian packages that are missing; one apt-get update per run at most.
  local missing=()
  for p in "$@"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
  [ ${#missing[@]} -eq 0 ] && return 0
  command -v apt-get >/dev/null || { log "apt-get not found; please install: ${missing[*]}"; return 1; }
  log "installing Debian packages: ${missing[*]}"
  as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >/dev/null
}

find_python() {
  for c in python3.13 python3.12 python3.11 python3; do
    if command -v "$c" >/dev/null && "$c" -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
      echo "$c"; return 0; fi
  done
  log "Python >= 3.11 is required"; return 1
}

setup_python() {
  local base
  base="$(find_python)"
  if [ ! -x "$PY" ]; then
    log "creating virtual environment $VENV"
    if ! "$base" -m venv "$VENV" 2>/dev/null; then
      rm -rf "$VENV"
      apt_install python3-venv
      "$base" -m venv "$VENV"
    fi
  fi
  local stamp="$VENV/.dap-stamp" want
  want="$(cat "$HERE/requirements.txt" "$HERE/setup.py" | sha256sum | cut -c1-16)"
  if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
    log "installing pinned Python dependencies (about a minute the first time)"
    "$PY" -m pip install -q -r "$HERE/requirements.txt"
    "$PY" -m pip install -q --no-deps --no-build-isolation -e "$HERE"
    echo "$want" > "$stamp"
  fi
}

setup_test_tools() {
  # check_urdf for the URDF test; chromium + xvfb for the browser test (see README).
  apt_install liburdfdom-tools
  if [ -f "$HERE/test/browser/package.json" ]; then
    # Commands, not package names: a machine may have Node.js (with npm) from elsewhere.
    command -v chromium >/dev/null || apt_install chromium
    command -v node >/dev/null || apt_install nodejs
    command -v npm >/dev/null || apt_install npm
    if [ ! -d "$HERE/test/browser/node_modules/playwright-core" ]; then
      log "installing playwright-core (npm, pinned)"
      (cd "$HERE/test/browser" && npm ci --silent --no-audit --no-fund)
    fi
  fi
}

warm_up() {
  # Compile the planner's kernels now, with progress, not inside the first node start (where
  # the page would wait minutes for a planner that looks stuck). Seconds when already cached.
  "$PY" -m digital_actor_planner.warmup \
    || log "warm-up failed; the planner compiles its kernels on its first start instead"
}

setup_meshes() {
  # Third-party scenes (zlib licence, not committed) for the large-scene bench and tests.
  "$PY" "$HERE/bench/third_party_meshes.py" fetch >/dev/null \
    || log "third-party meshes not fetched: the tests that walk them are skipped"
}

ros_env() {
  # Keep DDS discovery on this machine: Kilted ignores ROS_LOCALHOST_ONLY.
  export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
  export RMW_IMPLEMENTATION="${RMW_IMPLEMENTATION:-rmw_fastrtps_cpp}"
  export AMENT_PREFIX_PATH="$VENV${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
  export PATH="$VENV/bin:$PATH"
  export MPLBACKEND=Agg
}

cmd="${1:-demo}"
[ $# -gt 0 ] && shift
case "$cmd" in
  setup)
    setup_python; setup_test_tools; setup_meshes; warm_up ;;
  demo)
    # The demo warms the kernel cache itself when it is not current.
    setup_python; ros_env
    exec "$PY" -m digital_actor_planner.cli demo "$@" ;;
  test)
    setup_python; setup_test_tools; setup_meshes; warm_up; ros_env
    cd "$HERE"
    exec "$PY" -m pytest "$@" ;;
  shell)
    setup_python; ros_env; exec bash "$@" ;;
  *)
    log "usage: $0 demo|test|setup|shell [args...]"; exit 2 ;;
esac
