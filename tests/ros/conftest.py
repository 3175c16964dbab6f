"""The ROS 2 tests: each module skips (with the reason) only where the ros extra is not
installed; where it is, the message packages are built once for the whole run (a lock
serialises the xdist workers: the first builds, about 40 s on 2 cores, the others find it)."""

from __future__ import annotations

import importlib.util

if importlib.util.find_spec("rclpy") is not None:
    from usar_arm.ros.build import ensure_importable, setup

    setup()
    ensure_importable()  # the test modules import tf2_msgs and control_msgs
