"""Faults: a worker killed mid-run, orphaned workers, evaluation timeouts, resumes,
damaged checkpoints, an unreachable scheduler."""

import json
import multiprocessing
import os
import signal
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

import analysis
import placement
from placement.cli import main
from placement.pso import ExecutorBroken, PSOOptions, pso
from placement.workers import WorkerLost, WorkerPool
from simulation import Room

ROOM = Room.techtile()
NODES = ROOM.grid()[::9]
OPTIONS = PSOOptions(particles=6, iterations=3, tol=0.0)
PSO_MODULE = sys.modules["placement.pso"]  # (placement.pso is also the function's name)


def mean_peb(anchors, rng):
    return float(np.mean(analysis.peb(anchors, NODES)))


@dataclass(frozen=True)
class KillOnce:
    """A cost whose first call after ``armed`` exists kills its own worker (SIGKILL, as
    the out-of-memory killer would); ``flag`` makes it happen once."""

    flag: str
    armed: str = ""

    def __call__(self, anchors, rng):
        if (not self.armed or os.path.exists(self.armed)) and not os.path.exists(self.flag):
            try:
                os.close(os.open(self.flag, os.O_CREAT | os.O_EXCL))
            except FileExistsError:
                pass
            else:
                os.kill(os.getpid(), signal.SIGKILL)
        time.sleep(0.02)
        return mean_peb(anchors, rng)


@dataclass(frozen=True)
class StallOnce:
    """A cost whose first call sleeps far beyond any timeout; ``hard`` blocks SIGALRM
    first (as code stuck in C would ignore it)."""

    flag: str
    hard: bool = False

    def __call__(self, anchors, rng):
        try:
            os.close(os.open(self.flag, os.O_CREAT | os.O_EXCL))
        except FileExistsError:
            return mean_peb(anchors, rng)
        if self.hard:
            signal.pthread_sigmask(signal.SIG_BLOCK, [signal.SIGALRM])
        time.sleep(120)
        return 0.0


def test_a_killed_worker_costs_its_particles_only(tmp_path):
    cost = KillOnce(str(tmp_path / "killed"))
    with WorkerPool(2) as pool:
        res = pso(cost, ROOM, 4, options=OPTIONS, rng=1, executor=pool, chunksize=1)
        assert pool.lost == 1 and pool.restarts >= 1
    assert res.success and res.nit == OPTIONS.iterations
    assert res.failures == 1 and res.extra["lost"] == 1
    costs = np.asarray(res.costs)
    assert np.isinf(costs).sum() == 1 and np.isinf(costs[0]).sum() == 1
    # every other evaluation of the first iteration is exactly the serial one
    serial = pso(mean_peb, ROOM, 4, options=PSOOptions(particles=6, iterations=1), rng=1)
    ok = np.isfinite(costs[0])
    np.testing.assert_array_equal(costs[0][ok], np.asarray(serial.costs)[0][ok])


def test_worker_lost_is_raised_for_the_dead_workers_task_only(tmp_path):
    with WorkerPool(2) as pool:
        bad = pool.submit(KillOnce(str(tmp_path / "k")), ROOM.corners_layout(), None)
        with pytest.raises(WorkerLost, match=r"died while running this task \(signal 9\)"):
            bad.result(timeout=60)
        good = [pool.submit(mean_peb, ROOM.corners_layout(), None) for _ in range(4)]
        assert all(np.isfinite(f.result(timeout=60)) for f in good)


def test_plain_process_pool_breaking_raises_after_the_checkpoint(tmp_path):
    ckpt = tmp_path / "state.json"
    armed = tmp_path / "armed"
    cost = KillOnce(str(tmp_path / "killed"), armed=str(armed))

    def arm(res):  # called after iteration 1: the kill comes in iteration 2
        armed.touch()

    options = PSOOptions(particles=6, iterations=4, tol=0.0)
    with ProcessPoolExecutor(2) as ex:
        with pytest.raises(ExecutorBroken, match=r"iteration 2 .*state.json holds iteration 1"):
            pso(cost, ROOM, 4, options=options, rng=3, executor=ex, checkpoint=ckpt,
                callback=arm, cost_label="kill")  # fmt: skip
    assert json.loads(ckpt.read_text())["iteration"] == 1
    # the rerun resumes and ends with the result of an uninterrupted run
    resumed = pso(mean_peb, ROOM, 4, options=options, rng=3, checkpoint=ckpt, cost_label="kill")
    full = pso(mean_peb, ROOM, 4, options=options, rng=3)
    assert resumed.extra["resumed_from"] == 1
    assert resumed.history == full.history


@pytest.mark.parametrize("mode", ["serial", "pool", "pool-hard"])
def test_eval_timeout_makes_the_particle_inf(tmp_path, monkeypatch, mode):
    monkeypatch.setattr(PSO_MODULE, "_DEADLINE_GRACE", 1.0)
    cost = StallOnce(str(tmp_path / "stalled"), hard=mode == "pool-hard")
    options = PSOOptions(particles=4, iterations=2, tol=0.0, eval_timeout=0.5)
    t0 = time.monotonic()
    if mode == "serial":
        res = pso(cost, ROOM, 4, options=options, rng=0)
    else:
        with WorkerPool(2) as pool:
            res = pso(cost, ROOM, 4, options=options, rng=0, executor=pool)
    assert time.monotonic() - t0 < 30
    assert res.success and res.extra["timeouts"] >= 1 and res.failures == res.extra["timeouts"]
    assert res.extra["lost"] == 0


def test_eval_timeout_is_checked():
    for bad in (0, -1, float("nan"), "1", True):
        with pytest.raises(ValueError, match="^eval_timeout: must be a finite number > 0 s"):
            PSOOptions(eval_timeout=bad)


@pytest.mark.skipif(
    multiprocessing.get_start_method() != "fork", reason="the patched cost reaches forked workers"
)
def test_cli_rebuilds_its_pool_after_a_killed_worker(tmp_path, monkeypatch, capsys):
    flag = str(tmp_path / "killed")
    real = placement.PEBCost.__call__

    def dying(self, anchors, rng=None):  # the pool's workers are forked: they inherit it
        return KillOnce(flag)(anchors, rng) and real(self, anchors, rng)

    monkeypatch.setattr(placement.PEBCost, "__call__", dying)
    argv = ["plan", "--anchors", "4", "--cost", "peb", "--no-initial", "--particles", "4"]
    argv += ["--iterations", "3", "--finalists", "1", "--validate-realizations", "0"]
    argv += ["--no-progress", "--workers", "2", "--out", str(tmp_path / "out")]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "2 evaluation(s) failed and cost inf: 2 lost to dead worker processes" in out
    assert (tmp_path / "out" / "layout.json").exists()


def _children(pid):
    out = []
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                stat = Path(f"/proc/{d}/stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                out.append(int(d))
    return out


def _running(pid):
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"  # zombies have exited


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="needs /proc")
def test_no_orphan_workers_after_sigkill_of_the_cli(tmp_path):
    exe = Path(sys.executable).with_name("anchorplan")
    cmd = [str(exe), "plan", "--anchors", "4", "--cost", "peb", "--no-initial"]
    cmd += ["--particles", "4", "--iterations", "100000", "--finalists", "1"]
    cmd += ["--validate-realizations", "0", "--no-progress", "--workers", "2"]
    cmd += ["--out", str(tmp_path / "out")]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        kids = []
        while time.monotonic() < deadline and len(kids) < 2:
            kids = _children(proc.pid)
            time.sleep(0.05)
        assert len(kids) >= 2, "the pool's workers did not start"
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and any(_running(k) for k in kids):
        time.sleep(0.1)
    left = [k for k in kids if _running(k)]
    for k in left:
        os.kill(k, signal.SIGKILL)
    assert not left, f"orphaned workers {left}"


def test_cli_says_it_resumed_and_from_which_iteration(tmp_path, capsys):
    ckpt = tmp_path / "state.json"
    argv = ["plan", "--anchors", "4", "--cost", "peb", "--no-initial", "--particles", "4"]
    argv += ["--iterations", "3", "--finalists", "1", "--validate-realizations", "0"]
    argv += ["--no-progress", "--workers", "1", "--checkpoint", str(ckpt)]
    assert main([*argv, "--out", str(tmp_path / "a")]) == 0
    capsys.readouterr()
    assert main([*argv, "--out", str(tmp_path / "b")]) == 0
    captured = capsys.readouterr()
    assert f"checkpoint {ckpt}: found (iteration 2)" in captured.out
    assert f"resumed from checkpoint {ckpt} after iteration 2" in captured.out
    assert "resuming from" in captured.err
    a = json.loads((tmp_path / "a" / "result.json").read_text())
    b = json.loads((tmp_path / "b" / "result.json").read_text())
    assert a["anchors"] == b["anchors"] and a["history"] == b["history"]


@pytest.mark.parametrize(
    ("content", "says"),
    [
        ("null", "expected a JSON object"),
        ('{"version": 1, "fingerp', "not valid JSON, truncated?"),
        ("[1, 2]", "expected a JSON object"),
        ('{"version": 1}', "not a complete checkpoint"),
        ('{"a": 1}', "not an anchorplan checkpoint"),
        (b"\xff\xfe\x00", "cannot read it"),
    ],
)
def test_damaged_checkpoint_is_one_line_naming_the_file(tmp_path, capsys, content, says):
    ckpt = tmp_path / "state.json"
    if isinstance(content, bytes):
        ckpt.write_bytes(content)
    else:
        ckpt.write_text(content)
    t0 = time.monotonic()
    argv = ["plan", "--checkpoint", str(ckpt), "--out", str(tmp_path / "o"), "--no-progress"]
    assert main(argv) == 2
    assert time.monotonic() - t0 < 5
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(ckpt) in err and says in err
    assert "delete it" in err and "start afresh" in err
    with pytest.raises(ValueError, match=f"checkpoint {ckpt}: .*start afresh"):
        pso(mean_peb, ROOM, 4, options=OPTIONS, checkpoint=ckpt)


def test_dead_scheduler_fails_fast(tmp_path, capsys):
    pytest.importorskip("dask.distributed")
    t0 = time.monotonic()
    argv = ["plan", "--scheduler", "tcp://127.0.0.1:9", "--out", str(tmp_path / "o")]
    assert main(argv) == 2
    assert time.monotonic() - t0 < 8  # a 3 s connection timeout, and dask's import
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--scheduler tcp://127.0.0.1:9: cannot connect" in err
    assert main(["plan", "--scheduler", "no address", "--out", str(tmp_path / "o")]) == 2
    assert "--scheduler: expected an address like tcp://host:8786" in capsys.readouterr().err


def _die_once(marker: str, value: int) -> int:
    """Kill the worker process the first time (as the out-of-memory killer would)."""
    import os
    from pathlib import Path

    if not Path(marker).exists():
        Path(marker).write_text("died")
        os._exit(9)
    return value * 2


def test_run_jobs_resubmits_a_job_whose_worker_died(tmp_path):
    from placement.workers import WorkerPool, run_jobs

    marker = str(tmp_path / "marker")
    with WorkerPool(max_workers=2) as pool:
        out = run_jobs(pool, _die_once, [(marker, 1), (marker, 2), (marker, 3)])
    assert out == [2, 4, 6]


def test_run_jobs_on_a_plain_pool_that_breaks_raises_executor_broken(tmp_path):
    from concurrent.futures import ProcessPoolExecutor

    from placement.workers import ExecutorBroken, run_jobs

    marker = str(tmp_path / "marker")
    with ProcessPoolExecutor(max_workers=1) as pool:
        with pytest.raises(ExecutorBroken, match="WorkerPool"):
            run_jobs(pool, _die_once, [(marker, 1)])


def _blas_threads() -> int:
    from threadpoolctl import threadpool_info

    return max((d["num_threads"] for d in threadpool_info() if d["user_api"] == "blas"), default=1)


def test_a_worker_runs_one_blas_thread():
    """The pool has a process per core; a worker's BLAS keeps to one thread, so that the
    processes do not oversubscribe the cores (results do not depend on it)."""
    with WorkerPool(2) as pool:
        assert pool.submit(_blas_threads).result() == 1
