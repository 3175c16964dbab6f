"""The KR60's effectors on ROS 1 (`usar-arm ros --ros1`, the embedded simulator): actionlib's
SimpleActionClient drives the vacuum through control_msgs/GripperCommandAction (a malformed
goal REJECTED, as ROS 1's controllers reject), the seed's usarsim_inf status topics follow the
EFF lines and the command topic SETs; the generated types hash as Noetic's control_msgs 1.5."""

from __future__ import annotations

import json
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.ros1.helpers import ROOT, Master, Node, session
from usar_arm.ros import ros1_setup

NOETIC_MD5 = {
    "GripperCommand": "680acaff79486f017132a7f198d40f08",
    "GripperCommandAction": "950b2a6ebe831f5d4f4ceaba3d8be01e",
    "GripperCommandGoal": "86fd82f4ddc48a4cb6856cfa69217e43",
    "GripperCommandResult": "e4cbff56d3562bcf113da5a5adeef91f",
    "GripperCommandFeedback": "e4cbff56d3562bcf113da5a5adeef91f",
}
"""The MD5 sums of Noetic's control_msgs 1.5 GripperCommand types."""

CLIENT = r'''
import json, time
import actionlib, rospy
from actionlib_msgs.msg import GoalStatus
from control_msgs.msg import GripperCommandAction, GripperCommandGoal
from usarsim_inf.msg import EffectorCommand, EffectorStatus, ToolchangerStatus

rospy.init_node("effector_client", anonymous=True)
got = {"gripper": [], "changer": []}
rospy.Subscriber("KR60gripper/status", EffectorStatus,
                 lambda m: got["gripper"].append((m.header.frame_id, m.state)))
rospy.Subscriber("toolchange/status", ToolchangerStatus,
                 lambda m: got["changer"].append((m.effector_status.state, m.tool_type.type,
                                                  m.tool_name)))
client = actionlib.SimpleActionClient("KR60gripper/gripper_cmd", GripperCommandAction)
assert client.wait_for_server(rospy.Duration(60))
out = {}
for label, position in (("close", 1.0), ("malformed", 2.0), ("open", 0.0)):
    goal = GripperCommandGoal()
    goal.command.position = position
    client.send_goal(goal)
    assert client.wait_for_result(rospy.Duration(10))
    r = client.get_result()
    out[label] = [client.get_state(), r.position, r.reached_goal, r.stalled]
    if label == "close":
        time.sleep(0.5)
        out["status_after_close"] = got["gripper"][-1]
command = rospy.Publisher("KR60gripper/command", EffectorCommand, queue_size=2)
deadline = time.monotonic() + 10
while command.get_num_connections() == 0 and time.monotonic() < deadline:
    time.sleep(0.05)
got["gripper"].clear()
command.publish(EffectorCommand(state=EffectorCommand.CLOSE))
deadline = time.monotonic() + 5
while not any(s == 1 for _, s in got["gripper"]) and time.monotonic() < deadline:
    time.sleep(0.05)
out["after_command"] = got["gripper"][-1] if got["gripper"] else None
out["changer"] = got["changer"][-1]
out["REJECTED"], out["SUCCEEDED"] = GoalStatus.REJECTED, GoalStatus.SUCCEEDED
print(json.dumps(out))
'''


@pytest.fixture(scope="module")
def kr60(ros1_env: ros1_setup.Ros1Environment, tmp_path_factory: pytest.TempPathFactory
         ) -> Iterator[tuple[Master, Node, Path]]:
    folder = tmp_path_factory.mktemp("ros1-effectors")
    with session(ros1_env, folder, ["-v"]) as (master, node):
        yield master, node, folder


def _ros1(master: Master, code: str) -> dict:
    done = subprocess.run([str(master.ros1.python), "-c", code], capture_output=True,
                          text=True, timeout=120, env=master.env(), check=False, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    return dict(json.loads(done.stdout.strip().splitlines()[-1]))


def test_the_gripper_command_types_are_noetics_on_the_wire(kr60) -> None:
    master, _, _ = kr60
    assert _ros1(master, "import json, control_msgs.msg as c\n"
                         f"print(json.dumps({{n: getattr(c, n)._md5sum for n in "
                         f"{list(NOETIC_MD5)!r}}}))") == NOETIC_MD5


def test_actionlib_drives_the_vacuum_and_the_seeds_topics_follow(kr60) -> None:
    master, node, _ = kr60
    out = _ros1(master, CLIENT)
    succeeded, rejected = out["SUCCEEDED"], out["REJECTED"]
    assert out["close"] == [succeeded, 1.0, True, False], node.text()[-2000:]  # nothing held
    assert out["status_after_close"] == ["KR60gripper", 1]
    assert out["malformed"][0] == rejected and out["malformed"][2] is False
    assert out["open"] == [succeeded, 0.0, True, False]
    assert out["after_command"] == ["KR60gripper", 1]  # the command topic's CLOSE
    assert out["changer"] == [1, 1, "KR60gripper"]  # CLOSE, ToolType Gripper, its tool
