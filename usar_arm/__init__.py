"""usar-arm: learn a USARSim robot arm over the wire, describe it, plan and move it."""

__version__ = "0.1.0"
