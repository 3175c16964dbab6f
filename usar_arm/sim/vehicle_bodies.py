"""A ground vehicle's bodies in the simulator's world: a free chassis on driven, steered wheels
(:mod:`usar_arm.sim.vehicle` holds its data; :mod:`usar_arm.sim.drive_gains` the gains)."""

from __future__ import annotations

from typing import Any

from usar_arm.sim import mj
from usar_arm.sim.drive_gains import (
    STEER_KP,
    STEER_SIZE,
    WHEEL_DAMPING,
    WHEEL_FRICTION,
    WHEEL_KV,
)
from usar_arm.sim.physics_index import RobotEntry, VehicleIndex
from usar_arm.sim.scenery import VEHICLE_BIT, quat
from usar_arm.sim.vehicle import VehicleSpec


def add_vehicle(spec: mj.Spec, entry: RobotEntry, veh: VehicleSpec, floor_z: float
                 ) -> VehicleIndex:
    """A free chassis on its wheels: boxes and bumper masses on one body, one hinge per wheel
    (positive spin forward; a steered one on a position-driven knuckle) driven within MaxForce.

    The chassis is placed no lower than resting on the floor (INIT's z is the chassis
    origin, as UDK's CenterItem location)."""
    loc = list(entry.location)
    loc[2] = min(loc[2], floor_z - veh.rest_height)
    name = f"{entry.key}/platform"
    body = spec.worldbody.add_body(name=name, pos=loc, quat=quat(entry.platform_pose[:3, :3]))
    body.add_freejoint(name=f"{name}/free")
    for box in veh.chassis:
        body.add_geom(type=mj.BOX, size=list(box.half),
                      pos=list(box.center), mass=box.mass, contype=VEHICLE_BIT,
                      conaffinity=0)
    for _, offset, mass in veh.extra_masses:
        body.add_geom(type=mj.SPHERE, size=[0.01, 0, 0], pos=list(offset),
                      mass=mass, contype=0, conaffinity=0)
    joints: dict[str, str] = {}
    steers: dict[str, str] = {}
    for w in veh.wheels:
        holder, at = body, list(w.offset)
        if w.steer is not None:  # a knuckle turning about z (down: positive turns right)
            s = w.steer
            holder, at = body.add_body(name=f"{name}/{s.name}", pos=at), [0.0, 0.0, 0.0]
            steers[s.name] = f"{name}/{s.name}/steer"
            holder.add_joint(name=steers[s.name], type=mj.HINGE,
                             axis=[0.0, 0.0, 1.0], range=[s.limit_low, s.limit_high],
                             limited=True)
            holder.add_geom(type=mj.SPHERE, size=[STEER_SIZE, 0, 0],
                            mass=s.mass, contype=0, conaffinity=0)
            add_drive(spec, steers[s.name], s.max_force).set_to_position(kp=STEER_KP,
                                                                      kv=s.damping)
        wheel = holder.add_body(name=f"{name}/{w.name}", pos=at)
        jname = f"{name}/{w.name}/spin"
        wheel.add_joint(name=jname, type=mj.HINGE, axis=[0.0, -1.0, 0.0],
                        damping=WHEEL_DAMPING)
        wheel.add_geom(type=mj.SPHERE, size=[veh.wheel_radius, 0, 0],
                       mass=w.mass, contype=VEHICLE_BIT, conaffinity=0,
                       friction=[WHEEL_FRICTION, 0.005, 0.0001])
        if w.driven:
            add_drive(spec, jname, w.max_force).set_to_velocity(kv=WHEEL_KV)
        joints[w.name] = jname
    return VehicleIndex(veh, name, joints, steers)


def add_drive(spec: mj.Spec, joint: str, max_force: float) -> Any:
    """A joint's actuator ``<joint>/drive``, its force limited to +-``max_force``."""
    drive = spec.add_actuator(name=f"{joint}/drive", target=joint,
                              trntype=mj.TRN_JOINT)
    drive.forcelimited = True
    drive.forcerange = [-max_force, max_force]
    return drive


def index_vehicle(m: mj.Model, d: mj.Data, veh: VehicleIndex, ctrl: dict[str, float]) -> None:
    """Find a vehicle's addresses in a rebuilt model (its joints' state is carried over by
    name with every other's) and its drives' targets."""
    veh.body_id = mj.name_id(m, "body", veh.body)
    veh.wheel_qpos, veh.wheel_ctrl, veh.steer_qpos, veh.steer_ctrl = {}, {}, {}, {}
    for joints, at, drives in ((veh.wheel_joints, veh.wheel_qpos, veh.wheel_ctrl),
                               (veh.steer_joints, veh.steer_qpos, veh.steer_ctrl)):
        for part, jname in joints.items():
            j = mj.name_id(m, "joint", jname)
            at[part] = int(m.jnt_qposadr[j])
            a = mj.name_id(m, "actuator", f"{jname}/drive")
            if a >= 0:
                drives[part] = a
                d.ctrl[a] = ctrl.get(f"{jname}/drive", 0.0)
