"""Compile every numba kernel of the geometric core once, so that no command pays for it.

numba caches machine code on disk beside each module (``__pycache__``); ``make demo`` and
``make test`` run :func:`warm_up` right after installing, and :meth:`usar_arm.Arm.connect` runs
it before it starts the embedded simulator (a no-op when the cache is there):
``python -c "from usar_arm.planning.compiled import warm_up; warm_up()"``.
"""

from __future__ import annotations

from usar_arm.planning import bounds, bounds_walk, ik_kernel, lm_kernel, plan_kernel, ur_kernel


def warm_up() -> None:
    """Compile (or load from the cache) the collision, planning and IK kernels."""
    bounds.warm_up()
    bounds_walk.warm_up()
    plan_kernel.warm_up()
    ik_kernel.warm_up()
    lm_kernel.warm_up()
    ur_kernel.warm_up()
