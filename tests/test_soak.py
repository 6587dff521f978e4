"""The soak benchmark's arithmetic, and a small run of its in-process parts (no ROS)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from homeo_ops.soak import per_tick_ends, side_by_side, slope_per_10k


def test_slope_is_least_squares_after_the_first_tenth():
    pts = [(t, 50.0 + 0.2 * t / 10_000) for t in range(0, 100_001, 5_000)]
    assert slope_per_10k(pts) == pytest.approx(0.2)
    pts[0] = (0, 10.0)  # start-up growth in the first 10% does not count
    assert slope_per_10k(pts) == pytest.approx(0.2)


def test_time_per_tick_at_both_ends():
    # 1 ms a tick for the first half, 3 ms after: first tenth 1 ms, last tenth 3 ms
    times = [(t, t * 1e-3 if t <= 500 else 0.5 + (t - 500) * 3e-3) for t in range(0, 1001, 10)]
    first, last = per_tick_ends(times, 1000)
    assert first == pytest.approx(1e-3) and last == pytest.approx(3e-3)


def test_side_by_side_compares_the_same_minutes():
    # the long run: 100 ticks a second from clock 0, CPU 2 ms a tick, then 3 ms from clock 50 (the
    # machine got busier); the fresh run from clock 40 to 60: 1 ms, then 1.5 ms from clock 50
    def samples(t0, t1, start_tick, base):
        time, cpu, c = [], [], 0.0
        for i, w in enumerate(range(t0, t1 + 1)):
            k = start_tick + 100 * i
            time.append((k, float(w)))
            cpu.append((k, c))
            c += 100 * base * (1.5 if w >= 50 else 1.0)
        return {"time": time, "cpu": {"homeo_sim": cpu}, "reference": []}

    long, fresh = samples(0, 100, 0, 2e-3), samples(40, 60, 0, 1e-3)
    got = side_by_side(long, fresh, skip=0.0)
    assert got["seconds"] == pytest.approx(19.0)  # clock 40 to the fresh run's last sample but one
    assert got["homeo_sim"]["ratio"] == pytest.approx(2.0)
    assert got["homeo_sim"]["long_ticks"] == [4000, 5900]
    assert side_by_side(long, samples(200, 220, 0, 1e-3)) == {}  # no common minutes


def test_soak_runs_its_in_process_parts():
    r = subprocess.run([sys.executable, "-m", "homeo_launch.cli", "soak", "--iterations", "2000", "--bus", "300",
                        "--ticks", "0", "--json", "--quiet"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert set(out) == {"in_process", "bus"} and out["bus"]["ticks"] == 300
    p = out["in_process"]["processes"]["homeo-sim (in-process)"]
    assert p["rss_start_mb"] > 0 and p["cpu_s_per_tick_first"] > 0
    r = subprocess.run([sys.executable, "-m", "homeo_launch.cli", "soak", "--ticks", "50"], capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 2 and "at least 100" in r.stderr
    r = subprocess.run([sys.executable, "-m", "homeo_launch.cli", "soak", "--iterations", "0", "--ticks", "1000",
                        "--fresh", "200"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "at most a tenth" in r.stderr
