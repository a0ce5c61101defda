#!/usr/bin/env bash
# docs/your-stack.md's recipe from an install space (issue #55), run as a user would run it: only
# the installed toolkit sourced, in a clean environment, two user stacks in a workspace of their
# own overlaid on it.
#   - free-running: a copy of gap_nav renamed my_stack (no client of this project), steps 2-8: a
#     run of Exp. 1, a baseline of LAYOUTS seeded layouts, a campaign of SCENARIOS, its export,
#     report and a replay (which says by how much a free-running run differs);
#   - lockstep: asg_lockstep's twist_driver example built in the user's workspace against the
#     installed headers (my_lockstep), Exp. 1 run twice: the two trajectories must be equal.
# Exits 1 if a step fails. The install prefix is made by scripts/ci/check_install.py if missing.
# Steps 4-8 are the page's own commands (tests/doc_recipe.py pulls them from docs/your-stack.md
# and says which words it changes), run under Xvfb (step 4 starts rviz) on a sim-time master.
#   bash scripts/repro/your_stack_install.sh [WORK=/tmp/asg_recipe] [LAYOUTS=3] [SCENARIOS=5] [MODES=both|free]
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
WORK="${1:-/tmp/asg_recipe}"
LAYOUTS="${2:-3}"
SCENARIOS="${3:-5}"
MODES="${4:-both}"
PREFIX="$REPO/catkin_ws/build/install_check"
[ -f "$PREFIX/setup.bash" ] ||
  /usr/bin/python3 "$REPO/scripts/ci/check_install.py" "$REPO/catkin_ws" "$WORK/install.xml"
rm -rf "$WORK/my_ws" "$WORK/home" && mkdir -p "$WORK/my_ws/src" "$WORK/home"

# the user's two packages: gap_nav renamed, and the C++ client's example
cp -r "$REPO/catkin_ws/src/gap_nav" "$WORK/my_ws/src/my_stack"
(cd "$WORK/my_ws/src/my_stack" && rm -rf test && mv launch/gap_nav.launch launch/my_stack.launch &&
  grep -rl gap_nav . | xargs sed -i 's/gap_nav/my_stack/g')
cat > "$WORK/my_ws/src/my_stack/launch/asg_stack.launch" <<'EOF'
<launch>
  <arg name="output" default="log" />
  <rosparam ns="stack">
    name: my_stack
    nodes: [gap_drive, depth_to_cloud]
    mode: free
    acks: false
    command: twist
    sim_time: true
    worker: {publish_labels: false, realtime_factor: 1.0}
  </rosparam>
  <include file="$(find my_stack)/launch/my_stack.launch" />
</launch>
EOF
L="$WORK/my_ws/src/my_lockstep"
[ "$MODES" = free ] && L="$WORK/unused/my_lockstep"
mkdir -p "$L/src" "$L/launch" && cp "$REPO/catkin_ws/src/asg_lockstep/examples/twist_driver.cpp" "$L/src/"
cat > "$L/CMakeLists.txt" <<'EOF'
cmake_minimum_required(VERSION 3.10)
project(my_lockstep)
find_package(catkin REQUIRED COMPONENTS roscpp asg_lockstep geometry_msgs nav_msgs)
catkin_package()
add_executable(twist_driver src/twist_driver.cpp)
target_include_directories(twist_driver SYSTEM PRIVATE ${catkin_INCLUDE_DIRS})
target_link_libraries(twist_driver ${catkin_LIBRARIES})
set_target_properties(twist_driver PROPERTIES CXX_STANDARD 17)
EOF
cat > "$L/package.xml" <<'EOF'
<?xml version="1.0"?>
<package format="2">
  <name>my_lockstep</name>
  <version>0.0.1</version>
  <description>A user's stack with the C++ lockstep client.</description>
  <maintainer email="user@example.com">user</maintainer>
  <license>BSD</license>
  <buildtool_depend>catkin</buildtool_depend>
  <depend>roscpp</depend>
  <depend>asg_lockstep</depend>
  <depend>geometry_msgs</depend>
  <depend>nav_msgs</depend>
</package>
EOF
cat > "$L/launch/asg_stack.launch" <<'EOF'
<launch>
  <arg name="output" default="log" />
  <rosparam ns="stack">
    name: my_lockstep
    nodes: [twist_driver]
    command: twist
    worker: {publish_labels: false}
  </rosparam>
  <node pkg="my_lockstep" type="twist_driver" name="twist_driver" output="$(arg output)" />
</launch>
EOF

# the recipe, in a clean environment with only the install space (and then the user's) sourced
cat > "$WORK/recipe.sh" <<'EOF'
set -eo pipefail
PREFIX=$1 WORK=$2 LAYOUTS=$3 SCENARIOS=$4
step() { echo "== $*"; }
python3() { /usr/bin/python3 "$@"; }
export ROS_HOSTNAME=127.0.0.1 LP_NUM_THREADS=1
source "$PREFIX/setup.bash"
step "2. the user's workspace over the install space"
(cd "$WORK/my_ws" && catkin_make -DPYTHON_EXECUTABLE=/usr/bin/python3 > "$WORK/build.log" 2>&1) ||
  { tail -20 "$WORK/build.log"; exit 1; }
source "$WORK/my_ws/devel/setup.bash"
SCENE=$(rospack find asg_bringup)/scenarios/exp1.yaml
worker() {  # REG [sim_time]
  roslaunch --wait asg_bringup worker.launch stack:="$1" ${2:+sim_time:=$2} > "$WORK/worker.log" 2>&1 &
  WORKER=$!
}
stop_worker() { kill -INT $WORKER; wait $WORKER || true; }

if [ "$MODES" != free ]; then
  step "lockstep: my_lockstep, Exp. 1 twice (on a master of this script's own, stopped after)"
  export ROS_MASTER_URI=http://127.0.0.1:11461
  roscore -p 11461 > "$WORK/roscore.log" 2>&1 &
  CORE=$!
  until rostopic list > /dev/null 2>&1; do sleep 1; done
  worker "$(rospack find my_lockstep)/launch/asg_stack.launch"
  cd "$WORK/home"
  for i in 1 2; do rosrun asg_scenario run_scenario "$SCENE" --worker /worker_0 --out "lock$i" --timeout 300 | tail -1; done
  cmp lock1/trajectory.csv lock2/trajectory.csv
  echo "lockstep: the two runs' trajectories are equal"
  stop_worker
  kill -INT $CORE; wait $CORE || true
fi

step "free: my_stack, docs/your-stack.md's steps 4-8 as the page writes them (step 4 starts the master)"
export ROS_MASTER_URI=http://127.0.0.1:11311  # a user's default: the page's roscore listens there
cd "$WORK/home"
source "$WORK/steps.sh"
test "$(wc -l < ~/asg_runs/baseline/exp1-my-stack/my_stack.jsonl)" -eq "$LAYOUTS"
test -f ~/asg_runs/report/index.html
test -s ~/asg_runs/job.bag
echo "the recipe ran from the install space ($MODES)"
EOF
/usr/bin/python3 "$REPO/tests/doc_recipe.py" --layouts "$LAYOUTS" --scenarios "$SCENARIOS" > "$WORK/steps.sh"
exec env -i PATH=/usr/bin:/bin HOME="$WORK/home" TERM=dumb MODES="$MODES" \
  xvfb-run -a -s "-screen 0 1280x1024x24" bash "$WORK/recipe.sh" "$PREFIX" "$WORK" "$LAYOUTS" "$SCENARIOS"
