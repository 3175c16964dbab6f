"""The Ray backend on a local Ray instance (2 CPUs): the same map as the process pool, a dead
actor's chunk retried, and an address that does not answer refused within the timeout."""

from __future__ import annotations

import functools
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from usar_arm import jobs
from usar_arm.errors import EXIT_UNAVAILABLE, ChunkFailedError, ClusterUnavailableError
from usar_arm.planning.scene_file import load_scene
from usar_arm.robot import Robot
from usar_arm.workspace.engine import Job, run_job
from usar_arm.workspace.reach import ReachSettings

from . import faults

ray = pytest.importorskip("ray", reason="the ray extra is not installed "
                                        "(pip install 'usar-arm[ray]')")


@pytest.fixture(scope="module")
def local_ray() -> Iterator[None]:
    """One local Ray instance with 2 CPUs for the module (the backends join it)."""
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False,
             object_store_memory=256 * 2**20)
    yield
    ray.shutdown()


def test_ray_gives_the_same_map_as_the_process_pool(local_ray: None, kr60: Robot) -> None:
    settings = ReachSettings(0.3, 16)
    scene = load_scene("table")
    pool = jobs.reach_map(kr60, scene, settings, jobs.backend_for(2)).map
    on_ray = jobs.reach_map(kr60, scene, settings, jobs.backend_for(None, "local")).map
    for name in ("index", "manipulability", "margin", "best_orientation", "reachable"):
        assert np.array_equal(getattr(pool, name), getattr(on_ray, name)), name
    assert np.array_equal(pool.best_q, on_ray.best_q, equal_nan=True)


def test_a_dead_actor_has_its_chunk_retried_and_a_second_death_names_it(
        local_ray: None, tmp_path: Path) -> None:
    chunks = [np.arange(10 * i, 10 * i + 10) for i in range(6)]

    def job(work: object, key: str) -> Job:
        return Job("test", functools.partial(faults.prepare, str(tmp_path)), work,  # type: ignore[arg-type]
                   chunks, key, [10] * 6)

    backend = jobs.backend_for(2, "local")
    results, _ = run_job(job(faults.dies_once_on_chunk_3, "once"), backend)
    assert (tmp_path / "died").exists()
    assert np.array_equal(np.concatenate([r["squares"] for r in results]),
                          np.arange(60) ** 2)
    with pytest.raises(ChunkFailedError) as err:
        run_job(job(faults.always_dies_on_chunk_3, "always"), backend)
    assert err.value.chunk == 3 and err.value.attempts == 2


def test_a_refused_address_is_reported_at_once() -> None:
    backend = jobs.backend_for(None, "127.0.0.1:1", timeout=1.0)
    begin = time.perf_counter()
    with pytest.raises(ClusterUnavailableError) as err:
        next(iter(backend.run(Job("x", lambda: None, lambda c, k: {}, [1], "k", [1]), [0])))
    assert time.perf_counter() - begin < 2.0
    assert "127.0.0.1:1" in str(err.value) and "1 s" in str(err.value)


def test_an_address_that_accepts_tcp_but_is_no_ray_head_fails_within_the_timeout(
        tmp_path: Path) -> None:
    """This network answers TCP on any address (a proxy), so only Ray's own attempts to reach
    a GCS can tell; they are bounded by --ray-timeout. In a fresh process: this one may
    already be connected to the module's local Ray."""
    urdf = str(Path(__file__).resolve().parents[2] / "robots/generated/KR60.urdf")
    command = [str(Path(sys.executable).parent / "usar-arm"), "reach", "--urdf", urdf,
               "--out", str(tmp_path), "--ray", "10.255.255.1:6379", "--ray-timeout", "1"]
    begin = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)
    took = time.perf_counter() - begin
    assert done.returncode == EXIT_UNAVAILABLE, done.stderr[-2000:]
    assert "10.255.255.1:6379" in done.stderr and "waited 1 s" in done.stderr
    assert took < 12.0  # measured 4.6 s with start-up; Ray left unbounded waits 20 s
    assert not (tmp_path / "reach.npz").exists()
