"""The install's warm-up compiles every kernel signature a plan uses, so that no command pays for
compiling (the demo's first plan once took 7 s: the collision world handed its lever arms over
read-only, a type the warm-up never compiled; then 3.3-3.9 s: its start configuration came
read-only to the single-query kernel). The UR5's closed form (:mod:`usar_arm.planning.ur_kernel`)
is warmed up too."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PROBE = """
import json
import numpy as np
from usar_arm.planning import bounds, bounds_walk, ik_kernel, lm_kernel, plan_kernel, ur_kernel
from usar_arm.planning.compiled import warm_up
warm_up()
kernels = {name: getattr(bounds, name) for name in ("check", "summary")}
kernels["walk"] = bounds_walk.walk
kernels.update({f"plan_kernel.{n}": getattr(plan_kernel, n) for n in ("search", "shortcut")})
for module in (ik_kernel, lm_kernel, ur_kernel):
    kernels.update({f"{module.__name__}.{n}": getattr(module, n) for n in dir(module)
                    if hasattr(getattr(module, n), "signatures")})
before = {name: set(map(str, k.signatures)) for name, k in kernels.items()}
from usar_arm import Arm
arm = Arm.from_files("robots/generated/KR60.urdf")
arm.ik(arm.fk(np.array([0.3, -0.5, 0.4, 0.0, 0.5, 0.0])), seed=arm.home)
arm.plan(joints=np.array([0.3, -0.5, 0.4, 0.0, 0.5, 0.0]), scene="table")
arm.plan(joints=np.array([0.2, -0.3, 0.5, 0.1, 0.4, 0.0]), scene="table", motion="lin")
start = np.array([0.2, -0.3, 0.5, 0.1, 0.4, 0.0])
start.setflags(write=False)  # as a frozen reading or home comes (the demo's first move)
arm.plan(joints=np.array([0.3, -0.5, 0.4, 0.0, 0.5, 0.0]), start=start, scene="table")
ur = "examples/robots/example-robot-data/robots/ur_description/"
ur5 = Arm.from_files(ur + "urdf/ur5_robot.urdf", srdf=ur + "srdf/ur5.srdf", tip="ee_link")
pose = ur5.fk(np.array([0.3, -1.0, 1.2, 0.4, 0.9, 0.7]))
previous = ur5.ik(pose, seed=np.array([0.2, -1.1, 1.1, 0.3, 0.8, 0.6])).best.q
ur5.ik(ur5.fk(np.array([0.2, -1.0, 1.1, 0.4, 0.9, 0.7])), seed=previous)  # a read-only seed
arm.ik(arm.fk(np.array([0.2, -0.5, 0.4, 0.0, 0.5, 0.0])), seed=previous)
ur5.ik(pose, all_solutions=True)
print(json.dumps({name: sorted(set(map(str, k.signatures)) - before[name])
                  for name, k in kernels.items()}))
"""


def test_a_plan_after_the_warm_up_compiles_nothing_new() -> None:
    done = subprocess.run([sys.executable, "-c", PROBE], cwd=ROOT, capture_output=True,
                          text=True, timeout=600, check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    new = {name: sigs for name, sigs in json.loads(done.stdout.splitlines()[-1]).items() if sigs}
    assert new == {}, f"compiled at first use, not by the warm-up: {new}"


def test_a_changed_kernel_source_drops_the_compiled_caches(tmp_path: Path) -> None:
    """numba keys a cache by its own module's file only, and the kernels inline other modules'
    helpers: a change to any kernel source must drop every cached kernel."""
    from usar_arm.planning.jit import drop_stale_caches

    folders = (tmp_path / "planning", tmp_path / "workspace")
    for folder in folders:
        (folder / "__pycache__").mkdir(parents=True)
        (folder / "kernels.py").write_text("from usar_arm.planning.jit import kernel\n")
        (folder / "__pycache__" / "kernels.f-1.py311.nbi").write_bytes(b"index")
        (folder / "__pycache__" / "kernels.f-1.py311.1.nbc").write_bytes(b"code")
    (folders[0] / "other.py").write_text("print('no kernel here')\n")

    def cached() -> int:
        return sum(len(list(f.glob("__pycache__/*.nb[ic]"))) for f in folders)

    assert drop_stale_caches(folders) and cached() == 0  # (no stamp yet: dropped, stamped)
    (folders[1] / "__pycache__" / "kernels.f-1.py311.nbi").write_bytes(b"index")
    assert not drop_stale_caches(folders) and cached() == 1  # same sources: kept
    (folders[0] / "other.py").write_text("print('still no kernel')\n")
    assert not drop_stale_caches(folders) and cached() == 1  # not a kernel source
    (folders[1] / "kernels.py").write_text("from usar_arm.planning.jit import kernel  # new\n")
    assert drop_stale_caches(folders) and cached() == 0
