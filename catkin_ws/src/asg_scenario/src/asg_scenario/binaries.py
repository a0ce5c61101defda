"""Finding another package's executable as ROS does (issue #80; no rospy): catkin's workspace
search over CMAKE_PREFIX_PATH (`catkin.find_in_workspaces`, what `catkin_find` and roslaunch's
`<node pkg=... type=...>` resolve through), so that a tool runs from a devel space, an install
space or a user's workspace alike. A package that runs another's executable declares it as an
`exec_depend` of its package.xml; tests/test_architecture.py reads every `find_binary` call and
checks the declaration."""

import os


class BinaryNotFound(FileNotFoundError):
    pass


def find_binary(package: str, name: str) -> str:
    """The path of `package`'s executable `name` (its libexec folder: devel/lib/PACKAGE or
    install/lib/PACKAGE of the first workspace on CMAKE_PREFIX_PATH that has it); BinaryNotFound
    naming both and what to do."""
    try:
        from catkin.find_in_workspaces import find_in_workspaces

        found = find_in_workspaces(search_dirs=["libexec"], project=package, path=name, first_match_only=True)
    except ImportError:  # catkin's Python package absent: the workspaces' lib folders by hand
        found = [
            os.path.join(prefix, "lib", package, name)
            for prefix in os.environ.get("CMAKE_PREFIX_PATH", "").split(os.pathsep)
            if prefix and os.path.isfile(os.path.join(prefix, "lib", package, name))
        ][:1]
    found = [p for p in found if os.access(p, os.X_OK)]
    if not found:
        raise BinaryNotFound(
            f"no executable {name!r} of package {package!r} in the workspaces on CMAKE_PREFIX_PATH: "
            "build the workspace (bash scripts/setup.sh) and source its setup.bash"
        )
    return found[0]
