"""Conversion between canonical scenario dicts and asg_msgs messages.

Imports only the generated message classes (genpy), never rospy.
"""

from .schema import (
    HILL_FIELDS,
    INSTANCE_FIELDS,
    LANDSCAPE_FIELDS,
    OPERATIONAL_FIELDS,
    TERRAIN_FIELDS,
    TEXTURAL_FIELDS,
)


def _fill(msg, data, fields):
    # A field with a default may be missing: requests stored before it existed (a campaign's
    # rows, the reference runs) mean its default, which is what they ran.
    for f in fields:
        setattr(msg, f.key, data[f.key] if f.key in data or f.default is None else f.default)
    return msg


def _read(msg, fields):
    return {f.key: getattr(msg, f.key) for f in fields}


def to_scene_msg(scenario: dict):
    """asg_msgs/SceneDescription from a validated scenario dict."""
    from asg_msgs.msg import (
        Hill,
        Landscape,
        ObstacleInstance,
        ObstacleLayout,
        OperationalAttributes,
        SceneDescription,
        StructuralAttributes,
        Terrain,
        TexturalAttributes,
    )

    st = scenario["structural"]
    layouts = []
    for layout in st["layouts"]:
        insts = [_fill(ObstacleInstance(), i, INSTANCE_FIELDS) for i in layout["instances"]]
        layouts.append(ObstacleLayout(mesh_name=layout["mesh_name"], instances=insts))
    # A request stored before terrain existed has none: the flat ground it ran on.
    terrain = st.get("terrain", {})
    terrain_msg = _fill(Terrain(), terrain, TERRAIN_FIELDS)
    terrain_msg.hills = [_fill(Hill(), h, HILL_FIELDS) for h in terrain.get("hills", [])]
    return SceneDescription(
        structural=StructuralAttributes(
            landscape=_fill(Landscape(), st["landscape"], LANDSCAPE_FIELDS), layouts=layouts, terrain=terrain_msg
        ),
        textural=_fill(TexturalAttributes(), scenario["textural"], TEXTURAL_FIELDS),
        operational=_fill(OperationalAttributes(), scenario["operational"], OPERATIONAL_FIELDS),
    )


def to_goal_msg(scenario: dict):
    """asg_msgs/RunScenarioGoal from a validated scenario dict."""
    from asg_msgs.msg import RunScenarioGoal

    return RunScenarioGoal(
        scenario_id=scenario["scenario_id"], scene=to_scene_msg(scenario), record_labels=scenario["record_labels"]
    )


def from_scene_msg(scene, scenario_id: int = 1, name: str = "", record_labels: bool = True) -> dict:
    """Scenario dict (not yet validated) from an asg_msgs/SceneDescription."""
    st = scene.structural
    return {
        "format_version": 1,
        "name": name,
        "scenario_id": scenario_id,
        "record_labels": record_labels,
        "structural": {
            "landscape": _read(st.landscape, LANDSCAPE_FIELDS),
            "terrain": dict(_read(st.terrain, TERRAIN_FIELDS), hills=[_read(h, HILL_FIELDS) for h in st.terrain.hills]),
            "layouts": [
                {"mesh_name": l.mesh_name, "instances": [_read(i, INSTANCE_FIELDS) for i in l.instances]}
                for l in st.layouts
            ],
        },
        "textural": _read(scene.textural, TEXTURAL_FIELDS),
        "operational": _read(scene.operational, OPERATIONAL_FIELDS),
    }
