"""Writing the figures a study computes (no ROS)."""

import json


def write_json(path: str, data) -> None:
    """`data` as indented JSON with sorted keys and a final newline, the form the committed
    results take (results/*/*.json)."""
    with open(path, "w", encoding="utf-8") as f:
        json.dump(data, f, indent=1, sort_keys=True)
        f.write("\n")


def report(res, json_path: str, figure, figure_path: str, markdown, as_markdown: bool) -> int:
    """A study CLI's last steps: `res` to JSON_PATH and its figure (figure(res, path)) to
    FIGURE_PATH where given, then markdown(res) or `res` itself on stdout; exit status 0."""
    if json_path:
        write_json(json_path, res)
    if figure_path:
        figure(res, figure_path)
    print(markdown(res) if as_markdown else res)
    return 0
