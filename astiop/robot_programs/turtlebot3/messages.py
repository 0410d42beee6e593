"""The TurtleBot3's messages as its own nodes fill them (plain dicts with the real field names).

- /battery_state: turtlebot3_node/src/sensors/battery_state.cpp — voltage in V, `percentage`
  0–100 (the OpenCR's register × 0.01, NOT the message's 0–1), design_capacity 1.8 (Ah),
  present = voltage > 7.0; current, charge, capacity and the status fields are left at 0.
- /odom and odom → base_footprint: turtlebot3_node/src/odometry.cpp — from the odometry origin
  (0, 0) where the node started, twist linear.x and angular.z only, covariances all 0.
- /scan: hls_lfcd_lds_driver/src/hlds_laser_publisher.cpp (LDS-01) — 360 beams counter-clockwise
  from 0 rad, range_min 0.12, range_max 3.5, a beam with no return is 0.0.
- /joint_states: sensors/joint_state.cpp — wheel_left_joint, wheel_right_joint; position in rad,
  velocity the wheels' surface speed.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from typing import Any

import numpy as np

from astiop.sim.messages import f32, quaternion

LDS01_BEAMS = 360
LDS01_RANGE_MIN, LDS01_RANGE_MAX = 0.12, 3.5
LDS01_RPM = 300  # 5 scans a second: time_increment = 1 / (rpm · 6)
DESIGN_CAPACITY_AH = 1.8


def header(frame: str) -> dict[str, Any]:
    return {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": frame}  # stamped when sent


def compose(a: tuple[float, float, float], b: tuple[float, float, float]):
    """Pose b (in a's frame) in the frame a is in."""
    ax, ay, ath = a
    bx, by, bth = b
    c, s = math.cos(ath), math.sin(ath)
    return (ax + c * bx - s * by, ay + s * bx + c * by, ath + bth)


def relative(origin: tuple[float, float, float], pose: tuple[float, float, float]):
    """`pose` expressed in the frame whose origin is `origin` (both in one frame)."""
    ox, oy, oth = origin
    dx, dy = pose[0] - ox, pose[1] - oy
    c, s = math.cos(oth), math.sin(oth)
    th = math.atan2(math.sin(pose[2] - oth), math.cos(pose[2] - oth))
    return (c * dx + s * dy, -s * dx + c * dy, th)


def _pose(x: float, y: float, th: float) -> dict[str, Any]:
    return {"position": {"x": x, "y": y, "z": 0.0}, "orientation": quaternion(th)}


def pose_stamped(frame: str, pose) -> dict[str, Any]:
    return {"header": header(frame), "pose": _pose(*pose)}


def transform(parent: str, child: str, pose: tuple[float, float, float]) -> dict[str, Any]:
    x, y, th = pose
    return {
        "header": header(parent),
        "child_frame_id": child,
        "transform": {"translation": {"x": x, "y": y, "z": 0.0}, "rotation": quaternion(th)},
    }


def odometry(frames, odom_pose, v: float, w: float) -> dict[str, Any]:
    return {
        "header": header(frames.odom),
        "child_frame_id": frames.base_footprint,
        "pose": {"pose": _pose(*odom_pose), "covariance": [0.0] * 36},
        "twist": {
            "twist": {
                "linear": {"x": v, "y": 0.0, "z": 0.0},
                "angular": {"x": 0.0, "y": 0.0, "z": w},
            },
            "covariance": [0.0] * 36,
        },
    }


def battery_state(voltage: float, soc: float) -> dict[str, Any]:
    # the OpenCR reports centivolts and centi-percent as integers
    volts = int(voltage * 100) * 0.01
    return {
        "header": header(""),
        "voltage": volts,
        "percentage": int(soc * 10000) * 0.01,
        "design_capacity": DESIGN_CAPACITY_AH,
        "present": volts > 7.0,
    }


def laser_scan(frame: str, sim_ranges: np.ndarray) -> dict[str, Any]:
    """The simulator's beams (from -π) re-indexed from 0 rad; inf (nothing in range) as 0.0."""
    inc = 2.0 * math.pi / LDS01_BEAMS
    ranges = np.roll(np.asarray(sim_ranges, dtype=float), -LDS01_BEAMS // 2)
    ranges = np.where(np.isfinite(ranges) & (ranges <= LDS01_RANGE_MAX), ranges, 0.0)
    ranges = np.round(ranges, 3)
    return {
        "header": header(frame),
        "angle_min": 0.0,
        "angle_max": f32(2.0 * math.pi - inc),
        "angle_increment": f32(inc),
        "time_increment": f32(1.0 / (LDS01_RPM * 6)),
        "scan_time": f32(360.0 / (LDS01_RPM * 6)),
        "range_min": LDS01_RANGE_MIN,
        "range_max": LDS01_RANGE_MAX,
        "ranges": [f32(r) for r in ranges.tolist()],
        "intensities": [0.0 if r == 0.0 else 1000.0 for r in ranges.tolist()],
    }


def joint_states(prefix: str, wheel_angles, wheel_speeds) -> dict[str, Any]:
    return {
        "header": header(f"{prefix}base_link"),
        "name": [f"{prefix}wheel_left_joint", f"{prefix}wheel_right_joint"],
        "position": [float(a) for a in wheel_angles],
        "velocity": [float(v) for v in wheel_speeds],
        "effort": [],
    }


def imu(frame: str, yaw: float, w: float) -> dict[str, Any]:
    return {
        "header": header(frame),
        "orientation": quaternion(yaw),
        "angular_velocity": {"x": 0.0, "y": 0.0, "z": w},
        "linear_acceleration": {"x": 0.0, "y": 0.0, "z": 9.81},
    }


def amcl_pose(frame: str, pose) -> dict[str, Any]:
    cov = [0.0] * 36
    cov[0] = cov[7] = 0.0025  # a converged filter: a few cm
    cov[35] = 0.0007
    return {"header": header(frame), "pose": {"pose": _pose(*pose), "covariance": cov}}


def path(frame: str, points) -> dict[str, Any]:
    poses = []
    for (x0, y0), (x1, y1) in zip(points, [*points[1:], points[-1]], strict=True):
        heading = math.atan2(y1 - y0, x1 - x0) if (x1, y1) != (x0, y0) else 0.0
        poses.append({"header": header(frame), "pose": _pose(x0, y0, heading)})
    return {"header": header(frame), "poses": poses}


def footprint(frame: str, radius: float, sides: int = 16) -> dict[str, Any]:
    """costmap_2d's footprint for a robot_radius: a circle as a polygon."""
    points = [
        {"x": f32(radius * math.cos(a)), "y": f32(radius * math.sin(a)), "z": 0.0}
        for a in np.linspace(0.0, 2.0 * math.pi, sides, endpoint=False)
    ]
    return {"header": header(frame), "polygon": {"points": points}}


def fixed_joints(urdf_xml: str) -> list[dict[str, Any]]:
    """/tf_static: the URDF's fixed joints, as robot_state_publisher sends them."""
    out = []
    for joint in ET.fromstring(urdf_xml).iter("joint"):
        if joint.get("type") != "fixed":
            continue
        origin = joint.find("origin")
        xyz = [
            float(v)
            for v in (origin.get("xyz", "0 0 0") if origin is not None else "0 0 0").split()
        ]
        rpy = [
            float(v)
            for v in (origin.get("rpy", "0 0 0") if origin is not None else "0 0 0").split()
        ]
        out.append(
            {
                "header": header(joint.find("parent").get("link")),
                "child_frame_id": joint.find("child").get("link"),
                "transform": {
                    "translation": dict(zip("xyz", xyz, strict=True)),
                    "rotation": rpy_quaternion(*rpy),
                },
            }
        )
    return out


def rpy_quaternion(roll: float, pitch: float, yaw: float) -> dict[str, float]:
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return {
        "x": sr * cp * cy - cr * sp * sy,
        "y": cr * sp * cy + sr * cp * sy,
        "z": cr * cp * sy - sr * sp * cy,
        "w": cr * cp * cy + sr * sp * sy,
    }
