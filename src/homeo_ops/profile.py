"""Where a tick's time goes in each node: py-spy samples the running node processes from outside.

``py-spy record --idle --threads --nonblocking --format raw`` attached to every node writes one
line per distinct stack with its sample count. Each sample of a node's main thread is put in the
budget's category of its innermost frame that names one (``CATEGORIES``: decode, the HMAC check,
the join, the core step, encode, sign, publish, ...); a sample whose innermost frame is the
executor's wait is ``waiting`` (the node idle, for the other nodes or DDS). With ``--idle`` every
sample counts, so a category's share of a thread's samples is its share of the wall clock, and
times the run's milliseconds a tick its milliseconds a tick. Samples of other threads (the
checkpoint writer) are off the tick's path and reported apart, without their idle waits.

py-spy is a tool dependency, not the runtime's (``tools/requirements-profile.lock``; ``make
profile-setup``). ``--nonblocking`` reads the processes without pausing them: the sampled graph
runs at its own pace (a sample may rarely be torn, and is then counted as py-spy's error).
"""

from __future__ import annotations

import functools
import inspect
import os
import shutil
import signal
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

INSTALL = "make profile-setup (or: pip install -r tools/requirements-profile.lock)"
RATE_HZ = 200

WAITING, OTHER, GLUE = "waiting", "other", "node glue"
# (category, substrings of a py-spy frame "function (file:line)"); the innermost frame naming one wins
CATEGORIES = (
    ("decode", ("parse_json (homeo_msgs_py/schemas", "validate (homeo_msgs_py/schemas",
                "decode (homeo_msgs_py/schemas")),
    ("HMAC check", ("Signer.verify (",)),
    ("join", ("TickJoin.put (", "JoinedStage.put (")),
    ("core step", ("Host._tick (", "LockstepDriver._submit (", "LockstepDriver._step (", "LockstepDriver._finish (")),
    ("encode", ("encode (homeo_msgs_py/schemas",)),
    ("sign", ("Signer.sign (",)),
    ("publish", ("Publisher.publish (rclpy", "GatedPublisher.", "HomeoNode.spooled (")),
    ("checkpoint", ("Checkpointer.", "SlotWriter.", "write_atomic (", "BackgroundWriter.")),
    ("diagnostics", ("publish_diagnostics (",)),
    ("run status", ("_publish_status (",)),
    ("poll timer", ("WorldNode._poll (",)),
    ("executor", ("rclpy/executors.py", "rclpy/task.py", "rclpy/callback_groups.py", "rclpy/timer.py",
                  "rclpy/context.py", "rclpy/subscription.py", "rclpy/service.py", "rclpy/client.py",
                  "rclpy/guard_condition.py", "rclpy/waitable.py", "rclpy/__init__.py", "contextlib.py")),
)
ORDER = tuple(c for c, _ in CATEGORIES[:-1]) + (GLUE, OTHER, "executor", WAITING)
# the project's own code that nodes run: its packages of layers 1-4, whichever worlds are installed
HOMEO_CODE = tuple(f"({p.name}/" for p in Path(__file__).resolve().parents[1].iterdir()
                   if (p / "__init__.py").is_file() and p.name not in ("homeo_launch", "homeo_record", "homeo_ops",
                                                                       "homeo_topic"))
IDLE_LEAVES = ("threading.py", "queue.py")  # a helper thread's waits: not work


@functools.lru_cache(maxsize=1)
def wait_frames() -> tuple[str, ...]:
    """The frames a node's main thread waits in: rclpy's executor at its ``wait_set.wait`` line
    (whichever rclpy this is), and the C++ executor's spin call, under which nothing else shows."""
    from rclpy.executors import Executor

    lines, first = inspect.getsourcelines(Executor._wait_for_ready_callbacks)
    at = next(first + i for i, text in enumerate(lines) if "wait_set.wait(" in text)
    return (f"Executor._wait_for_ready_callbacks (rclpy/executors.py:{at})", "spin_forever (homeo_msgs_py/")


def category(frames: list[str]) -> str:
    """The budget category of one sample's stack, outermost frame first."""
    leaf = frames[-1] if frames else ""
    if any(leaf.startswith(w) for w in wait_frames()):
        return WAITING
    homeo = False
    for f in reversed(frames):
        for name, pats in CATEGORIES:
            if any(p in f for p in pats):
                return GLUE if name == "executor" and homeo else name
        homeo = homeo or any(p in f for p in HOMEO_CODE)
    return GLUE if homeo else OTHER


def parse_raw(text: str) -> dict[str, Counter]:
    """py-spy's raw output (``--threads``): ``thread (TID): NAME;frame;...;frame COUNT`` per line ->
    ``{"main": Counter(category -> samples), "helpers": Counter(...)}``; helper threads' idle waits
    are left out (they are not work)."""
    main, helpers = Counter(), Counter()
    for line in text.splitlines():
        stack, _, count = line.rstrip().rpartition(" ")
        if not stack or not count.isdigit():
            continue
        frames = stack.split(";")
        thread = frames.pop(0) if frames and frames[0].startswith("thread (") else "MainThread"
        if thread.endswith("MainThread"):
            main[category(frames)] += int(count)
        elif frames and not any(w in frames[-1] for w in IDLE_LEAVES):
            helpers[thread.split(": ", 1)[-1] + " thread (off the tick)"] += int(count)
    return {"main": main, "helpers": helpers}


def find_pyspy() -> str | None:
    """py-spy next to this Python (the project's venv) or on the PATH."""
    here = Path(sys.executable).parent / "py-spy"
    return str(here) if here.exists() else shutil.which("py-spy")


def require_pyspy() -> str:
    """py-spy's path, or ``ProfilerMissing`` saying how to install it."""
    exe = find_pyspy()
    if exe is None:
        raise ProfilerMissing(f"py-spy is not installed: {INSTALL}")
    return exe


class Sampler:
    """py-spy attached to processes (name -> pid) from ``start`` to ``stop``."""

    def __init__(self, rate: int = RATE_HZ, exe: str | None = None):
        self.rate = rate
        self.exe = exe or require_pyspy()
        self._tmp = tempfile.TemporaryDirectory(prefix="homeo-profile-")
        self._procs: dict = {}

    def start(self, pids: dict) -> None:
        for name, pid in pids.items():
            out = Path(self._tmp.name) / f"{name}.txt"
            cmd = [self.exe, "record", "--pid", str(pid), "--rate", str(self.rate), "--idle", "--threads",
                   "--nonblocking", "--format", "raw", "--output", str(out)]
            log = open(Path(self._tmp.name) / f"{name}.log", "wb")
            self._procs[name] = (subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT),
                                 out)
            log.close()

    def stop(self, keep: str | None = None) -> dict[str, dict[str, Counter]]:
        """Stop sampling (py-spy writes its file on SIGINT); each process's budget. ``keep``: a folder
        to copy the raw files into (flame graphs: ``flamegraph.pl FILE``)."""
        self._wait_sampling()  # a py-spy stopped before it attached writes nothing
        for p, _ in self._procs.values():
            if p.poll() is None:
                p.send_signal(signal.SIGINT)
        out = {}
        for name, (p, path) in self._procs.items():
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
            try:
                text = path.read_text()
            except OSError:
                log = (Path(self._tmp.name) / f"{name}.log").read_text(errors="replace").strip().splitlines()
                raise ProfilerFailed(f"py-spy wrote no samples of {name}: {log[-1] if log else 'no output'}") from None
            if keep:
                os.makedirs(keep, exist_ok=True)
                shutil.copy(path, Path(keep) / path.name)
            out[name] = parse_raw(text)
        self._procs.clear()
        return out

    def _wait_sampling(self, bound_s: float = 5.0) -> None:
        """Until every py-spy says it samples (its first line), or has exited; bounded."""
        import time

        end = time.monotonic() + bound_s
        for name, (p, _) in self._procs.items():
            log = Path(self._tmp.name) / f"{name}.log"
            while p.poll() is None and time.monotonic() < end and "Sampling" not in log.read_text(errors="replace"):
                time.sleep(0.02)

    def close(self) -> None:
        for p, _ in self._procs.values():
            if p.poll() is None:
                p.kill()
                p.wait()
        self._procs.clear()
        self._tmp.cleanup()


class ProfilerMissing(RuntimeError):
    """py-spy is not installed (one line: how to install it)."""


class ProfilerFailed(RuntimeError):
    """py-spy could not sample a process (one line)."""


def per_tick(budgets: dict[str, dict[str, Counter]], ms_per_tick: float) -> dict[str, dict[str, float]]:
    """Milliseconds a tick of each category, per process: its share of the main thread's samples times
    the run's wall clock a tick; helper threads' work by the same measure (samples at the same rate)."""
    out = {}
    for name, b in budgets.items():
        total = sum(b["main"].values())
        if not total:
            continue
        row = {c: n / total * ms_per_tick for c, n in b["main"].items()}
        row.update({c: n / total * ms_per_tick for c, n in b["helpers"].items()})
        out[name] = row
    return out


def table(ms: dict[str, dict[str, float]], ms_per_tick: float) -> str:
    """The budget as a text table: categories down, processes across, ms a tick (and % of the tick)."""
    names = list(ms)
    helpers = sorted({c for row in ms.values() for c in row if c not in ORDER})
    rows = [c for c in ORDER if any(c in row for row in ms.values())] + helpers
    width = max(len(r) for r in rows + ["category"]) + 1
    head = "ms a tick".ljust(width) + "".join(f"{n:>18}" for n in names)
    lines = [head, "-" * len(head)]
    for r in rows:
        cells = "".join(f"{ms[n].get(r, 0.0):10.3f} ({100 * ms[n].get(r, 0.0) / ms_per_tick:4.1f}%)" for n in names)
        lines.append(r.ljust(width) + cells)
    busy = {n: sum(v for c, v in ms[n].items() if c in ORDER and c != WAITING) for n in names}
    lines.append("busy (not waiting)".ljust(width) + "".join(f"{busy[n]:10.3f} ({100 * busy[n] / ms_per_tick:4.1f}%)"
                                                             for n in names))
    return "\n".join(lines)
