"""A node parameter declared once, as data (no rclpy): name, type (from the default), range or
choices, whether it is set at start only, the thesis equation it stands for, and its doc.

The nodes declare ROS parameters from these (``node_base.HomeoNode.declare_specs``: the
descriptor carries the range and the doc), the launchers and commands add their flags from
them (``add_flag``), and docs print them (``markdown_table``). A value from anywhere (a
parameter set over the network, a command line, a YAML file) goes through ``check``: it is
accepted as the declared type, or refused with a one-line reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

SCALARS = (bool, int, float, str)


@dataclass(frozen=True)
class ParamSpec:
    name: str
    default: object  # bool | int | float | str | tuple of str: its type is the parameter's
    doc: str
    lo: float | None = None  # inclusive range of a number
    hi: float | None = None
    choices: tuple = ()  # the values a string may take
    fixed: bool = False  # set at start only (a change is refused; the same value is accepted)
    eq: str = ""  # the thesis equation or table it stands for, e.g. "3.27"

    def __post_init__(self):
        t = type(self.default)
        if t not in SCALARS and not (t is tuple and all(type(x) is str for x in self.default)):
            raise TypeError(f"parameter {self.name}: unsupported default {self.default!r}")
        if self.choices and t is not str:
            raise TypeError(f"parameter {self.name}: choices need a string default")
        self.check(self.default)  # a declaration that refuses its own default is a bug

    @property
    def kind(self) -> type:
        return type(self.default)

    @property
    def flag(self) -> str:
        return "--" + self.name.replace("_", "-")

    def check(self, value):
        """``value`` as this parameter's type, or ValueError with a one-line reason (an int is
        taken for a float; nothing else is converted)."""
        t, given = self.kind, value
        if t is float and type(value) is int:
            value = float(value)
        if t is tuple and isinstance(value, list):
            value = tuple(value)
        who = f"{self.name} " if self.name else ""  # a nameless spec: a value argparse or a caller names
        if type(value) is not t or (t is tuple and not all(type(x) is str for x in value)):
            raise ValueError(f"{who}must be {_type_name(t)}, not {_shown(value)}")
        if t in (int, float):
            if t is float and not math.isfinite(value):
                raise ValueError(f"{who}must be a finite number, not {value!r}")
            if (self.lo is not None and value < self.lo) or (self.hi is not None and value > self.hi):
                raise ValueError(f"{who}= {given!r} is outside {self.range_text()}" if who else
                                 f"{given!r} is outside {self.range_text()}")
        if self.choices and value not in self.choices:
            raise ValueError(f"{who}must be one of {', '.join(self.choices)}, not {_shown(value)}")
        return value

    def range_text(self) -> str:
        if self.choices:
            return " | ".join(self.choices)
        if self.lo is None and self.hi is None:
            return ""
        shown = (lambda x: str(int(x))) if self.kind is int else (lambda x: f"{x:g}")
        lo = "-inf" if self.lo is None else shown(self.lo)
        hi = "inf" if self.hi is None else shown(self.hi)
        return f"[{lo}, {hi}]"

    def parse(self, text: str):
        """A command-line value, checked (ValueError: one line)."""
        t = self.kind
        if t is bool:
            low = text.strip().lower()
            if low not in ("true", "false", "1", "0", "yes", "no"):
                raise ValueError(f"{self.name + ' ' if self.name else ''}must be true or false, not {_shown(text)}")
            return self.check(low in ("true", "1", "yes"))
        if t in (int, float):
            try:
                v = t(text) if len(text) <= 40 else None
            except ValueError:
                v = None
            if v is None:
                raise ValueError(f"{self.name + ' ' if self.name else ''}must be {_type_name(t)}, not {_shown(text)}")
            return self.check(v)
        if t is tuple:
            return self.check(tuple(x for x in text.split(",") if x))
        return self.check(text)


def _type_name(t: type) -> str:
    return {bool: "true or false", int: "an integer", float: "a number", str: "a string",
            tuple: "a list of strings"}[t]


def _shown(value) -> str:
    from .text import one_line

    text = repr(value)
    return one_line(text if len(text) <= 40 else text[:37] + "...")


def arg_type(spec: ParamSpec):
    """An argparse ``type`` that checks a command-line value by ``spec`` (one line when it refuses)."""
    import argparse

    def conv(text: str):
        try:
            return spec.parse(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
    return conv


def number(lo: float | None, hi: float | None = None, kind: type = int) -> ParamSpec:
    """A nameless number in [lo, hi] (a command-line count, a checkpoint's field): ``.check`` or ``arg_type``."""
    return ParamSpec("", kind(lo if lo is not None else 0), "", lo, hi)


def checked(v, what: str, lo: float | None = None, hi: float | None = None, kind: type = float,
            error: type[Exception] = ValueError):
    """``v`` as a number of ``kind`` in [lo, hi], checked by its declaration (``number``); else ``error``: one
    line that names ``what`` (a file's field, a checkpoint's)."""
    try:
        return ParamSpec(what, kind(lo if lo is not None else 0), "", lo, hi).check(v)
    except ValueError as exc:
        raise error(str(exc)) from None


def add_flag(parser, spec: ParamSpec, default=None, help_extra: str = "") -> None:
    """An argparse option for ``spec`` (``--dod``); its value is checked by ``spec.parse``.
    ``default``: the option's default (None: not given, the node's or scenario's default applies)."""
    conv = arg_type(spec)

    eq = f" (Eq {spec.eq})" if spec.eq and spec.eq[0].isdigit() else (f" ({spec.eq})" if spec.eq else "")
    rng = spec.range_text()
    more = {"nargs": "?", "const": True, "metavar": "true|false"} if spec.kind is bool else {"metavar": spec.name.upper()}
    parser.add_argument(spec.flag, dest=spec.name, type=conv, default=default,  # a bare bool flag says true
                        help=f"{spec.doc}{eq}" + (f"; {rng}" if rng else "") + help_extra, **more)


def markdown_table(specs, defaults: dict | None = None) -> str:
    """The parameters as a markdown table (docs); ``defaults`` overrides the shown defaults."""
    rows = ["| parameter | type | range | default | set | Eq | meaning |", "|---|---|---|---|---|---|---|"]
    for s in specs:
        d = (defaults or {}).get(s.name, s.default)
        shown = ", ".join(d) if isinstance(d, tuple) else repr(d) if isinstance(d, str) else str(d).lower() \
            if isinstance(d, bool) else f"{d:g}" if isinstance(d, float) else str(d)
        rows.append(f"| `{s.name}` | {s.kind.__name__ if s.kind is not tuple else 'string list'} | "
                    f"{s.range_text().replace('|', chr(92) + '|') or '-'} | {shown or chr(39) * 2} | {'at start' if s.fixed else 'live'} | "
                    f"{s.eq or '-'} | {s.doc} |")
    return "\n".join(rows)
