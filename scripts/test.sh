#!/usr/bin/env bash
# The whole test suite: gtest (C++ cores), pytest (Python cores), rostest (integration).
# Installs and builds first when needed. Prints 'N passed, N failed' and exits non-zero on any
# failure or when no test ran.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
install_packages
build_workspace ON
RESULTS="$WS/build/test_results"
rm -rf "$RESULTS"
mkdir -p "$RESULTS/pytest"

# rostest starts its own master; everything talks over loopback, so a host name that does not
# resolve (a fresh container) does not matter and nothing listens beyond this machine.
export ROS_HOSTNAME=127.0.0.1 ROS_IP=127.0.0.1
unset ROS_MASTER_URI
# The U-Net backend of the end-to-end tests: the shipped bf16 where this CPU runs it natively,
# channels_last where oneDNN would emulate it (25x slower; asg_perception.numerics.test_backend).
export ASG_TEST_UNET_BACKEND="${ASG_TEST_UNET_BACKEND:-$(/usr/bin/python3 -c \
    'from asg_perception.numerics import test_backend; print(test_backend())')}"
log "U-Net backend of the end-to-end tests: $ASG_TEST_UNET_BACKEND"

log "style: ruff format --check and ruff check (ruff.toml)"
mkdir -p "$RESULTS/style"
/usr/bin/python3 "$REPO/scripts/ci/check_style.py" "$REPO" "$RESULTS/style/ruff.xml"

log "gtest + rostest (catkin_make run_tests)"
export LP_NUM_THREADS=1
# Test binaries build on both cores; the tests then run one at a time: the end-to-end rostests
# each run two workers with the U-Net, and side by side they would starve each other.
(cd "$WS" && catkin_make tests -j2 2>&1 | grep -E 'error|warning' ) || true
# The console shows each finished test file and every failure; the whole output, with the
# [ERROR] lines that fault-injection tests cause on purpose, goes to build/run_tests.log.
(cd "$WS" && catkin_make run_tests -j1 2>&1 | /usr/bin/python3 "$REPO/scripts/ci/console_filter.py" \
    "$WS/build/run_tests.log") || true

log "catkin_make install (into build/install_check)"
/usr/bin/python3 "$REPO/scripts/ci/check_install.py" "$WS" "$RESULTS/install/install.xml"

log "pytest (Python cores)"
for t in "$WS"/src/*/test; do
  pkg="$(basename "$(dirname "$t")")"
  ls "$t"/test_*.py >/dev/null 2>&1 || continue
  /usr/bin/python3 -m pytest -q -p no:cacheprovider --ignore="$t/rostest" \
      --junitxml="$RESULTS/pytest/$pkg.xml" "$t" || true
done

log "pytest (end-to-end tests in tests/: scale-out over two hosts, ...)"
/usr/bin/python3 -m pytest -q -p no:cacheprovider --junitxml="$RESULTS/pytest/tests.xml" "$REPO"/tests/test_*.py || true

/usr/bin/python3 "$REPO/scripts/ci/summarize_tests.py" "$RESULTS"
