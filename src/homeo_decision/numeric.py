"""Float sums that give the same bits on every Python this project runs on (3.11 and 3.12)."""

from __future__ import annotations

from typing import Iterable


def left_sum(xs: Iterable[float]) -> float:
    """The plain left-to-right sum, as Python 3.11's ``sum`` adds floats. Python 3.12's ``sum``
    compensates the rounding (Neumaier), which moves a result in its last bit: a seed's run must
    give the same numbers on both (tests/golden)."""
    total = 0.0
    for x in xs:
        total += x
    return total
