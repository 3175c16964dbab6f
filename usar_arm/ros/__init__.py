"""The live ROS 2 interface (``usar-arm ros``, docs/ros.md).

* :mod:`.build`: builds the message packages the package index lacks into a cache (no rclpy);
* :mod:`.goals`, :mod:`.frames`, :mod:`.runner`: the driver's rules as plain Python (goal
  checks, the transform tree, running goals on usar-arm's executor);
* :mod:`.node`: the only module that imports rclpy and ROS message packages.
"""
