#!/usr/bin/python3
"""Run the suite's test files side by side on the machine's cores (issue #69).

The suite's jobs are every gtest and rostest that catkin registered with CTest, each package's
pytest folder, and the top-level tests/ folder (a file that took SPLIT_S or more in the estimates
runs as a job of its own, the rest as one job). Most of them use one core at a time: a lockstep
run hands the CPU from the simulator to the stack and back, so on a 2-core machine one job leaves
the other core idle. The jobs are started longest first by their estimated time (the list
scheduling rule that keeps the lanes even) on JOBS lanes.

Each job's output goes to LOGS/NAME.log; the console gets one line per finished job and, for a job
that failed, the end of its log. Every job leaves a JUnit file under RESULTS: a job that wrote
none (it crashed, or ran past --timeout and was killed) gets one that fails and names its log, so
that the closing summary counts it.

    run_parallel.py WS REPO RESULTS LOGS [--jobs 2] [--estimates TIMES.json] [--timeout 2400]

TIMES.json is a record of summarize_tests.py (`{"files": {test file: seconds}}`); without it, or
for a file it lacks, a job is estimated at DEFAULT_S."""

import argparse
import glob
import json
import os
import signal
import subprocess
import sys
import threading
from concurrent.futures import ThreadPoolExecutor
import time
from xml.sax.saxutils import escape, quoteattr

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import console_filter  # noqa: E402

SPLIT_S = 10.0  #: [s] a tests/ file estimated at this or more runs as a job of its own
DEFAULT_S = 5.0  #: [s] the estimate of a job the estimates do not know
PYTEST = ["/usr/bin/python3", "-m", "pytest", "-q", "-p", "no:cacheprovider"]


class Job:
    def __init__(self, name, cmd, cwd, result, estimate):
        self.name, self.cmd, self.cwd, self.result, self.estimate = name, cmd, cwd, result, estimate
        self.seconds, self.rc = 0.0, None


def ctest_jobs(ws, results, est):
    """Every gtest binary and rostest catkin registered with CTest, run by its own command:
    catkin's run_tests.py, which writes a failing result file when the test wrote none. The pytest
    files and folders registered too (scripts/ci/pytest.cmake, for ctest) are pytest_jobs'."""
    build = os.path.join(ws, "build")
    out = subprocess.run(["ctest", "--show-only=json-v1"], cwd=build, capture_output=True, text=True, check=True)
    jobs = []
    for t in json.loads(out.stdout)["tests"]:
        if "_pytest_" in t["name"]:
            continue
        cwd = next((p["value"] for p in t.get("properties", []) if p["name"] == "WORKING_DIRECTORY"), build)
        result = t["command"][3]  # run_tests.py RESULT_FILE [--return-code] COMMAND
        rel = os.path.relpath(result, results)
        wrapped = os.path.join(os.path.dirname(rel), os.path.basename(rel).replace("rostest-", "rosunit-", 1))
        estimate = est.get(wrapped, est.get(rel, DEFAULT_S))
        jobs.append(Job(rel, t["command"], cwd, result, estimate))
    return jobs


def pytest_jobs(ws, repo, results, est):
    """Each package's test/ folder (its rostest/ left to rostest), and tests/ in parts."""
    jobs = []
    for t in sorted(glob.glob(os.path.join(ws, "src", "*", "test"))):
        if not glob.glob(os.path.join(t, "test_*.py")):
            continue
        pkg = os.path.basename(os.path.dirname(t))
        xml = os.path.join(results, "pytest", f"{pkg}.xml")
        estimate = sum(v for k, v in est.items() if k.startswith(f"{pkg}: ")) or DEFAULT_S
        cmd = PYTEST + [f"--ignore={t}/rostest", f"--junitxml={xml}", t]
        jobs.append(Job(f"pytest/{pkg}", cmd, repo, xml, estimate))
    rest = []
    for f in sorted(glob.glob(os.path.join(repo, "tests", "test_*.py"))):
        stem = os.path.splitext(os.path.basename(f))[0]
        estimate = est.get(f"tests: tests.{stem}", 0.0)
        if estimate >= SPLIT_S:
            xml = os.path.join(results, "pytest", "tests", f"{stem}.xml")
            jobs.append(Job(f"pytest/tests/{stem}", PYTEST + [f"--junitxml={xml}", f], repo, xml, estimate))
        else:
            rest.append((f, estimate))
    if rest:
        xml = os.path.join(results, "pytest", "tests.xml")
        estimate = sum(e for _, e in rest) or DEFAULT_S
        jobs.append(Job("pytest/tests", PYTEST + [f"--junitxml={xml}"] + [f for f, _ in rest], repo, xml, estimate))
    return jobs


def failed_result(job, log, why):
    """A JUnit file that fails, for a job that wrote none."""
    os.makedirs(os.path.dirname(job.result), exist_ok=True)
    with open(job.result, "w", encoding="utf-8") as f:
        f.write(
            f'<?xml version="1.0"?>\n<testsuite name={quoteattr(job.name)} tests="1" failures="1">'
            f'<testcase classname="run_parallel" name={quoteattr(job.name)} time="{job.seconds:.1f}">'
            f'<failure message="no result file">{escape(why)}: see {escape(log)}</failure></testcase></testsuite>\n'
        )


def run(job, logs, timeout):
    log = os.path.join(logs, job.name.replace(os.sep, "__") + ".log")
    t0 = time.monotonic()
    with open(log, "w", encoding="utf-8", errors="replace") as out:
        p = subprocess.Popen(job.cmd, cwd=job.cwd, stdout=out, stderr=subprocess.STDOUT, start_new_session=True)
        try:
            job.rc = p.wait(timeout=timeout)
            why = f"exited {job.rc} without writing {job.result}"
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)  # the job and everything it started
            job.rc = p.wait()
            why = f"killed after {timeout:.0f} s"
    job.seconds = time.monotonic() - t0
    if not os.path.exists(job.result) or job.rc < 0:
        failed_result(job, log, why)
    return log


def schedule(jobs, lanes, logs, timeout):
    """Longest estimate first, onto the first free lane; one console line per finished job and,
    for a failed one, the lines of its log that console_filter shows (its failures, not the
    [ERROR] lines that fault-injection tests log on purpose)."""
    done, lock = [], threading.Lock()

    def one(job):
        log = run(job, logs, timeout)
        with lock:
            done.append(job)
            verdict = "ok" if job.rc == 0 else f"FAILED (exit {job.rc}; {log})"
            print(f"[{len(done):3d}/{len(jobs)}] {job.seconds:7.1f} s  {verdict}  {job.name}", flush=True)
            if job.rc != 0:
                with open(log, encoding="utf-8", errors="replace") as f:
                    lines = [ln for ln in f if console_filter.shown(ln)] or ["    (nothing the filter shows)\n"]
                sys.stdout.write("".join("    " + ln for ln in lines[-20:]))

    # the pool runs its tasks in the order they were submitted
    with ThreadPoolExecutor(max_workers=lanes) as pool:
        for f in [pool.submit(one, j) for j in sorted(jobs, key=lambda j: -j.estimate)]:
            f.result()
    return done


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("ws")
    ap.add_argument("repo")
    ap.add_argument("results")
    ap.add_argument("logs")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="lanes run side by side")
    ap.add_argument("--estimates", help="a times.json record of summarize_tests.py")
    ap.add_argument("--timeout", type=float, default=2400.0, help="[s] a job still running then is killed")
    a = ap.parse_args(argv)
    if a.jobs < 1:
        ap.error(f"--jobs {a.jobs}: at least 1")
    est = {}
    if a.estimates:
        try:
            with open(a.estimates, encoding="utf-8") as f:
                est = json.load(f)["files"]
        except (OSError, ValueError, KeyError) as e:
            ap.error(f"--estimates {a.estimates}: not a times record ({e})")
    os.makedirs(a.logs, exist_ok=True)
    jobs = ctest_jobs(a.ws, a.results, est) + pytest_jobs(a.ws, a.repo, a.results, est)
    t0 = time.monotonic()
    done = schedule(jobs, a.jobs, a.logs, a.timeout)
    wall = time.monotonic() - t0
    busy = sum(j.seconds for j in done)
    print(
        f"{len(done)} jobs on {a.jobs} lanes: {busy:.0f} s of job time in {wall:.0f} s ({busy / max(wall, 1e-9):.2f}x)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
