"""Writing the figures a study computes (no ROS)."""

import json


def write_json(path: str, data) -> None:
    """`data` as indented JSON with sorted keys and a final newline, the form the committed
    results take (results/*/*.json)."""
    with open(path, "w", encoding="utf-8") as f:
        json.dump(data, f, indent=1, sort_keys=True)
        f.write("\n")
