# Shared by setup.sh, demo.sh and test.sh: paths, the Debian packages, install and build steps.
# Debian's ROS 1 lives in /usr/bin/python3's site-packages: whatever python3 comes first on the
# caller's PATH, everything here runs with /usr/bin/python3.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
WS="$REPO/catkin_ws"
export PATH="/usr/bin:/bin:/usr/sbin:/sbin:$PATH"
export PYTHONDONTWRITEBYTECODE=1
export ROS_PYTHON_VERSION=3

# Every package the stack needs, all from Debian bookworm.
APT_PACKAGES=(
  build-essential cmake catkin python3-catkin-pkg ros-message-generation ros-message-runtime
  libroscpp-dev python3-rospy librostest-dev python3-rostest rosbash python3-roslaunch
  libactionlib-dev python3-actionlib libtf2-ros-dev python3-tf2-ros librosbag-dev python3-rosbag
  ros-std-msgs ros-geometry-msgs ros-sensor-msgs ros-nav-msgs ros-visualization-msgs
  libstd-msgs-dev libgeometry-msgs-dev libsensor-msgs-dev libnav-msgs-dev libvisualization-msgs-dev
  python3-std-msgs python3-geometry-msgs python3-sensor-msgs python3-nav-msgs
  python3-visualization-msgs python3-actionlib-msgs libactionlib-msgs-dev
  rviz ros-desktop-dev
  libbullet-dev libosmesa6-dev mesa-common-dev liboctomap-dev libeigen3-dev libopencv-dev
  libgtest-dev googletest libyaml-cpp-dev
  python3-torch python3-opencv python3-numpy python3-yaml python3-matplotlib python3-scipy python3-tqdm
  python3-pytest python3-pil xvfb python3-pip python3-protobuf
  python3-numba python3-pandas python3-sklearn python3-threadpoolctl python3-sortedcontainers
  libros-rosgraph-msgs-dev python3-rosgraph-msgs
  # gap_nav, the third stack under test (issue #55): Debian's nodelet and depth_image_proc
  libnodeletlib-tools libdepth-image-proc0d libdepth-image-proc-dev
)
# From PyPI, pinned, without dependencies (every dependency above is Debian's: pip's numpy 2 would
# break Debian's torch): TensorBoard's event-file writer for campaign scalars, CMA-ES for the
# `cmaes` search, and pyribs (the last release for numpy 1) with its one dependency Debian lacks
# for the `map-elites` search (docs/agent.md), all pure Python; and ruff, the formatter and linter
# that scripts/test.sh runs (ruff.toml; a static binary). ONNX Runtime, OpenVINO and onnx (for
# int8 quantization) are measured beside torch in issue #24's backend table
# (python3 -m asg_perception.runtimes); the versions are the last built for numpy 1, and the
# segmenter node does not use them. orjson parses the campaign exports (asg_agent.records.export;
# the same values as the standard library's json, two to three times as fast: the analysis and
# its tests read each export several times).
PIP_PACKAGES=(tensorboardX==2.6.2.2 cma==3.3.0 numpy-groupies==0.11.2 ribs==0.7.1 ruff==0.8.4
  onnxruntime==1.19.2 openvino==2024.4.0 onnx==1.16.2 orjson==3.10.12)

log() { printf '\033[1m[asg]\033[0m %s\n' "$*"; }

as_root() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }

install_packages() {
  local missing=()
  for p in "${APT_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -eq 0 ]; then
    log "all ${#APT_PACKAGES[@]} Debian packages present"
  else
    log "installing ${#missing[@]} Debian packages: ${missing[*]}"
    as_root apt-get update
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}"
  fi
  install_pip_packages
}

install_pip_packages() {
  local p name want have
  for p in "${PIP_PACKAGES[@]}"; do
    name="${p%%==*}"; want="${p##*==}"
    # `pip show` fails for a package not installed: under pipefail that must not end the script.
    have="$({ /usr/bin/python3 -m pip show "$name" 2>/dev/null || true; } | sed -n 's/^Version: //p')"
    [ "$have" = "$want" ] && continue
    log "installing $p from PyPI (no dependencies) for /usr/bin/python3"
    as_root /usr/bin/python3 -m pip install --quiet --no-input --disable-pip-version-check \
        --break-system-packages --no-deps "$p"
  done
}

source_ros() {
  # setup files read unset variables
  set +u
  # shellcheck disable=SC1091
  [ -f "$WS/devel/setup.bash" ] && source "$WS/devel/setup.bash"
  set -u
}

build_workspace() {
  local first=0
  [ -f "$WS/devel/setup.bash" ] || first=1
  log "building catkin workspace $WS"
  source_ros
  (cd "$WS" && catkin_make -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCMAKE_BUILD_TYPE=Release \
      -DCATKIN_ENABLE_TESTING="${1:-ON}" -j2 "${@:2}")
  if [ "$first" -eq 1 ]; then
    # Debian's catkin: the first configure does not put the devel space on the Python path of
    # rostest nodes; configuring again with the workspace sourced does.
    log "first build: configuring again with the devel space sourced"
    source_ros
    (cd "$WS" && catkin_make --force-cmake -DPYTHON_EXECUTABLE=/usr/bin/python3 \
        -DCMAKE_BUILD_TYPE=Release -DCATKIN_ENABLE_TESTING="${1:-ON}" -j2 "${@:2}")
  fi
  source_ros
}

# A ROS master of our own, on loopback and a port of our own (a user's roscore is left alone),
# and scene workers for studies that drive workers directly (baseline, flaw_or_layout, soak).
#   use_local_master PORT LOG_DIR     exports ROS_MASTER_URI and friends, one llvmpipe thread each
#   start_master                      roscore on that port; its PID in MASTER_PID
#   start_workers N ARGS...           N worker.launch (worker_0..), markers off; PIDs in WORKER_PIDS
#   stop_workers; stop_master
use_local_master() {
  export ROS_MASTER_URI="http://127.0.0.1:$1" ROS_HOSTNAME=127.0.0.1 ROS_IP=127.0.0.1
  export LP_NUM_THREADS=1 ROS_LOG_DIR="$2"
  mkdir -p "$ROS_LOG_DIR"
}
start_master() {  # returns once the master answers: a roslaunch that finds none starts its own
  roscore -p "${ROS_MASTER_URI##*:}" >/dev/null 2>&1 &
  MASTER_PID=$!
  local t
  for t in $(seq 120); do  # a loaded machine (campaigns beside it) takes more than a few seconds
    rosparam get /run_id >/dev/null 2>&1 && return 0
    kill -0 "$MASTER_PID" 2>/dev/null || break
    sleep 0.5
  done
  echo "start_master: no ROS master answers at $ROS_MASTER_URI after 60 s" >&2
  return 1
}
start_workers() {
  local n="$1" w
  shift
  WORKER_PIDS=()
  for ((w = 0; w < n; w++)); do
    roslaunch --wait "$REPO/launch/worker.launch" ns:="worker_$w" markers:=false "$@" >/dev/null 2>&1 &
    WORKER_PIDS+=($!)
  done
}
stop_workers() {  # safe to call before start_workers (an EXIT trap)
  [ -n "${WORKER_PIDS[*]:-}" ] || return 0
  kill "${WORKER_PIDS[@]}" 2>/dev/null || true
  wait "${WORKER_PIDS[@]}" 2>/dev/null || true
  WORKER_PIDS=()
}
stop_master() {
  [ -n "${MASTER_PID:-}" ] || return 0
  kill "$MASTER_PID" 2>/dev/null || true
  wait "$MASTER_PID" 2>/dev/null || true
  MASTER_PID=""
}
