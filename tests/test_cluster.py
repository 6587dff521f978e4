"""Studies on a Ray cluster (issue 30): the same JSON as the local pool's, a node lost mid-study, a study
interrupted and started again; the kept runs, the one-line errors. The clusters are real (Ray on loopback,
tools/loopback_cluster.py: a head and worker nodes on ports chosen free at run time), started and stopped
by the test that uses them."""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import given, settings, strategies as st

# one worker runs every Ray test in turn (make test: --dist loadgroup): `--cluster auto` finds any Ray cluster
# running on this machine, another test's too
pytestmark = pytest.mark.xdist_group("ray")

from homeo_sim.parallel import Kept, Pool, code_digest, parallel_map
from homeo_sim.runner import RunConfig, _run_one, run_seeds
from homeo_sim.sweep import run_jobs

TOOLS = Path(__file__).resolve().parents[1] / "tools"
sys.path.insert(0, str(TOOLS))


def cli(*args, env=None, timeout=900):
    return subprocess.run([sys.executable, "-m", "homeo_sim.cli", *map(str, args)], capture_output=True, text=True,
                          env=env, timeout=timeout)


def results(path: Path) -> dict:
    """results.json without its wall times (the one part that differs from run to run)."""
    data = json.loads((path / "results.json").read_text())
    data.pop("timing")
    return data


def kept_files(out: Path) -> dict[str, int]:
    return {f.name: f.stat().st_mtime_ns for f in (out / "runs" / code_digest()).glob("*.json")}


@pytest.fixture
def cluster():
    pytest.importorskip("ray")
    from loopback_cluster import LoopbackCluster

    c = LoopbackCluster(head_cpus=1, nodes=(2,)).start()
    try:
        yield c
    finally:
        c.stop()


# -- on a real cluster ------------------------------------------------------------------------------

@pytest.mark.ray
@pytest.mark.slow
def test_report_on_a_cluster_is_the_local_report(cluster, tmp_path):
    # the claim: the 20-seed report (480 runs) on a head and a node, gives the local pool's JSON; runs of
    # 1000 iterations, not 5000 (what is compared does not depend on a run's length; the suite's time does)
    local = cli("report", "--seeds", 20, "--iterations", 1000, "--quiet", "--out", tmp_path / "local")
    assert local.returncode == 0, local.stderr
    ray = cli("report", "--seeds", 20, "--iterations", 1000, "--quiet", "--out", tmp_path / "ray", "--cluster",
              cluster.address, env=cluster.env)
    assert ray.returncode == 0, ray.stderr
    assert "(480 runs on 3 workers)" in ray.stdout  # the cluster's three CPUs ran them, not this machine's two
    assert results(tmp_path / "ray") == results(tmp_path / "local")
    assert len(kept_files(tmp_path / "ray")) == 480


@pytest.mark.ray
def test_a_node_lost_mid_study_gives_the_same_json(tmp_path):
    pytest.importorskip("ray")
    from loopback_cluster import LoopbackCluster

    args = ("sweep", "dod", "--seeds", 3, "--iterations", 3000, "--json", "--quiet")
    local = cli(*args)
    assert local.returncode == 0, local.stderr
    # the head runs no tasks (the driver is attached to it): every run is on one of the two nodes
    with LoopbackCluster(head_cpus=0, nodes=(1, 1)) as c:
        out = tmp_path / "ray"
        proc = subprocess.Popen([sys.executable, "-m", "homeo_sim.cli", *map(str, args), "--out", out,
                                 "--cluster", c.address], env=c.env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True)
        try:
            _wait_for_kept(out, 4, proc)
            c.kill(c.nodes[0])  # with the run it was running
            stdout, stderr = proc.communicate(timeout=600)
        finally:
            proc.kill()
    assert proc.returncode == 0, stderr
    assert json.loads(stdout) == json.loads(local.stdout)


@pytest.mark.ray
def test_an_interrupted_study_runs_only_what_is_missing(cluster, tmp_path):
    out = tmp_path / "study"
    args = ("sweep", "xi", "--seeds", 4, "--iterations", 2000, "--json", "--quiet", "--out", out,
            "--cluster", cluster.address)
    err = _interrupted(args, out, 3, cluster.env)
    before = kept_files(out)
    m = re.search(r"interrupted: (\d+) of (\d+) runs kept in (\S+)", err)
    assert m and int(m[1]) == len(before) and Path(m[3]) == out / "runs" / code_digest(), err
    assert "cancelled the study's" in err and err.strip().endswith("homeo-sim: interrupted")
    n_runs = int(m[2])
    assert n_runs == 7 * 4 and 3 <= len(before) < n_runs  # seven values of xi, four seeds
    again = cli(*args, env=cluster.env)
    assert again.returncode == 0, again.stderr
    after = kept_files(out)
    assert len(after) == n_runs
    assert {k: after[k] for k in before} == before  # the kept runs were read, not run again
    local = cli(*args[:-2])
    assert json.loads(again.stdout) == json.loads(local.stdout)


def _interrupted(args, out: Path, n: int, env=None) -> str:
    """Ctrl-C to ``homeo-sim ARGS`` once it kept ``n`` runs in ``out``: its stderr (exit 130 checked)."""
    proc = subprocess.Popen([sys.executable, "-m", "homeo_sim.cli", *map(str, args)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_for_kept(out, n, proc)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    return err


def _wait_for_kept(out: Path, n: int, proc, limit: float = 300) -> None:
    deadline = time.monotonic() + limit
    while len(kept_files(out)) < n:
        assert proc.poll() is None, proc.communicate()[1]
        assert time.monotonic() < deadline, f"fewer than {n} runs kept after {limit} s"
        time.sleep(0.1)


# -- kept runs, without a cluster --------------------------------------------------------------------

def test_kept_runs_are_read_back_exactly_and_used(tmp_path):
    cfgs = [RunConfig(iterations=300), RunConfig(iterations=300, dod=0.0, adaptive_dod=True)]
    fresh = run_jobs(cfgs, [1, 2], workers=1, curves=True)
    pool = Pool(1, keep=tmp_path)
    first = run_jobs(cfgs, [1, 2], pool, curves=True)
    again = run_jobs(cfgs, [1, 2], pool, curves=True)
    for a, b, c in ((x, y, z) for rows in zip(fresh, first, again) for x, y, z in zip(*rows)):
        assert a.metrics == b.metrics == c.metrics and a.learning == c.learning and a.extra == c.extra
        assert type(c.extra.get("dod_final", 0.0)) is type(a.extra.get("dod_final", 0.0))
        for k in ("t", "HSR", "wRSR", "dod"):
            if k in a.curves:
                assert c.curves[k].dtype == a.curves[k].dtype and (c.curves[k] == a.curves[k]).all()
    # a kept run is what a rerun returns: change one and the rerun reports the change
    key = Kept.key(_run_one, RunConfig(iterations=200, seed=5))
    run_seeds(RunConfig(iterations=200), [5, 6], Pool(1, keep=tmp_path))
    f = tmp_path / code_digest() / f"{key}.json"
    data = json.loads(f.read_text())
    data["metrics"]["HSR"] = 0.125
    f.write_text(json.dumps(data))
    assert [r.metrics["HSR"] for r in run_seeds(RunConfig(iterations=200), [5, 6], Pool(1, keep=tmp_path))][0] == 0.125
    # a file that does not decode is run again, and rewritten
    f.write_text('{"": "os.system", "command": "true"}')
    assert run_seeds(RunConfig(iterations=200), [5], Pool(1, keep=tmp_path))[0].metrics["HSR"] != 0.125
    assert json.loads(f.read_text())[""] == "EpisodeResult"


def test_ctrl_c_with_out_says_how_many_runs_are_kept(tmp_path):
    err = _interrupted(("run", "--seeds", "400", "--quiet", "--out", tmp_path), tmp_path, 2)
    m = re.fullmatch(r"interrupted: (\d+) of 400 runs kept in (\S+)\nhomeo-sim: interrupted\n", err)
    assert m and int(m[1]) == len(kept_files(tmp_path)) >= 2, err


def test_a_kept_run_is_keyed_by_its_scenario_file_too(tmp_path):
    from homeo_decision.scenarios import default_scenario_path

    f = tmp_path / "s.json"
    f.write_text(Path(default_scenario_path()).read_text())
    k1 = Kept.key(len, RunConfig(scenario=str(f)))
    f.write_text(f.read_text() + " ")
    assert Kept.key(len, RunConfig(scenario=str(f))) != k1 != Kept.key(len, RunConfig(scenario=str(f), seed=1))


# -- the one-line errors -------------------------------------------------------------------------------

@settings(max_examples=200, deadline=None)
@given(st.text(max_size=80))
def test_cluster_address_is_auto_host_port_or_ray_url(s):
    import argparse

    from homeo_sim.cluster import address

    try:
        assert address(s) == s
    except argparse.ArgumentTypeError as exc:
        assert "\n" not in str(exc) and "is not auto, HOST:PORT or ray://HOST:PORT" in str(exc)
        return
    host, _, port = s.removeprefix("ray://").rpartition(":")
    assert s == "auto" or (host and 1 <= int(port) <= 65535)


@pytest.mark.parametrize("bad", ["", "localhost", "host:0", "host:65536", "http://h:1", "ray://h", "h:1:2", "a b:1"])
def test_bad_cluster_addresses_are_one_line(bad):
    proc = cli("run", "--seeds", 2, "--cluster", bad)
    assert proc.returncode == 2 and len(proc.stderr.splitlines()) == 1, proc.stderr
    assert "is not auto, HOST:PORT or ray://HOST:PORT" in proc.stderr


def test_without_ray_the_error_says_how_to_install_it():
    code = ("import sys; sys.modules['ray'] = None; from homeo_sim.cli import main; "
            "sys.exit(main(['run', '--seeds', '2', '--iterations', '50', '--cluster', '127.0.0.1:6379']))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and proc.stderr == ("homeo-sim: error: --cluster needs Ray: pip install '.[cluster]' "
                                                    "(in a checkout: make cluster-setup)\n")


def test_an_unreachable_cluster_is_one_line_within_a_bounded_wait():
    pytest.importorskip("ray")
    with socket.socket() as s:  # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    listener = socket.socket()  # and one that accepts but is no Ray cluster
    listener.bind(("127.0.0.1", 0))
    listener.listen(8)
    try:
        for addr, said in ((f"127.0.0.1:{port}", "cannot reach the Ray cluster at"),
                           (f"ray://127.0.0.1:{port}", "cannot reach the Ray cluster at"),
                           (f"127.0.0.1:{listener.getsockname()[1]}", "does not answer as a Ray cluster within 30 s")):
            t0 = time.monotonic()
            proc = cli("run", "--seeds", 2, "--iterations", 50, "--cluster", addr, timeout=120)
            assert proc.returncode == 2 and said in proc.stderr, proc.stderr
            assert len(proc.stderr.strip().splitlines()) == 1 and proc.stdout == "", proc.stderr
            assert time.monotonic() - t0 < 120  # the wait is 30 s; the rest, starting Python on a busy machine
    finally:
        listener.close()
    env = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"}
    env["RAY_TMPDIR"] = f"/tmp/noray{os.getpid()}"  # no cluster has ever written its address there
    proc = cli("run", "--seeds", 2, "--cluster", "auto", env=env, timeout=120)
    assert proc.returncode == 2 and "--cluster auto: no running Ray cluster on this machine" in proc.stderr, proc.stderr


def test_files_of_this_machine_stay_off_the_cluster(tmp_path):
    proc = cli("run", "--seeds", 2, "--trace", tmp_path / "t.jsonl", "--cluster", "127.0.0.1:6379")
    assert proc.returncode == 2 and "--cluster: runs that read or write files" in proc.stderr, proc.stderr
    assert not (tmp_path / "t.jsonl").exists()


def test_parallel_map_keeps_any_job_in_order(tmp_path):
    # the seam itself: results by their place in args, whatever finishes first, kept or not
    out = parallel_map(abs, [-3, 2, -1, 0], Pool(2, keep=tmp_path))
    assert out == [3, 2, 1, 0] == parallel_map(abs, [-3, 2, -1, 0], Pool(2, keep=tmp_path))
    assert len(list((tmp_path / code_digest()).glob("*.json"))) == 4


# -- the searches ---------------------------------------------------------------------------------------

def _search(out: Path, *more, env=None):
    args = ["search", "--search-seeds", "0-1", "--statement-seeds", "0-19", "--gate", "0", "--out", str(out), *more]
    return subprocess.run([sys.executable, str(TOOLS / "error_search.py"), *map(str, args)], capture_output=True,
                          text=True, env=env, timeout=600)


def _trials(out: Path) -> list[dict]:
    return [json.loads(ln) for ln in (out / "trials.jsonl").read_text().splitlines()]


def test_a_search_started_again_goes_on_where_it_stopped(tmp_path):
    pytest.importorskip("optuna")
    whole = _search(tmp_path / "whole", "--trials", 3)
    assert whole.returncode == 0, whole.stderr
    first = _search(tmp_path / "split", "--trials", 2)
    assert first.returncode == 0, first.stderr
    runs = kept_files(tmp_path / "split")
    again = _search(tmp_path / "split", "--trials", 3)
    assert again.returncode == 0, again.stderr
    assert "2 trials done, 1 to go" in again.stderr
    # the same three trials as one search of three (the sampler's seed, the study's history), each run once
    strip = lambda ts: [{k: t[k] for k in ("open", "score", "trial")} for t in ts]  # noqa: E731
    assert strip(_trials(tmp_path / "split")) == strip(_trials(tmp_path / "whole"))
    assert {k: v for k, v in kept_files(tmp_path / "split").items() if k in runs} == runs
    bad = _search(tmp_path / "bad", "--trials", 1, "--storage", "nosuchdb://x")
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1, bad.stderr
    assert bad.stderr.startswith("error_search.py: error: --storage nosuchdb://x: ")


@pytest.mark.ray
def test_a_search_on_a_cluster_scores_as_here(cluster, tmp_path):
    pytest.importorskip("optuna")
    here = _search(tmp_path / "here", "--trials", 2)
    there = _search(tmp_path / "there", "--trials", 2, "--parallel-trials", 2, "--cluster", cluster.address,
                    env=cluster.env)
    assert here.returncode == 0 and there.returncode == 0, there.stderr
    by_open = lambda ts: sorted((json.dumps(t["open"], sort_keys=True), t["score"]) for t in ts)  # noqa: E731
    assert by_open(_trials(tmp_path / "there")) == by_open(_trials(tmp_path / "here"))
