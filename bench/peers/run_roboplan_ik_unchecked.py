"""roboplan's SimpleIk without its collision check (check_collisions=False), for the IK rows of
both modes: python run_roboplan_ik_unchecked.py PROBLEMS.json RESULTS.json (see
run_roboplan_ik.py)."""

import os
import runpy

os.environ["ROBOPLAN_IK_CHECK_COLLISIONS"] = "0"
runpy.run_path(os.path.join(os.path.dirname(os.path.abspath(__file__)), "run_roboplan_ik.py"),
               run_name="__main__")
