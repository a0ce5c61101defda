#!/usr/bin/env bash
# The screenshot of docs/agent.md: the real TensorBoard page of a campaign's event files, taken
# headless. TensorBoard is not a dependency of the project: this puts it (pinned, with numpy < 2)
# in a virtual environment of its own under runs/, and Chromium from Debian.
#   bash scripts/repro/tensorboard_shot.sh LOGDIR OUT.png [URL_FRAGMENT=timeseries]
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
LOGDIR="$(realpath "${1:?usage: tensorboard_shot.sh LOGDIR OUT.png}")"
OUT="$(realpath -m "${2:?usage: tensorboard_shot.sh LOGDIR OUT.png}")"
VENV="$REPO/runs/tensorboard-venv"
[ -x "$VENV/bin/tensorboard" ] || {
  /usr/bin/python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet tensorboard==2.15.1 "numpy<2"
}
command -v chromium >/dev/null || as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends chromium
PORT="${ASG_TB_PORT:-6016}"
"$VENV/bin/tensorboard" --logdir "$LOGDIR" --host 127.0.0.1 --port "$PORT" >/dev/null 2>&1 &
TB=$!
trap 'kill $TB 2>/dev/null || true' EXIT
for _ in $(seq 30); do curl -sf "http://127.0.0.1:$PORT/" >/dev/null 2>&1 && break; sleep 1; done
chromium --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size=1600,1500 \
    --virtual-time-budget=20000 --screenshot="$OUT" "http://127.0.0.1:$PORT/?darkMode=false#${3:-timeseries}" \
    2>/dev/null
log "wrote $OUT"
