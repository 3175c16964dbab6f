"""Base placement ranks the same whatever runs its chunks: in this process or on 2 workers."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from usar_arm.planning.robot import Robot
from usar_arm.planning.scene_file import load_scene
from usar_arm.workspace import jobs
from usar_arm.workspace.placement import PlaceSettings
from usar_arm.workspace.targets import load_targets

REPO = Path(__file__).resolve().parents[2]


def test_place_gives_the_same_ranking_with_0_and_2_workers(kr60: Robot) -> None:
    targets = load_targets(REPO / "examples" / "workspace" / "table-targets.yaml")
    scene = load_scene("table")
    settings = PlaceSettings(step=0.4, yaw_steps=4, chunk_candidates=16)  # several chunks
    here = jobs.place(kr60, scene, targets, settings, jobs.backend_for(0))
    pool = jobs.place(kr60, scene, targets, settings, jobs.backend_for(2))
    assert here.stats.chunks_run > 2 and pool.stats.workers == 2
    assert len(here.ranking.order) > 10  # a ranking worth comparing
    assert np.array_equal(here.ranking.order, pool.ranking.order)
    assert np.array_equal(here.ranking.score, pool.ranking.score)
    assert np.array_equal(here.ranking.margins, pool.ranking.margins)
    assert here.best == pool.best
    for (q0, m0), (q2, m2) in zip(here.solutions, pool.solutions, strict=True):
        assert np.array_equal(q0, q2) and np.array_equal(m0, m2)
