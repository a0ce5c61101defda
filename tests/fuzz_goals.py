"""RunScenario goals from a hostile or broken client (issue #14; run by fuzz_inputs.py goals and,
shortly, by tests/bad_input.test). Needs a running worker (worker.launch, any stack)."""

import math
import os
import random
import time
from collections import Counter

import rospy
from actionlib_msgs.msg import GoalStatus
from asg_msgs.msg import ObstacleInstance, RunScenarioAction, RunScenarioActionResult

from asg_scenario import load_scenario
from asg_scenario.convert import to_goal_msg

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
FLOATS = [
    ("nan", math.nan),
    ("inf", math.inf),
    ("-inf", -math.inf),
    ("huge", 1e300),
    ("negative", -1e6),
    ("zero", 0.0),
    ("tiny", 1e-300),
    ("minus_one", -1.0),
]
UINTS = [("zero", 0), ("max", 2**32 - 1), ("big", 10**6)]
NAMES = {
    0: "PENDING",
    1: "ACTIVE",
    2: "PREEMPTED",
    3: "SUCCEEDED",
    4: "ABORTED",
    5: "REJECTED",
    6: "PREEMPTING",
    7: "RECALLING",
    8: "RECALLED",
    9: "LOST",
}
TERMINAL = {GoalStatus.SUCCEEDED, GoalStatus.ABORTED, GoalStatus.PREEMPTED, GoalStatus.RECALLED, GoalStatus.REJECTED}


def base_goal(scenario_id):
    s = load_scenario(os.path.join(REPO, "scenarios", "exp1.yaml"))
    s["scenario_id"] = scenario_id
    s["operational"]["sim_timeout"] = 2.0  # valid mutants run, briefly
    return to_goal_msg(s)


def float_fields(g):
    sc = g.scene
    out = [
        (sc.structural.landscape, "size"),
        (sc.structural.landscape, "border"),
        (sc.textural, "sun_inclination_deg"),
        (sc.textural, "sun_yaw_deg"),
    ]
    out += [
        (sc.operational, f)
        for f in (
            "start_x",
            "start_y",
            "start_yaw",
            "goal_x",
            "goal_y",
            "goal_radius",
            "safety_radius",
            "speed",
            "sim_timeout",
            "idle_timeout",
            "stuck_timeout",
            "max_roll_deg",
            "max_pitch_deg",
        )
    ]
    for layout in sc.structural.layouts:
        for inst in layout.instances:
            out += [(inst, f) for f in ("x", "y", "yaw", "scale")]
    return out


def mutate(rng, g):
    """(class, goal)."""
    k = rng.random()
    if k < 0.5:
        obj, field = rng.choice(float_fields(g))
        name, v = rng.choice(FLOATS)
        setattr(obj, field, v)
        return f"float:{name}", g, f"{type(obj).__name__}.{field} = {v}"
    if k < 0.6:
        obj, field = rng.choice(
            [
                (g.scene.structural.landscape, "subdivisions"),
                (g.scene.textural, "ground_texture_seed"),
                (g, "top_down_px"),
                (g, "scenario_id"),
            ]
        )
        name, v = rng.choice(UINTS)
        setattr(obj, field, v)
        return f"uint:{field}:{name}", g, f"{field} = {v}"
    if k < 0.7:
        layout = rng.choice(g.scene.structural.layouts)
        layout.mesh_name = rng.choice(["", "x" * 10000, "../../etc/passwd", "juniper\x00", "ünïcode", "JUNIPER"])
        return "mesh_name", g, repr(layout.mesh_name[:40])
    if k < 0.8:
        layout = rng.choice(g.scene.structural.layouts)
        n = rng.choice([0, 513, 5000])
        layout.instances = [
            ObstacleInstance(
                visible=True, cast_shadow=True, x=rng.uniform(0, 100), y=rng.uniform(0, 100), yaw=0.0, scale=1.0
            )
            for _ in range(n)
        ]
        return f"instances:{n}", g, f"{layout.mesh_name}: {n} instances"
    if k < 0.85:
        g.scene.structural.layouts = []
        return "no_layouts", g, ""
    return "valid", g, ""


def rss_kb(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return 0


def fuzz_goals(worker, count, seed, pid_of=None, progress=True):
    """Sends `count` goals (plus, every 25th, a new goal and a cancel mid-run)."""
    rng = random.Random(seed)
    from asg_scenario.ros_node import GoalClient

    c = GoalClient(f"{worker.rstrip('/')}/run_scenario", RunScenarioAction)
    if not c.wait_for_server(rospy.Duration(60)):
        raise RuntimeError(f"no worker at {worker}/run_scenario")
    classes, states, failures = Counter(), Counter(), []
    # What the worker really answered, by goal id: tells a result the server never sent from one
    # that the client library lost.
    answered = {}
    sub = rospy.Subscriber(
        f"{worker.rstrip('/')}/run_scenario/result",
        RunScenarioActionResult,
        lambda m: answered.__setitem__(m.status.goal_id.id, (m.status.status, m.result.error)),
        queue_size=100,
    )
    rospy.sleep(0.5)
    lost = []
    pid0 = pid_of() if pid_of else None
    rss = []
    t0 = time.time()
    for n in range(count):
        cls, g, detail = mutate(rng, base_goal(1000 + n % 7))  # scenario ids repeat on purpose
        classes[cls] += 1
        c.send_goal(g)
        if n % 25 == 12:  # a new goal while one runs, then a cancel
            rospy.sleep(0.05)
            c.send_goal(base_goal(5000 + n))
            classes["new_goal_mid_run"] += 1
            rospy.sleep(rng.uniform(0.0, 0.3))
            c.cancel_goal()
            classes["cancel_mid_run"] += 1
        if not c.wait_for_result(rospy.Duration(20)):
            gid = c.gh.comm_state_machine.action_goal.goal_id.id if c.gh else ""
            if gid in answered:  # the worker answered; the client did not deliver it
                lost.append(
                    {
                        "class": cls,
                        "detail": detail,
                        "answer": NAMES.get(answered[gid][0]),
                        "error": answered[gid][1][:200],
                    }
                )
                states["answered, lost by the client"] += 1
                # a failure too (issue #79): the client of issue #68 delivers every answer, and a
                # lost one must fail the run rather than pass as answered
                failures.append(
                    {"class": cls, "detail": detail, "n": n, "why": "answered by the worker, lost by the client"}
                )
            else:
                failures.append({"class": cls, "detail": detail, "n": n, "why": "no result within 20 s"})
            c.cancel_goal()
            continue
        st, r = c.get_state(), c.get_result()
        states[NAMES.get(st, str(st))] += 1
        if st not in TERMINAL:
            failures.append({"class": cls, "why": f"state {st}"})
        elif st == GoalStatus.ABORTED and (r is None or not r.error.strip()):
            failures.append({"class": cls, "why": "aborted without an error text"})
        if pid_of and n % 50 == 49:
            pid = pid_of()
            if pid != pid0:
                failures.append({"class": cls, "why": f"worker restarted (pid {pid0} -> {pid})"})
                pid0 = pid
            rss.append(rss_kb(pid))
        if progress and n % 200 == 199:
            print(f"  {n + 1}/{count} goals, {len(failures)} failure(s), {time.time() - t0:.0f} s")
    sub.unregister()
    growth = (rss[-1] - rss[len(rss) // 4]) if len(rss) >= 4 else 0
    return {
        "mode": "goals",
        "inputs": count,
        "seed": seed,
        "seconds": round(time.time() - t0, 1),
        "classes": dict(sorted(classes.items())),
        "outcomes": dict(sorted(states.items())),
        "rss_kb": rss,
        "rss_growth_kb_after_warmup": growth,
        "lost_by_client": lost[:50],
        "lost_count": len(lost),
        "failures": failures[:50],
        "failure_count": len(failures),
    }
