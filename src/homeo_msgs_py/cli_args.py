"""Command-line helpers every homeo command shares: one-line errors (exit 2) and checked numbers."""

from __future__ import annotations

import argparse
import json


class UserError(Exception):
    """A mistake of the user's: reported in one line, exit code 2."""


class Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, no usage dump; argparse quotes what the user typed raw
        from .schemas import one_line

        raise UserError(one_line(message))


def int_at_least(lo: int, hi: int | None = None):
    """An integer >= lo (and <= hi), checked by its declaration (``params.ParamSpec``)."""
    from .params import arg_type, number

    return arg_type(number(lo, hi))


def float_in(lo: float, hi: float):
    from .params import arg_type, number

    return arg_type(number(lo, hi, float))


def user_path(s: str) -> str:
    """A file or folder the user named: ``~`` is their home, as the shell would have it (``--x=~/f``
    reaches a program unexpanded)."""
    import os

    return os.path.expanduser(s)


def key_value(s: str) -> tuple[str, str]:
    """``KEY=VALUE``, the value as text (its declaration parses it)."""
    if "=" not in s:
        raise argparse.ArgumentTypeError(f"{s!r} is not KEY=VALUE")
    k, v = s.split("=", 1)
    return k.strip(), v


def setting(s: str) -> tuple[str, object]:
    """``KEY=VALUE``, the value as JSON where it is JSON (a scenario's open choice), else as text."""
    k, v = key_value(s)
    try:
        val = json.loads(v)
    except json.JSONDecodeError:
        val = v
    return k.strip(), val


def run_command(prog: str, command, user_errors: tuple = (), failures: tuple = (), os_errors: bool = False) -> int:
    """Run ``command()`` as a command-line program: a user's mistake (``UserError`` or one of
    ``user_errors``) is one line and exit 2, one of ``failures`` (the program failed, e.g. a node
    died) one line and exit 1; a closed pipe ends quietly (141), Ctrl-C with 130. With
    ``os_errors`` an OSError is a user's mistake too (a file they named)."""
    import os
    import sys

    try:
        return command()
    except (UserError, *user_errors) as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    except failures as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 1
    except BrokenPipeError:  # e.g. piped into head: stop quietly, as Unix tools do
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except OSError as exc:
        if not os_errors:
            raise
        print(f"{prog}: error: {exc.filename or ''}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130


def leave(code: int):
    """End the process with ``code`` at once, its output flushed: for a program that ran a libqi session, whose
    threads and static objects can abort (SIGABRT) the interpreter's teardown and turn a clean exit into -6."""
    import os
    import sys

    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def die_with_parent() -> None:
    """Nodes (and companions) started by the launcher end if it is killed outright (no orphans)."""
    import os
    import signal

    ppid = os.environ.get("HOMEO_PARENT_PID")
    if not ppid:
        return
    try:
        import ctypes

        libc = ctypes.CDLL("libc.so.6", use_errno=True)
        # PR_SET_PDEATHSIG: the launcher stops its nodes gracefully; this fires only when it died
        # without doing so, and then nothing must be left running
        libc.prctl(1, signal.SIGKILL)
        if os.getppid() != int(ppid):  # the parent died before prctl
            os._exit(1)
    except (OSError, AttributeError, ValueError):
        pass
