"""usar-arm: learn a USARSim robot arm over the wire, describe it, plan and move it.

The library's front door is :class:`usar_arm.Arm` (see ``examples/``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"
__all__ = ["Arm", "__version__"]

if TYPE_CHECKING:
    from usar_arm.arm import Arm


def __getattr__(name: str) -> Any:
    # Imported lazily: `import usar_arm` stays light for tools that only need a submodule.
    if name == "Arm":
        from usar_arm.arm import Arm

        return Arm
    raise AttributeError(f"module 'usar_arm' has no attribute '{name}'")
