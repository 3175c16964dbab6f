"""The gains of the embedded simulator's vehicle drives: wheel spin and steer (MuJoCo units).

UDK's PhysX drives are springs of stiffness MaxForce (50000 by default) with the joint's
Damping; MuJoCo at 1 ms steps needs softer numbers for the vehicles' light wheels, chosen and
measured here. :mod:`usar_arm.sim.physics` builds the drives with them.
"""

from __future__ import annotations

WHEEL_KV = 20.0
"""Gain (N·m per rad/s) of a wheel's velocity drive, within the wheel's MaxForce: stiff enough
that a wheel keeps within 5 % of the speed DRIVE gives it while the tyres slide sideways in a
skid turn, soft enough that a start from rest does not rock the chassis. Measured at 1.3 rad/s:
turning in place, 2 N·m per rad/s let the wheels fall to 0.6-0.85 rad/s, 20 keeps them at
1.23-1.26 (50 at 1.27-1.28, but the chassis pitched 0.10 rad on starting, 0.018 at 20)."""
WHEEL_DAMPING = 0.001
"""Viscous friction of a wheel's axle (N·m·s/rad)."""
WHEEL_FRICTION = 1.0
"""Sliding friction coefficient between a wheel and the ground."""
STEER_KP = 1000.0
"""Stiffness (N·m/rad) of a steer joint's position drive. With the joint's Damping (50 on
FrontAckerman) as its damping, the steer settles with a time constant of Damping / STEER_KP
= 0.05 s and no overshoot; UDK's 50000 would make the spring too stiff for 1 ms steps on a
6 kg wheel and knuckle (the damping, not the spring, is integrated implicitly)."""
STEER_SIZE = 0.03
"""Radius (m) of the sphere that carries a steer knuckle's mass (it touches nothing)."""
