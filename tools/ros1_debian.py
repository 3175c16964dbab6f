"""Install Debian's ROS 1 and the tools that judge the ROS 1 node, where this machine allows.

    python tools/ros1_debian.py [--check]

`make test` runs it before the suite: as root with apt-get (CI, a fresh Debian 12), it installs
what is missing with `apt-get install -y --no-install-recommends` (about 360 MB, 30-60 s, once);
elsewhere it says in one line why not and the tests of tests/ros1 skip, naming the command.
``--check`` only says what is missing (exit 1 when something is). The package lists are
usar_arm.ros.ros1_setup's (NODE_NEEDS: the node; TOOLS_NEED: robot_state_publisher, RViz,
rosbag, view_frames, Xvfb, ImageMagick, Tesseract).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys

from usar_arm.ros.ros1_setup import NODE_NEEDS, TOOLS_NEED, apt_command, missing

NEEDS = NODE_NEEDS + TOOLS_NEED


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="only say what is missing")
    args = parser.parse_args()
    absent = missing(NEEDS)
    if not absent:
        print("ROS 1 (Debian's) and its tools: installed")
        return 0
    if args.check:
        print(f"ROS 1: missing {', '.join(absent)}: {apt_command(NEEDS)}")
        return 1
    apt = shutil.which("apt-get")
    if apt is None or os.geteuid() != 0:
        why = "no apt-get here" if apt is None else "not root"
        print(f"ROS 1 not installed ({why}); the ROS 1 tests will skip. To run them: "
              f"sudo {apt_command(NEEDS)}")
        return 0
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    print(f"ROS 1: installing {', '.join(absent)} (once)", flush=True)
    subprocess.run([apt, "update", "-qq"], check=True, env=env)
    subprocess.run([*apt_command(NEEDS).split(), "-qq"], check=True, env=env,
                   stdout=subprocess.DEVNULL)
    still = missing(NEEDS)
    if still:
        print(f"ROS 1: still missing {', '.join(still)} after apt-get install")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
