"""Where things are: the repository's root, found from this file (the devel space's package
resolves to the source tree). The one place that walks up the folders."""

import os

#: the repository's root (the folder holding catkin_ws/, experiments/, results/, docs/)
REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), *[".."] * 5))


def repo_relative(path: str) -> str:
    """`path` relative to the repository this code runs from, or "" when it lies outside it (or
    when this code runs from an install space, which is no repository)."""
    if not os.path.isdir(os.path.join(REPO, "catkin_ws", "src")):
        return ""
    rel = os.path.relpath(os.path.realpath(path), REPO) if path else ".."
    return "" if rel.startswith("..") else rel


def in_repo(path: str) -> str:
    """A path as recorded (repository-relative, as committed records hold them, or absolute, as
    older records and files outside the repository do) made absolute: a relative one is the
    repository's."""
    return path if not path or os.path.isabs(path) else os.path.join(REPO, path)
