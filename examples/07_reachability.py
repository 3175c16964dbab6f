"""Where can the KR60 reach, and where should it stand for a cell's six targets?

A coarse reachability map (25 cm voxels, 32 orientations) of the checked-in description in the
table scene, on two local worker processes; then the best base for the targets of
examples/workspace/table-targets.yaml. The commands `usar-arm reach` and `usar-arm place` do the
same with pictures and files.
"""

from pathlib import Path

import numpy as np

from usar_arm import Arm
from usar_arm.planning.scene_file import load_scene
from usar_arm.workspace import PlaceSettings, ReachSettings, jobs, load_targets

HERE = Path(__file__).resolve().parent

if __name__ == "__main__":  # (worker processes must not run this on import)
    arm = Arm.from_files(HERE.parent / "robots/generated/KR60.urdf")
    table = load_scene("table")
    backend = jobs.backend_for(workers=2)
    run = jobs.reach_map(arm.robot, table, ReachSettings(resolution=0.25, orientations=32),
                         backend)
    m = run.map
    print(f"{int((m.index > 0).sum())} of {len(run.plan.voxels)} voxels within reach are "
          f"reached; {run.plan.queries:,} queries in {run.stats.seconds:.1f} s")
    above_part = np.array([[1.45, -0.45, 1.0]])
    print(f"index above the part: {m.lookup(above_part)[0]:.2f}")

    targets = load_targets(HERE / "workspace/table-targets.yaml")
    found = jobs.place(arm.robot, table, targets, PlaceSettings(step=0.4, yaw_steps=4), backend)
    best = found.best
    c = found.candidates
    print(f"best base: x {c.x[best]:.2f} m, y {c.y[best]:.2f} m, "
          f"yaw {np.degrees(c.yaw[best]):.0f} deg, score {found.ranking.score[best]:.3f}")
