"""The Ray backend: ``--ray local`` starts a fresh instance of its own (in a command of its
own), and on one module-wide local instance of 2 CPUs, joined with ``auto``: the same map as
the process pool, a dead actor's chunk retried, more workers than CPUs capped, an actor that
cannot start named within its timeout; addresses that do not answer are refused in time."""

from __future__ import annotations

import functools
import json
import logging
import os
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from usar_arm.core.errors import EXIT_UNAVAILABLE
from usar_arm.core.job_errors import ChunkFailedError, ClusterUnavailableError
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene_file import load_scene
from usar_arm.workspace import jobs
from usar_arm.workspace.engine import Job, run_job
from usar_arm.workspace.reach import ReachSettings

from . import faults

ray = pytest.importorskip("ray", reason="the ray extra is not installed "
                                        "(pip install 'usar-arm[ray]')")
from usar_arm.workspace.ray_backend import RayBackend  # noqa: E402  (needs ray)

REPO = Path(__file__).resolve().parents[2]
URDF = str(REPO / "robots" / "generated" / "KR60.urdf")
SMALL = ["--resolution", "0.3", "--orientations", "16"]


@pytest.fixture(scope="module")
def local_ray() -> Iterator[None]:
    """One local Ray instance with 2 CPUs for the module, which ``auto`` joins."""
    ray.init(address="local", num_cpus=2, include_dashboard=False, log_to_driver=False,
             object_store_memory=256 * 2**20)
    yield
    ray.shutdown()


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def _squares_job(work: object, key: str, folder: Path, chunks: int = 6) -> Job:
    parts = [np.arange(10 * i, 10 * i + 10) for i in range(chunks)]
    return Job("test", functools.partial(faults.prepare, str(folder)), work,  # type: ignore[arg-type]
               parts, key, [10] * chunks)


def _squares(results: list[dict[str, np.ndarray]]) -> np.ndarray:
    return np.concatenate([r["squares"] for r in results])


def test_local_starts_a_fresh_instance_of_its_own_and_gives_the_pools_map(
        local_ray: None, tmp_path: Path) -> None:
    """The real --ray local path, in a command of its own (this process is connected to the
    module's instance, which local must neither join nor stop)."""
    command = [str(Path(sys.executable).parent / "usar-arm"), "reach", "--urdf", URDF, *SMALL,
               "--scene", "table", "--json", "-q"]
    on_ray = subprocess.run([*command, "--ray", "local", "--workers", "2",
                             "--out", str(tmp_path / "ray")], capture_output=True, text=True,
                            timeout=300, check=False)
    assert on_ray.returncode == 0, on_ray.stderr[-3000:]
    run = json.loads(on_ray.stdout)["run"]
    assert run["backend"] == "2 Ray actors on a fresh local Ray instance"
    assert 0 < run["backend_start_seconds"] <= run["seconds"]
    # while Ray started, a helper ran at most one worker's share (the rest: the actors)
    assert run["chunks_run_by_the_command_while_ray_started"] <= run["chunks_run"] // 3
    pool = subprocess.run([*command, "--workers", "2", "--out", str(tmp_path / "pool")],
                          capture_output=True, text=True, timeout=300, check=False)
    assert pool.returncode == 0, pool.stderr[-3000:]
    with np.load(tmp_path / "ray" / "reach.npz") as a, np.load(tmp_path / "pool" /
                                                               "reach.npz") as b:
        for name in ("index", "manipulability", "margin", "best_orientation", "reachable"):
            assert np.array_equal(a[name], b[name]), name
        assert np.array_equal(a["best_q"], b["best_q"], equal_nan=True)
    assert ray.is_initialized() and ray.cluster_resources()["CPU"] == 2  # ours lives on


LOCAL_TWICE = """
import functools, sys, numpy as np, ray
from usar_arm.workspace.engine import Job, run_job
from usar_arm.workspace.ray_backend import RayBackend
from tests.workspace import faults
chunks = [np.arange(10 * i, 10 * i + 10) for i in range(12)]
job = Job("t", functools.partial(faults.prepare, sys.argv[1]), faults.slow_square, chunks,
          "k", [10] * 12)
backend = RayBackend("local", 2)
gcs = []
for _ in range(2):
    results, stats = run_job(job, backend)
    assert np.array_equal(np.concatenate([r["squares"] for r in results]), np.arange(120) ** 2)
    assert RayBackend.stopping is not None  # stopping in the background
    assert 1 <= stats.chunks_here <= 4, stats  # (Ray takes seconds to start; its share: 12 / 3)
    gcs.append(backend.gcs_address)
assert gcs[0] != gcs[1], gcs  # a fresh instance each time
job = Job("t", functools.partial(faults.prepare, sys.argv[1]), faults.dies_once_on_chunk_3,
          chunks, "dies", [10] * 12)
results, stats = run_job(job, backend)  # (whether the helper or an actor died: retried)
assert np.array_equal(np.concatenate([r["squares"] for r in results]), np.arange(120) ** 2)
print("ok")
"""


def test_local_starts_afresh_each_run_with_a_helper_while_it_starts(tmp_path: Path) -> None:
    """Each run a fresh instance, stopped in the background; while it starts, a helper process
    runs chunks (one worker's share at most); a process that dies costs its chunk one try."""
    done = subprocess.run([sys.executable, "-c", LOCAL_TWICE, str(tmp_path)], cwd=REPO,
                          capture_output=True, text=True, timeout=180, check=False)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr[-3000:]


def test_local_refuses_a_process_already_connected_to_another_instance(
        local_ray: None) -> None:
    with pytest.raises(ClusterUnavailableError, match="already connected") as err:
        jobs.backend_for(2, "local").start()
    assert "--ray auto" in str(err.value)
    assert ray.is_initialized()


def test_ray_gives_the_same_map_as_the_process_pool(local_ray: None, kr60: Robot) -> None:
    settings = ReachSettings(0.3, 16)
    scene = load_scene("table")
    pool = jobs.reach_map(kr60, scene, settings, jobs.backend_for(2)).map
    on_ray = jobs.reach_map(kr60, scene, settings, jobs.backend_for(None, "auto")).map
    for name in ("index", "manipulability", "margin", "best_orientation", "reachable"):
        assert np.array_equal(getattr(pool, name), getattr(on_ray, name)), name
    assert np.array_equal(pool.best_q, on_ray.best_q, equal_nan=True)


def test_a_dead_actor_has_its_chunk_retried_and_a_second_death_names_it(
        local_ray: None, tmp_path: Path) -> None:
    backend = jobs.backend_for(2, "auto")
    results, _ = run_job(_squares_job(faults.dies_once_on_chunk_3, "once", tmp_path), backend)
    assert (tmp_path / "died").exists()
    assert np.array_equal(_squares(results), np.arange(60) ** 2)
    with pytest.raises(ChunkFailedError) as err:
        run_job(_squares_job(faults.always_dies_on_chunk_3, "always", tmp_path), backend)
    assert err.value.chunk == 3 and err.value.attempts == 2


def test_a_chunk_that_raises_is_retried_on_its_living_actor(local_ray: None,
                                                            tmp_path: Path) -> None:
    results, _ = run_job(_squares_job(faults.raises_once_on_chunk_3, "raises", tmp_path),
                         jobs.backend_for(2, "auto"))
    assert (tmp_path / "raised").exists()
    assert np.array_equal(_squares(results), np.arange(60) ** 2)


def test_more_workers_than_free_cpus_are_capped_and_said(
        local_ray: None, tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    backend = jobs.backend_for(4, "auto")
    begin = time.perf_counter()
    with caplog.at_level(logging.WARNING, logger="usar_arm.workspace"):
        results, stats = run_job(_squares_job(faults.square, "capped", tmp_path, 12), backend)
    assert np.array_equal(_squares(results), np.arange(120) ** 2)
    assert stats.workers == 2 and stats.backend.startswith("2 Ray actors")
    assert "4 Ray actors asked for" in caplog.text and "2 CPUs free" in caplog.text
    assert time.perf_counter() - begin < 60


def test_an_actor_that_cannot_start_is_named_within_its_timeout(
        local_ray: None, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Four actors on 2 CPUs, as when another job takes the CPUs between the count and the
    actors' placement: two can never be scheduled, and the run must not wait forever."""
    monkeypatch.setattr(RayBackend, "_actor_count", lambda self: 4)
    backend = RayBackend("auto", 4, start_timeout=5.0)
    begin = time.perf_counter()
    with pytest.raises(ClusterUnavailableError, match=r"actor \d of 4 was not ready within 5 s"):
        run_job(_squares_job(faults.square, "stuck", tmp_path, 40), backend)
    assert time.perf_counter() - begin < 5.0 + 10.0
    deadline = time.monotonic() + 10.0  # its actors were killed (Ray frees their CPUs soon)
    while ray.available_resources().get("CPU") != 2 and time.monotonic() < deadline:
        time.sleep(0.1)
    assert ray.available_resources().get("CPU") == 2


def test_before_it_connects_the_backend_does_not_claim_zero_actors() -> None:
    assert "0 Ray" not in RayBackend("10.255.255.1:6379").describe()
    assert RayBackend("h:6379", 3).describe().startswith("3 Ray actors (at most one per")
    assert RayBackend("local").describe() == ("Ray actors (one per free CPU) on a fresh local "
                                              "Ray instance")
    with pytest.raises(ClusterUnavailableError, match="HOST:PORT"):
        RayBackend("nonsense")


def test_a_refused_address_is_reported_at_once() -> None:
    backend = jobs.backend_for(None, "127.0.0.1:1", timeout=1.0)
    begin = time.perf_counter()
    with pytest.raises(ClusterUnavailableError) as err:
        backend.start()
    assert time.perf_counter() - begin < 2.0
    assert "127.0.0.1:1" in str(err.value) and "1 s" in str(err.value)


def test_an_address_that_accepts_tcp_but_is_no_ray_head_fails_within_the_timeout(
        tmp_path: Path) -> None:
    """This network answers TCP on any address (a proxy), so only Ray's own attempts to reach
    a GCS can tell; they are bounded by --ray-timeout. In a fresh process: this one may
    already be connected to the module's local Ray."""
    command = [str(Path(sys.executable).parent / "usar-arm"), "reach", "--urdf", URDF,
               "--out", str(tmp_path), "--ray", "10.255.255.1:6379", "--ray-timeout", "1"]
    plain = {k: v for k, v in os.environ.items() if not k.startswith("RAY_AUTH")}  # (Ray's
    begin = time.perf_counter()  # in-process start of the module's instance sets token mode)
    done = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False,
                          env=plain)
    took = time.perf_counter() - begin
    assert done.returncode == EXIT_UNAVAILABLE, done.stderr[-2000:]
    assert "10.255.255.1:6379" in done.stderr and "waited 1 s" in done.stderr
    assert "RAY_AUTH_MODE=token" in done.stderr  # (the port answered: it may be a token head)
    assert took < 12.0  # measured 4.6 s with start-up; Ray left unbounded waits 20 s
    assert not (tmp_path / "reach.npz").exists()


@pytest.mark.slow
def test_a_head_with_token_authentication_is_joined_in_token_mode_and_named_without(
        tmp_path: Path) -> None:
    """A head started by ``ray start`` with token authentication (a token of its own, a
    temporary folder of its own, so no other test's ``auto`` finds it): a command not in token
    mode is refused with the setting it lacks named, one in token mode joins it."""
    bin_dir = Path(sys.executable).parent
    token = tmp_path / "token"
    token.write_text("usar-arm-test-" + "0123456789abcdef" * 2)
    env = {**os.environ, "RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN_PATH": str(token)}
    env.pop("RAY_ADDRESS", None)
    port = _free_port()
    with tempfile.TemporaryDirectory(prefix="ray", dir="/tmp") as temp:  # (short: sockets)
        head = subprocess.Popen(
            [str(bin_dir / "ray"), "start", "--head", "--block", f"--port={port}",
             "--num-cpus=1", "--include-dashboard=false", f"--temp-dir={temp}"],
            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            _wait_for_port(port, head, 180.0)
            command = [str(bin_dir / "usar-arm"), "reach", "--urdf", URDF, *SMALL, "-q",
                       "--ray", f"127.0.0.1:{port}", "--ray-timeout", "3"]
            plain = {k: v for k, v in env.items() if not k.startswith("RAY_AUTH")}
            refused = subprocess.run([*command, "--out", str(tmp_path / "refused")], env=plain,
                                     capture_output=True, text=True, timeout=180, check=False)
            assert refused.returncode == EXIT_UNAVAILABLE, refused.stderr[-2000:]
            assert "RAY_AUTH_MODE=token" in refused.stderr.strip().splitlines()[-1]
            assert not (tmp_path / "refused" / "reach.npz").exists()
            joined = subprocess.run([*command, "--out", str(tmp_path / "joined")], env=env,
                                    capture_output=True, text=True, timeout=300, check=False)
            assert joined.returncode == 0, joined.stderr[-2000:]
            assert (tmp_path / "joined" / "reach.npz").exists()
        finally:
            head.terminate()  # (--block: the head stops its cluster's processes on SIGTERM)
            head.wait(timeout=120)


def _wait_for_port(port: int, process: subprocess.Popen[bytes], limit: float) -> None:
    """Until something listens on ``port`` of this host (at most ``limit`` s)."""
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        assert process.poll() is None, f"ray start exited with {process.returncode}"
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1.0).close()
            return
        except OSError:
            time.sleep(0.5)
    raise AssertionError(f"nothing listened on port {port} within {limit:g} s")
