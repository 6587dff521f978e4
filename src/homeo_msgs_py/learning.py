"""The decision's learning parameters (Algorithm 1), declared once.

Each is a ``params.ParamSpec``: name, type (from the default), range, the thesis's default, the
equation it stands for and its doc. Everything else comes from ``LEARNING``:

- the decision node's ROS parameters, their descriptors and live changes (``node_base.declare_specs``);
- the checks of ``DecisionCore.set_params`` and of a scenario's ``learning`` block;
- the decision checkpoint's ``params`` (written and read by iterating ``LEARNING`` and ``SEED``);
- the ``params`` of ``homeo/action`` (``schemas.py``), and so its JSON Schema (``json_schemas.py``);
- the command-line flags of the commands that take them (``add_learning_flags``, ``learning_values``);
- docs/GRAPH.md's table (``python -m homeo_msgs_py.learning`` prints it; a test compares).

The default here is the thesis's; a scenario's ``learning`` block overrides it at run time (the
thesis scenario gives the same values), and a flag or a node parameter overrides that.

``xi`` is bounded by 1e6, not by the node's former 1000: the scenario file, the message contract and
``homeo-sim`` already took up to 1e6, so no scenario that loads can give the node a default it refuses.
"""

from __future__ import annotations

from typing import Iterable, Mapping

from .graph import SEED_MAX
from .params import ParamSpec, add_flag, markdown_table

DOD = ParamSpec("dod", 0.25, "Degree of Dedication: the serving drive's share of the drive weights "
                "(a scenario that leaves it out: 1 / number of drives)", lo=0.0, hi=1.0, eq="3.27-3.28")
XI = ParamSpec("xi", 1.0, "motivation factor: extra weight of the dominant motivation's drive in the reward",
               lo=0.0, hi=1e6, eq="3.20")
GAMMA = ParamSpec("gamma", 0.5, "discount factor of the Object-Q update", lo=0.0, hi=1.0, eq="3.14")
FEEDBACK = ParamSpec("feedback", True, "learn from the user's feedback (false: the reward leaves it out, "
                     "and no pseudo update)", eq="3.22")
PSEUDO_UPDATE = ParamSpec("pseudo_update", True, "learn from the user's proposals (pseudo update)", eq="3.23")

# in the order of homeo/action's ``params`` (the order of its JSON object)
LEARNING: tuple[ParamSpec, ...] = (DOD, XI, GAMMA, FEEDBACK, PSEUDO_UPDATE)
BY_NAME: dict[str, ParamSpec] = {s.name: s for s in LEARNING}

# not a learning parameter, but the decision's checkpoint keeps it beside them and its node declares it
SEED = ParamSpec("seed", 0, "seed of the decision's random stream (setting it reseeds)", lo=0, hi=SEED_MAX)


def check_learning(values: Mapping, specs: Iterable[ParamSpec] = LEARNING) -> dict:
    """``values`` (any subset of ``specs``, by name) checked and typed, or ValueError with a one-line
    reason: an unknown name, a value of the wrong type, one out of range."""
    by_name = {s.name: s for s in specs}
    out = {}
    for name, value in values.items():
        spec = by_name.get(name)
        if spec is None:
            from .text import one_line

            raise ValueError(f"unknown learning parameter {one_line(repr(name))[:40]}; known: {', '.join(by_name)}")
        out[name] = spec.check(value)
    return out


def add_learning_flags(parser, specs: Iterable[ParamSpec] = LEARNING, help_extra: str = "") -> None:
    """One flag per parameter of ``specs`` (``--dod X``, ``--pseudo-update false``), each checked by its
    declaration (a bad value: argparse's one-line error). Not given: None, the scenario's value applies."""
    for spec in specs:
        add_flag(parser, spec, help_extra=help_extra)


def add_no_pseudo_flag(parser) -> None:
    """``--no-pseudo``, the older spelling of ``--pseudo-update false`` (its value lands in the same place)."""
    parser.add_argument("--no-pseudo", dest=PSEUDO_UPDATE.name, action="store_const", const=False,
                        help=f"switch off pseudo updates (Eq {PSEUDO_UPDATE.eq}): {PSEUDO_UPDATE.flag} false")


def learning_values(args, specs: Iterable[ParamSpec] = LEARNING) -> dict:
    """The parameters of ``specs`` given on the command line (``args`` from a parser with
    ``add_learning_flags``), by name: what a launcher passes to the decision node as its parameters."""
    return {s.name: getattr(args, s.name) for s in specs if getattr(args, s.name, None) is not None}


def table() -> str:
    """The parameters as docs/GRAPH.md shows them."""
    return markdown_table(LEARNING)


if __name__ == "__main__":
    print(table())
