"""Where files named by parameters may live (no rclpy).

Anyone on the ROS domain can set a node's parameters, so a path parameter is a way to make a
node write or read any file its user can. Every file a node names by parameter (Q-table,
intention model, trace, checkpoints) therefore resolves inside one data directory, set when
the node starts (``data_dir``; the launcher passes its ``--data-dir``, default ``out/``): a
relative path is taken under it, and anything that resolves outside it (``..``, an absolute
path elsewhere, a symbolic link out) is refused with a reason.
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


def resolve(data_dir: str, path: str, what: str = "path") -> str:
    """``path`` as an absolute path inside ``data_dir`` ('' stays '': not set)."""
    if not path:
        return ""
    if not isinstance(path, str) or "\0" in path:
        raise OutsideDataDir(f"{what} is not a file name")
    base = os.path.realpath(data_dir)
    full = os.path.realpath(os.path.join(base, os.path.expanduser(path)))
    if full == base or os.path.commonpath([base, full]) != base:
        raise OutsideDataDir(f"{what} {one_line(path)} is outside the data directory {one_line(base)}")
    return full


def options_inside(data_dir: str, named) -> None:
    """Command-line file options ``(option, path)`` (paths as given, from the working directory)
    inside ``data_dir``, where the nodes will accept them; else a one-line ``UserError``."""
    from .cli_args import UserError

    for opt, f in named:
        if f:
            try:
                resolve(data_dir, os.path.abspath(f), opt)
            except OutsideDataDir as exc:
                raise UserError(f"{exc} (give --data-dir, or a path under it)") from None
