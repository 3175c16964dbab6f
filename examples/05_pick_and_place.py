"""A pick-and-place, as `usar-arm demo` runs it: the part and the bin created through the
WorldController, the part picked by the vacuum where the simulator says it is, carried around
the tower as an attached object and let go in the bin, each move planned in the scene the
simulator reports, executed and measured; the simulator then judges where the part came to
rest, and a picture and a rosbag2 of the whole cycle are written.
"""

from pathlib import Path
from tempfile import mkdtemp

from usar_arm import Arm
from usar_arm.arm.cell_session import CellSession
from usar_arm.arm.cycle import pick_and_place, tcp_offset
from usar_arm.arm.pick_place import run_pick_place
from usar_arm.export.bag import write_bag
from usar_arm.export.render import render_arm, tool_path

with Arm.connect("KR60") as arm:
    assert arm.client is not None
    with CellSession(arm.client.host, arm.client.port, "table") as cell:
        cell.build()  # CONTROL Create of the part and the bin, each confirmed by GetSTA
        part = cell.pose("part")
        assert part is not None
        moves = pick_and_place(arm.home, tcp_offset(arm.robot), (part[0, 3], part[1, 3]))
        done = run_pick_place(arm, cell, moves)

print(f"{'move':<9} {'type':<4} {'motion s':>8} {'tool0 mm':>8}")
for row in done.cycle.rows():
    print(f"{row['move']:<9} {row['motion'].upper():<4} {row['duration_s']:>8.2f} "
          f"{row['true_tip_error_m'] * 1000:>8.2f}")
print(done.placement.line())

# One timeline for the whole cycle: the planned moves where they started, and the ASTA feedback.
cycle, executed = done.cycle.timeline()

folder = Path(mkdtemp(prefix="pick-and-place-"))
chain = arm.robot.chain
render_arm(folder / "cycle.png", done.carrying_chain or chain, done.carried_goals[0],
           done.scenes["end"], tool_path(chain, cycle))
bag = write_bag(folder / "cycle.bag", chain, arm.urdf, cycle, executed)
print("wrote", folder / "cycle.png", "and", bag.path, dict(bag.topics))
