"""The CI helpers of scripts/ci: what the test console shows (issue #38: expected errors of the
fault-injection tests out of it, every failure in it) and the closing summary."""

import json
import os
import subprocess
import sys

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
sys.path.insert(0, os.path.join(REPO, "scripts", "ci"))
import console_filter  # noqa: E402

RUN = """\
[ERROR] [1795651097.2]: scene worker: goal refused: layouts[0].instances[2].x = nan: not a number
[ WARN] [1795651097.3]: planner: scenario 4: cannot use the frame at t = 0.1
[ROSUNIT] Outputting test results to /ws/build/test_results/asg_tests/rostest-tests_bad_input.xml
[Testcase: testbad_input] ... ok
[Testcase: testcampaign] ... FAILURE!
 * RESULT: FAIL
[  PASSED  ] 12 tests.
[  FAILED  ] Parameters.BadValuesAreRefusedWithTheParameterNamed
/ws/src/asg_planner/src/core/parameters.cpp:12:3: error: 'x' was not declared in this scope
make[2]: *** [CMakeFiles/planner.dir/build.make:76] Error 1
Traceback (most recent call last):
"""


def test_the_console_keeps_verdicts_and_failures_and_drops_node_logs(tmp_path):
    log = tmp_path / "run_tests.log"
    res = subprocess.run(
        [sys.executable, os.path.join(REPO, "scripts", "ci", "console_filter.py"), str(log)],
        input=RUN,
        capture_output=True,
        text=True,
        check=True,
    )
    shown = res.stdout.splitlines()
    assert "[ERROR]" not in res.stdout and "[ WARN]" not in res.stdout
    assert shown[0].startswith("[ROSUNIT] Outputting test results to")
    assert "[Testcase: testcampaign] ... FAILURE!" in shown and "[Testcase: testbad_input] ... ok" not in shown
    assert " * RESULT: FAIL" in shown
    assert "[  FAILED  ] Parameters.BadValuesAreRefusedWithTheParameterNamed" in shown
    assert any(": error: 'x' was not declared" in s for s in shown)
    assert any(s.startswith("make[2]: ***") for s in shown)
    assert shown[-1] == f"(the whole output of the tests, nodes' expected errors included: {log})"
    assert log.read_text() == RUN  # nothing lost


def test_shown_is_a_pure_line_rule():
    assert console_filter.shown("[  FAILED  ] 1 test, listed below:")
    assert not console_filter.shown("[ERROR] [1.0]: planner: error: x")


def summarize(folder):
    """scripts/ci/summarize_tests.py over the result files in `folder`."""
    return subprocess.run(
        [sys.executable, os.path.join(REPO, "scripts", "ci", "summarize_tests.py"), str(folder)],
        capture_output=True,
        text=True,
    )


def test_the_summary_names_each_failure_and_fails_on_it(tmp_path):
    (tmp_path / "a.xml").write_text(
        '<testsuite><testcase classname="A" name="ok"/><testcase classname="A" name="bad">'
        '<failure message="boom">Traceback\nAssertionError: 1 != 2</failure></testcase>'
        '<testcase classname="A" name="skip"><skipped/></testcase></testsuite>'
    )
    res = summarize(tmp_path)
    assert res.returncode == 1
    assert "FAILED a.xml::A.bad" in res.stdout
    assert "AssertionError: 1 != 2" in res.stdout  # why, without opening the file
    assert res.stdout.splitlines()[-1] == "tests: 1 passed, 1 failed, 1 skipped"
    (tmp_path / "a.xml").write_text('<testsuite><testcase classname="A" name="ok"/></testsuite>')
    res = summarize(tmp_path)
    assert res.returncode == 0 and res.stdout.splitlines()[-1] == "tests: 1 passed, 0 failed, 0 skipped"


def test_the_summary_lists_the_slowest_test_files(tmp_path):
    (tmp_path / "pytest").mkdir()
    (tmp_path / "pytest" / "asg_agent.xml").write_text(
        '<testsuites><testsuite><testcase classname="test.test_campaign" name="a" time="30.5"/>'
        '<testcase classname="test.test_campaign" name="b" time="10"/>'
        '<testcase classname="test.test_td3.TestAgent" name="c" time="2"/></testsuite></testsuites>'
    )
    (tmp_path / "rosunit-suite.xml").write_text(
        '<testsuite><testcase classname="S" name="t" time="95.25"/></testsuite>'
    )
    # the rostest file of the same test wraps that run: not counted again
    (tmp_path / "rostest-suite.xml").write_text('<testsuite><testcase classname="R" name="t" time="96"/></testsuite>')
    lines = summarize(tmp_path).stdout.splitlines()
    at = lines.index("slowest test files (3 files, 2.3 min in all):")
    assert lines[at + 1 : at + 4] == [
        "      95.2 s  rosunit-suite.xml",
        "      40.5 s  asg_agent: test.test_campaign",
        "       2.0 s  asg_agent: test.test_td3",
    ]
    rec = json.loads((tmp_path / "times.json").read_text())  # every file's time, for a later comparison
    assert rec["files"] == {
        "rosunit-suite.xml": 95.2,
        "asg_agent: test.test_campaign": 40.5,
        "asg_agent: test.test_td3": 2.0,
    }
    assert rec["cores"] >= 1 and "cpu" in rec
    # two runs compared file by file: the files both ran, and those only one ran
    other = dict(rec, files={"rosunit-suite.xml": 80.0, "asg_agent: test.test_campaign": 50.0, "new.xml": 9.0})
    (tmp_path / "other.json").write_text(json.dumps(other))
    cmp = subprocess.run(
        [sys.executable, os.path.join(REPO, "scripts", "ci", "summarize_tests.py"), "--compare"]
        + [str(tmp_path / "times.json"), str(tmp_path / "other.json")],
        capture_output=True,
        text=True,
    )
    assert cmp.returncode == 0, cmp.stderr
    assert "files in both: 2, 135.7 s before, 130.0 s after (0.96x)" in cmp.stdout
    assert "only before: 1 file, 2.0 s; only after: 1 file, 9.0 s" in cmp.stdout


def test_an_error_outside_any_test_case_is_a_failure(tmp_path):
    # What rosunit writes when a rostest's setUpClass raises: no test case, errors="1".
    (tmp_path / "rosunit-sound_runs.xml").write_text(
        '<testsuite errors="1" failures="0" name="unittest.suite.TestSuite" tests="0" time="7.8"></testsuite>'
    )
    (tmp_path / "rostest-sound_runs.xml").write_text(
        '<testsuite errors="0" failures="0" tests="1"><testcase classname="rostest.runner.RosTest" name="t"/></testsuite>'
    )
    # A suite whose count matches its test cases is not counted twice.
    (tmp_path / "b.xml").write_text(
        '<testsuites><testsuite errors="1" failures="1" name="B"><testcase classname="B" name="e"><error>x</error>'
        '</testcase><testcase classname="B" name="f"><failure>y</failure></testcase></testsuite></testsuites>'
    )
    res = summarize(tmp_path)
    assert res.returncode == 1
    assert "FAILED rosunit-sound_runs.xml::unittest.suite.TestSuite" in res.stdout
    assert "setUpClass" in res.stdout
    assert res.stdout.splitlines()[-1] == "tests: 1 passed, 3 failed, 0 skipped"


def test_rostest_repeat_reads_a_failing_summary_through_its_colours(tmp_path):
    """rostest colours a failing count (ESC[1;31m * FAILURES: 1 ESC[0m); the repeat's record read
    such a line as '?' (issue #68 item 4's first sound_runs repeat)."""
    fake = tmp_path / "bin"
    fake.mkdir()
    (fake / "rostest").write_text(
        "#!/bin/bash\n"
        f'echo "Traceback: {REPO}/tests/x_check.py, log in $HOME/.ros/log/x.log"\n'
        'printf "SUMMARY\\n\\033[1;31m * RESULT: FAIL\\033[0m\\n * TESTS: 8\\n * ERRORS: 0\\n'
        '\\033[1;31m * FAILURES: 1\\033[0m\\n"\nexit 1\n'
    )
    (fake / "rostest").chmod(0o755)
    out = tmp_path / "record.txt"
    script = os.path.join(REPO, "scripts", "repro", "rostest_repeat.sh")
    env = dict(os.environ, ASG_ROSTEST=str(fake / "rostest"))
    r = subprocess.run(["bash", script, "2", str(out), "a note", "x.test"], env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-800:]
    rows = [ln.split() for ln in out.read_text().splitlines() if not ln.startswith("#")]
    assert [row[:6] for row in rows] == [["x.test", str(k), "FAIL", "8", "1", "0"] for k in (1, 2)]
    kept = (tmp_path / "record-x.test-1.log").read_text()  # a failed run's log is kept beside the record,
    assert "Traceback: $REPO/tests/x_check.py, log in $ROS_HOME/log/x.log" in kept  # with no machine's paths
    assert "x.test: 0 of 2 passed" in r.stdout


def parallel():
    sys.path.insert(0, os.path.join(REPO, "scripts", "ci"))
    import run_parallel

    return run_parallel


def test_the_lanes_take_the_longest_job_first_and_run_side_by_side(tmp_path):
    rp = parallel()
    marks = tmp_path / "marks"

    def job(name, seconds, estimate):
        xml = tmp_path / f"{name}.xml"
        code = (
            f"import time; open({str(marks)!r}, 'a').write('start {name}\\n'); time.sleep({seconds}); "
            f"open({str(xml)!r}, 'w').write('<testsuite/>')"
        )
        return rp.Job(name, [sys.executable, "-c", code], str(tmp_path), str(xml), estimate)

    jobs = [job("short", 0.1, 1.0), job("long", 1.0, 9.0), job("mid", 0.5, 5.0)]
    done = rp.schedule(jobs, 2, str(tmp_path), timeout=60)
    starts = [ln.split()[1] for ln in marks.read_text().splitlines()]
    assert set(starts[:2]) == {"long", "mid"} and starts[2] == "short"  # longest estimates first
    assert sorted(j.name for j in done) == ["long", "mid", "short"] and all(j.rc == 0 for j in done)
    # side by side: the two lanes took about the long job's time, not the sum of all three
    assert max(j.seconds for j in done) < sum(j.seconds for j in done)


def test_a_job_that_leaves_no_result_is_counted_as_a_failure(tmp_path):
    rp = parallel()
    crash = rp.Job(
        "crash", [sys.executable, "-c", "raise SystemExit(3)"], str(tmp_path), str(tmp_path / "r" / "crash.xml"), 1
    )
    hang = rp.Job("hang", ["bash", "-c", "sleep 60 & sleep 60"], str(tmp_path), str(tmp_path / "r" / "hang.xml"), 1)
    rp.schedule([crash, hang], 2, str(tmp_path), timeout=1.5)
    assert crash.rc == 3 and hang.rc < 0 and hang.seconds < 30  # the hung job and its child were killed
    res = summarize(tmp_path / "r")
    assert res.returncode == 1
    assert "exited 3 without writing" in res.stdout and "killed after 2 s" in res.stdout
    assert res.stdout.splitlines()[-1] == "tests: 0 passed, 2 failed, 0 skipped"


def test_tests_folder_files_estimated_long_run_alone_and_name_their_results_as_one_folder(tmp_path):
    rp = parallel()
    repo, ws = tmp_path / "repo", tmp_path / "ws"
    (repo / "tests").mkdir(parents=True)
    (ws / "src" / "pkg" / "test").mkdir(parents=True)
    (ws / "src" / "pkg" / "test" / "test_a.py").write_text("def test_a():\n    pass\n")
    for stem in ("test_big", "test_small", "test_new"):
        (repo / "tests" / f"{stem}.py").write_text(f"def {stem}_case():\n    pass\n\ndef test_it():\n    pass\n")
    est = {"tests: tests.test_big": 30.0, "tests: tests.test_small": 2.0, "pkg: test.test_a": 4.0}
    jobs = {j.name: j for j in rp.pytest_jobs(str(ws), str(repo), str(tmp_path / "res"), est)}
    assert sorted(jobs) == ["pytest/pkg", "pytest/tests", "pytest/tests/test_big"]
    assert (jobs["pytest/tests/test_big"].estimate, jobs["pytest/tests"].estimate, jobs["pytest/pkg"].estimate) == (
        30.0,
        2.0,
        4.0,
    )
    assert jobs["pytest/tests"].cmd[-2:] == [str(repo / "tests" / "test_new.py"), str(repo / "tests" / "test_small.py")]
    # a part's results count under its folder's name, as when the folder ran whole
    part = tmp_path / "res" / "pytest" / "tests"
    part.mkdir(parents=True)
    (part / "test_big.xml").write_text(
        '<testsuite><testcase classname="tests.test_big" name="t" time="3"/></testsuite>'
    )
    summarize(tmp_path / "res")
    assert json.loads((tmp_path / "res" / "times.json").read_text())["files"] == {"tests: tests.test_big": 3.0}


def test_a_failed_jobs_console_lines_are_its_failures_not_its_expected_errors(tmp_path, capsys):
    rp = parallel()
    xml = tmp_path / "f.xml"
    code = (
        "print('[ERROR] [1.0]: scene worker: goal refused on purpose'); "
        "print('FAILED tests/test_x.py::test_y - AssertionError: 1 != 2'); "
        f"open({str(xml)!r}, 'w').write('<testsuite/>'); raise SystemExit(1)"
    )
    rp.schedule([rp.Job("f", [sys.executable, "-c", code], str(tmp_path), str(xml), 1)], 1, str(tmp_path), 60)
    out = capsys.readouterr().out
    assert "FAILED (exit 1;" in out and "    FAILED tests/test_x.py::test_y - AssertionError: 1 != 2" in out
    assert "goal refused on purpose" not in out
    assert console_filter.shown("ERROR tests/test_x.py::test_z - RuntimeError")


def test_ctest_knows_every_pytest_file_and_folder_and_run_parallel_leaves_them_to_pytest(tmp_path):
    # issue #80 item 7: scripts/ci/pytest.cmake registers each package's pytest folder and each
    # tests/ file with CTest (ctest -j and catkin_make run_tests see the whole suite); run_parallel,
    # which runs them its own way, takes from CTest only the gtest binaries and rostests
    import glob

    build = os.path.join(REPO, "catkin_ws", "build")
    out = subprocess.run(["ctest", "--show-only=json-v1"], cwd=build, capture_output=True, text=True, check=True)
    names = {t["name"] for t in json.loads(out.stdout)["tests"]}
    want = {
        f"_ctest_asg_tests_pytest_{os.path.basename(f)[:-3]}"
        for f in glob.glob(os.path.join(REPO, "tests", "test_*.py"))
    }
    want |= {
        f"_ctest_{os.path.basename(os.path.dirname(t))}_pytest_test"
        for t in glob.glob(os.path.join(REPO, "catkin_ws", "src", "*", "test"))
        if glob.glob(os.path.join(t, "test_*.py"))
    }
    assert want <= names, sorted(want - names)
    jobs = parallel().ctest_jobs(os.path.join(REPO, "catkin_ws"), str(tmp_path), {})
    assert jobs and not [j.name for j in jobs if "pytest" in " ".join(map(str, j.cmd))]
    assert len(jobs) == len([n for n in names if "_pytest_" not in n])


def test_a_registered_pytest_runs_as_ctest_runs_it_and_writes_its_result(tmp_path):
    """The command CTest holds for a registered pytest folder runs through catkin's run_tests.py
    (which takes each command as one string: registered as separate words, every pytest folder
    and file failed at once, with no result file) and writes its JUnit file; scripts/test.sh's
    ctest branch fails when ctest does."""
    build = os.path.join(REPO, "catkin_ws", "build")
    out = subprocess.run(["ctest", "--show-only=json-v1"], cwd=build, capture_output=True, text=True, check=True)
    test = next(t for t in json.loads(out.stdout)["tests"] if t["name"] == "_ctest_asg_lockstep_pytest_test")
    xml = test["command"][3]
    cmd = [str(tmp_path / "r.xml") if c == xml else c.replace(xml, str(tmp_path / "r.xml")) for c in test["command"]]
    cwd = next(p["value"] for p in test["properties"] if p["name"] == "WORKING_DIRECTORY")
    p = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-2000:]
    assert 'failures="0"' in (tmp_path / "r.xml").read_text() and "testcase" in (tmp_path / "r.xml").read_text()
    script = open(os.path.join(REPO, "scripts", "test.sh"), encoding="utf-8").read()
    assert "|| ctest_rc=$?" in script and 'exit "$ctest_rc"' in script
