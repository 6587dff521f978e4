"""Checkpoints off the tick's path (``homeo_decision.checkpoint_writer``): the tick hands over a
snapshot and goes on; one thread writes the newest; the final one is written at shutdown after
what was on its way. No timing: a write the test holds back shows what the caller does not wait for."""

from __future__ import annotations

import json
import threading

import pytest

from homeo_decision import checkpoint
from homeo_decision.agent import DecisionCore
from homeo_decision.checkpoint_writer import BackgroundWriter


class HeldWrites:
    """A ``write`` that blocks until the test lets it go, and records what it wrote, in which thread."""

    def __init__(self):
        self.release = threading.Event()
        self.started = threading.Event()
        self.written, self.threads = [], []

    def __call__(self, snap):
        self.started.set()
        self.release.wait(10)
        self.written.append(snap)
        self.threads.append(threading.current_thread().name)


def test_the_caller_does_not_wait_for_a_write_and_the_newest_snapshot_wins():
    w = HeldWrites()
    bg = BackgroundWriter(w, name="ck-test")
    bg.submit(1)
    assert w.started.wait(10)  # the thread is inside the first write, held
    bg.submit(2)
    bg.submit(3)  # 2 was still waiting: it is superseded by 3, never written
    assert w.written == [] and not bg.idle()
    w.release.set()
    assert bg.flush(10)
    assert w.written == [1, 3] and bg.superseded == 1 and w.threads == ["ck-test", "ck-test"]
    assert bg.close(10)
    with pytest.raises(RuntimeError):
        bg.submit(4)


def test_close_writes_what_is_pending_and_a_failing_write_does_not_end_the_thread():
    seen = []

    def write(snap):
        if snap == "bad":
            raise OSError("disk on fire")
        seen.append(snap)

    bg = BackgroundWriter(write)
    bg.submit("bad")
    assert bg.flush(10) and isinstance(bg.error, OSError)
    bg.submit("good")
    assert bg.close(10) and seen == ["good"]


def _decision_checkpointer(tmp_path, core, ticks, background=True, log=lambda text: None):
    return checkpoint.Checkpointer(str(tmp_path), "homeo_decision", 10,
                                   lambda: checkpoint.decision_snapshot(core, ticks[0], 0, "s1"), log,
                                   background=background)


def test_a_background_checkpointer_writes_off_the_callers_thread_and_close_writes_the_last(tmp_path, monkeypatch, thesis):
    core = DecisionCore(thesis, 3)
    ticks = [10]
    held = HeldWrites()
    real_save = checkpoint.save

    def slow_disk(path, ck):  # the write is held: the tick must not wait for it
        held(ck["ticks"])
        real_save(path, ck)

    monkeypatch.setattr(checkpoint, "save", slow_disk)
    ck = _decision_checkpointer(tmp_path, core, ticks)
    ck.after_tick(10)  # hands over and returns while the disk holds the write
    assert held.started.wait(10) and held.written == [] and ck.saved == 0
    assert not (tmp_path / "homeo_decision.json").exists()
    ticks[0] = 20
    ck.after_tick(20)
    ck.after_tick(20)  # the same ticks again: not handed over twice
    held.release.set()
    ck.close()  # at shutdown: what is on its way is written first
    assert held.written == [10, 20] and held.threads == ["homeo_decision-checkpoints"] * 2
    assert ck.saved == 2 and ck.last_ticks == 20 and ck.superseded == 0
    assert checkpoint.load(tmp_path / "homeo_decision.json", "homeo_decision")["ticks"] == 20
    ticks[0] = 25
    assert ck.save()  # after close: written in the caller, at once (the final checkpoint)
    assert held.threads[-1] == threading.current_thread().name and ck.last_ticks == 25
    assert not list(tmp_path.glob("*.tmp"))


def test_a_snapshot_is_the_state_when_it_was_taken_not_when_it_is_written(thesis):
    core = DecisionCore(thesis, 5)
    snap = checkpoint.decision_snapshot(core, 7, 0)
    want = json.dumps(checkpoint.decision_checkpoint(core, 7, 0), sort_keys=True)
    core.q.q[0][0][0] += 1.0  # the tick goes on learning before the writer gets to it
    core.rng.random()
    assert snap.ticks == 7 and json.dumps(snap(), sort_keys=True) == want
    assert json.dumps(checkpoint.decision_checkpoint(core, 7, 0), sort_keys=True) != want


def test_a_failed_background_write_is_counted_and_logged_and_the_final_save_retries(tmp_path, thesis):
    core = DecisionCore(thesis, 3)
    logged = []
    blocker = tmp_path / "homeo_decision.json"
    blocker.mkdir()  # a directory where the file should go: every write fails
    ck = _decision_checkpointer(tmp_path, core, [10], log=logged.append)
    ck.after_tick(10)
    ck.close()
    assert ck.failed == 1 and ck.saved == 0 and ck.last_ticks == -1 and "is a directory" in logged[0]
    assert "\n" not in ck.last_error
    blocker.rmdir()
    assert ck.save() and ck.last_ticks == 10  # the final save at shutdown writes what the thread could not


def test_the_drives_slots_written_in_the_background_load_as_the_newest_tick(tmp_path, thesis):
    from homeo_decision.hosts import PerceptionHost

    host = PerceptionHost(thesis)
    answer = [(0, {})]
    ck = checkpoint.Checkpointer(str(tmp_path), "homeo_drives", 1,
                                 lambda: checkpoint.drives_checkpoint(host.perception, 0, *answer[0]), background=True)
    for k in range(50):
        answer[0] = (k, {"k": k})
        ck.save()
    ck.close()
    got = checkpoint.load(tmp_path / "homeo_drives.slots", "homeo_drives")
    assert got["ticks"] == 50 and got["state"]["answer"] == {"k": 49}
    assert ck.saved + ck.superseded == 50
