"""Exports of plans and executions to formats other tools read (ROS 2 bags)."""
