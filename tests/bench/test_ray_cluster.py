"""The benchmark's own Ray cluster is stopped without stopping anyone else's: ``ray stop`` once
killed the Ray instance of a test session running beside the benchmark, and its test worker."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

import ray_cluster  # noqa: E402

BYSTANDER = """
import sys, ray
ray.init(address="local", num_cpus=1, include_dashboard=False, log_to_driver=False)
square = ray.remote(lambda x: x * x)
print("up", flush=True)
for line in sys.stdin:
    print(ray.get(square.remote(int(line))), flush=True)
"""


@pytest.mark.slow
def test_the_benchmarks_cluster_stops_alone_and_another_instance_keeps_working() -> None:
    bystander = subprocess.Popen([sys.executable, "-c", BYSTANDER], stdin=subprocess.PIPE,
                                 stdout=subprocess.PIPE, text=True)
    try:
        assert bystander.stdout is not None and bystander.stdin is not None
        assert bystander.stdout.readline().strip() == "up"
        theirs = ray_cluster.processes_of([f"{bystander.pid}"])  # (its session folder's name)
        with ray_cluster.own_cluster(1) as marks:
            ours = ray_cluster.processes_of(marks)
            assert len(ours) >= 3, "the head's GCS, raylet and agents were not found"
            assert not ours & theirs
        assert not ray_cluster.processes_of(marks), "a process of the cluster survived"
        assert not [p for p in ours if Path(f"/proc/{p}").exists()]
        bystander.stdin.write("7\n")
        bystander.stdin.flush()
        assert bystander.stdout.readline().strip() == "49"  # still working
    finally:  # (end of input: it leaves, and its instance stops with it)
        if bystander.stdin is not None:
            bystander.stdin.close()
        try:
            bystander.wait(60)
        except subprocess.TimeoutExpired:
            bystander.kill()
            bystander.wait(30)
