"""Where files named by parameters may live (no rclpy).

Anyone on the ROS domain can set a node's parameters, so a path parameter set while the node runs
is a way to make it write or read any file its user can. Such a path (a Q-table, an intention
model, a trace) therefore resolves inside one data directory, set when the node starts
(``data_dir``; the launcher passes its ``--data-dir``, default ``out/``): a relative path is taken
under it, and anything that resolves outside it (``..``, an absolute path elsewhere, ``~``, a
symbolic link out) is refused with a reason. The values a node starts with come from whoever
started it (a command line, a launch file, a parameter file), who can write those files anyway:
they may name any place (``trusted``); a relative one is still taken under the data directory.
"""

from __future__ import annotations

import os

from .schemas import one_line

DEFAULT = "out"
ENV = "HOMEO_DATA_DIR"


def default_dir(env=os.environ) -> str:
    return os.path.abspath(env.get(ENV) or DEFAULT)


class OutsideDataDir(ValueError):
    """A path that does not resolve inside the data directory (``str()`` is the reason)."""


def resolve(data_dir: str, path: str, what: str = "path", trusted: bool = False) -> str:
    """``path`` as an absolute path inside ``data_dir``, or anywhere when ``trusted`` (a value the
    node started with); '' stays '': not set."""
    if not path:
        return ""
    if not isinstance(path, str) or "\0" in path:
        raise OutsideDataDir(f"{what} is not a file name")
    base = os.path.realpath(data_dir)
    full = os.path.realpath(os.path.join(base, os.path.expanduser(path)))
    if trusted:
        return full
    if full == base or os.path.commonpath([base, full]) != base:
        raise OutsideDataDir(f"{what} {one_line(path)} is outside the data directory {one_line(base)}")
    return full
