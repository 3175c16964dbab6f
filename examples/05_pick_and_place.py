"""A pick-and-place cycle, as `usar-arm demo` runs it: seven PTP and LIN moves in the table
scene, each planned from where the arm really is, executed and measured; then a picture and a
rosbag2 of the whole cycle.
"""

from pathlib import Path
from tempfile import mkdtemp

from usar_arm import Arm
from usar_arm.arm.cycle import pick_and_place, run_cycle, tcp_offset
from usar_arm.export.bag import write_bag
from usar_arm.export.render import render_arm, tool_path
from usar_arm.planning.scene_file import load_scene

with Arm.connect("KR60") as arm:
    moves = pick_and_place(arm.home, tcp_offset(arm.robot))
    result = run_cycle(arm, moves, scene="table")

print(f"{'move':<9} {'type':<4} {'motion s':>8} {'tool0 mm':>8}")
for row in result.rows():
    print(f"{row['move']:<9} {row['motion'].upper():<4} {row['duration_s']:>8.2f} "
          f"{row['true_tip_error_m'] * 1000:>8.2f}")

# One timeline for the whole cycle: the planned moves where they started, and the ASTA feedback.
cycle, executed = result.timeline()

folder = Path(mkdtemp(prefix="pick-and-place-"))
chain = arm.robot.chain
render_arm(folder / "cycle.png", chain, arm.home, load_scene("table"), tool_path(chain, cycle))
bag = write_bag(folder / "cycle.bag", chain, arm.urdf, cycle, executed)
print("wrote", folder / "cycle.png", "and", bag.path, dict(bag.topics))
