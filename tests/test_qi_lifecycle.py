"""Stand-ins and bridges opened and closed again and again in one process, as the in-process qi
tests do one after another (``tools/qi_stress.py``). With qi 3.1.5, a closed session's leftovers
destroyed by an automatic garbage collection inside a later ``registerService`` killed the process
with a segfault (in 9 stress runs out of 11, docs/PEPPER.md). ``collect_closed_session`` destroys them
when the session closes. The test runs in a subprocess, so a crash fails it, not the test session."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("qi")

pytestmark = [pytest.mark.qi, pytest.mark.slow]

TOOL = Path(__file__).resolve().parents[1] / "tools" / "qi_stress.py"


def test_three_hundred_open_use_close_cycles_in_one_process_survive():
    r = subprocess.run([sys.executable, "-X", "faulthandler", str(TOOL), "300"], capture_output=True, text=True,
                       timeout=900)
    # libqi writes its own warnings to stdout too: the tool's line is the last
    assert r.returncode == 0 and r.stdout.splitlines()[-1:] == ["survived 300 cycles"], r.stderr[-3000:]
