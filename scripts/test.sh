#!/usr/bin/env bash
# The whole test suite: gtest (C++ cores), pytest (Python cores), rostest (integration).
# Installs and builds first when needed. Prints 'N passed, N failed' and exits non-zero on any
# failure or when no test ran.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
# the whole run's wall time, measured from here (summarize_tests.py writes it into times.json as wall_s)
export ASG_SUITE_START="${ASG_SUITE_START:-$(date +%s.%N)}"
install_packages
build_workspace ON
RESULTS="$WS/build/test_results"
rm -rf "$RESULTS"
mkdir -p "$RESULTS/pytest"

# rostest starts its own master; everything talks over loopback, so a host name that does not
# resolve (a fresh container) does not matter and nothing listens beyond this machine.
export ROS_HOSTNAME=127.0.0.1 ROS_IP=127.0.0.1
unset ROS_MASTER_URI
# The U-Net backend of the end-to-end tests: the shipped default (fp32 polyphase), or, were the
# default a bf16 one, channels_last where oneDNN would emulate it (asg_perception.numerics.test_backend).
export ASG_TEST_UNET_BACKEND="${ASG_TEST_UNET_BACKEND:-$(/usr/bin/python3 -c \
    'from asg_perception.numerics import test_backend; print(test_backend())')}"
log "U-Net backend of the end-to-end tests: $ASG_TEST_UNET_BACKEND"

log "style: ruff format --check and ruff check (ruff.toml)"
mkdir -p "$RESULTS/style"
/usr/bin/python3 "$REPO/scripts/ci/check_style.py" "$REPO" "$RESULTS/style/ruff.xml"

# The install check reconfigures the build folder (another install prefix, then back): it runs
# before the test binaries are built and the tests read that folder.
log "catkin_make install (into build/install_check)"
/usr/bin/python3 "$REPO/scripts/ci/check_install.py" "$WS" "$RESULTS/install/install.xml"

log "building the test binaries"
export LP_NUM_THREADS=1
(cd "$WS" && catkin_make tests -j2 2>&1 | grep -E 'error|warning' ) || true

# gtest, rostest and pytest files side by side, one job a core, longest first by the times of the
# newest record (issue #69): most of them use one core at a time. The console shows each finished
# job and the end of a failed one's log; each job's whole output, with the [ERROR] lines that
# fault-injection tests cause on purpose, is in build/test_logs/. ASG_TEST_JOBS=1 runs them one
# at a time.
rm -rf "$WS/build/test_logs"
mkdir -p "$WS/build/test_logs"
if [ "${ASG_TEST_RUNNER:-parallel}" = ctest ]; then
  # CTest runs every registered test (gtest, rostest, and the pytest files and folders that
  # scripts/ci/pytest.cmake registers), ordered by the costs it learnt in this build folder
  log "gtest + rostest + pytest by ctest -j ${ASG_TEST_JOBS:-$(nproc)} (log in build/test_logs/ctest.log)"
  # ctest's own verdict counts too: a test that could not even start writes no JUnit file
  ctest_rc=0
  # (under pipefail the pipeline's status is ctest's; its summary line always matches the filter)
  (cd "$WS/build" && ctest -j "${ASG_TEST_JOBS:-$(nproc)}" --timeout 2400 --output-log "$WS/build/test_logs/ctest.log" 2>&1 \
      | grep --line-buffered -E '^ *[0-9]+/[0-9]+ Test|tests passed|tests failed') || ctest_rc=$?
else
  log "gtest + rostest + pytest, ${ASG_TEST_JOBS:-$(nproc)} side by side (logs in build/test_logs/)"
  /usr/bin/python3 "$REPO/scripts/ci/run_parallel.py" "$WS" "$REPO" "$RESULTS" "$WS/build/test_logs" \
      --jobs "${ASG_TEST_JOBS:-$(nproc)}" --estimates "$REPO/results/suite_times/r6-ae5392e-xeon-noamx.json"
fi

/usr/bin/python3 "$REPO/scripts/ci/summarize_tests.py" "$RESULTS"
if [ "${ctest_rc:-0}" -ne 0 ]; then
  log "ctest failed (exit $ctest_rc): see $WS/build/test_logs/ctest.log"
  exit "$ctest_rc"
fi
