"""The simulator's state as ROS 2 messages (plain dicts with the real field names)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from astiop.distro import current_distro
from astiop.sim.battery import CAPACITY_AH
from astiop.sim.state import SimState


def stamp(t: float, frame: str) -> dict[str, Any]:
    sec = int(t)
    return {
        "stamp": {"sec": sec, "nanosec": int(round((t - sec) * 1e9)) % 1_000_000_000},
        "frame_id": frame,
    }


def f32(v: float) -> float:
    """A float32 field's value as rclpy gives it: the float32, widened to a Python float
    (27.117 prints as 27.117000579833984, as `ros2 topic echo` shows it)."""
    return float(np.float32(v))


def quaternion(yaw: float) -> dict[str, float]:
    return {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}


def _pose(x: float, y: float, th: float) -> dict[str, Any]:
    return {"position": {"x": x, "y": y, "z": 0.0}, "orientation": quaternion(th)}


def _cov(diag: float) -> list[float]:
    return [diag if i % 7 == 0 else 0.0 for i in range(36)]


def odometry(s: SimState) -> dict:
    return {
        "header": stamp(s.t, "odom"),
        "child_frame_id": "base_link",
        "pose": {"pose": _pose(s.x, s.y, s.theta), "covariance": _cov(0.001)},
        "twist": {
            "twist": {
                "linear": {"x": s.vx, "y": s.vy, "z": 0.0},
                "angular": {"x": 0.0, "y": 0.0, "z": s.wz},
            },
            "covariance": _cov(0.001),
        },
    }


def robot_pose(s: SimState) -> dict:
    return {"x": round(s.x, 4), "y": round(s.y, 4), "theta": round(s.theta, 4)}


def battery_state(s: SimState) -> dict:
    if s.battery_charging:
        status = 1
    elif s.docked and s.battery_soc >= 0.999:
        status = 4
    else:
        status = 2
    return {
        "header": stamp(s.t, "base_link"),
        "voltage": f32(s.battery_voltage),
        "temperature": 25.0,
        "current": f32(s.battery_current),
        "charge": f32(s.battery_soc * CAPACITY_AH),
        "capacity": CAPACITY_AH,
        "design_capacity": CAPACITY_AH,
        "percentage": f32(s.battery_soc),
        "power_supply_status": status,
        "power_supply_health": 1,
        "power_supply_technology": battery_technology(),
        "present": True,
        "cell_voltage": [],
        "cell_temperature": [],
        "location": "2x UCG22-12 VRLA in series",
        "serial_number": "",
    }


def battery_technology() -> int:
    """The ASTIbot's two 12 V lead-acid batteries: VRLA (8), a constant Jazzy's BatteryState
    has and Humble's does not (there: UNKNOWN, 0)."""
    return 0 if current_distro() == "humble" else 8


def robot_status(s: SimState) -> dict:
    return {
        "header": stamp(s.t, "base_link"),
        "state": s.state,
        "mode": s.mode,
        "active_goal": s.active_goal,
        "fault": s.fault,
        "speed": round(s.speed, 3),
        "e_stopped": s.e_stopped,
        "docked": s.docked,
    }


def laser_scan(s: SimState, spec) -> dict:
    return {
        "header": stamp(s.scan_stamp, "laser"),
        "angle_min": f32(spec.angle_min),
        "angle_max": f32(spec.angle_min + spec.angle_increment * (spec.beams - 1)),
        "angle_increment": f32(spec.angle_increment),
        "time_increment": 0.0,
        "scan_time": 1.0 / spec.rate_hz,
        "range_min": spec.range_min,
        "range_max": spec.range_max,
        "ranges": [f32(r) for r in np.round(s.scan_ranges, 4).tolist()],
        "intensities": [],
    }


def obstacle_array(s: SimState) -> dict:
    return {
        "header": stamp(s.scan_stamp, "base_link"),
        "count": len(s.detected),
        "obstacles": [
            {
                "kind": o.kind,
                "distance": round(o.distance, 3),
                "bearing": round(o.bearing, 3),
                "position": {"x": round(o.x, 3), "y": round(o.y, 3), "z": 0.0},
                "size": round(o.size, 3),
            }
            for o in s.detected
        ],
    }


def conveyor_status(s: SimState) -> dict:
    return {
        "header": stamp(s.t, "base_link"),
        "running": s.conveyor_direction != 0,
        "direction": s.conveyor_direction,
        "loaded": s.conveyor_loaded,
        "load_sensor_entry": s.sensor_entry,
        "load_sensor_seated": s.sensor_seated,
        "lamp": s.lamp,
    }


def path(s: SimState) -> dict:
    poses = [{"header": stamp(s.t, "map"), "pose": _pose(x, y, 0.0)} for x, y in s.plan]
    return {"header": stamp(s.t, "map"), "poses": poses}


def diagnostics(s: SimState) -> dict:
    def status(level, name, message, hw, values):
        return {
            "level": level,
            "name": name,
            "message": message,
            "hardware_id": hw,
            "values": [{"key": k, "value": str(v)} for k, v in values.items()],
        }

    motor_level = 2 if s.fault else 0
    wheels = {n: f"{w:.2f} rad/s" for n, w in zip(("FL", "FR", "RL", "RR"), s.wheel_speeds)}
    soc = s.battery_soc
    bat_level = 2 if soc < 0.1 else 1 if soc < 0.2 else 0
    return {
        "header": stamp(s.t, ""),
        "status": [
            status(motor_level, "astibot_base: motors", s.fault or "OK", "MD60 x4", wheels),
            status(
                0,
                "lidar_driver: lidar",
                "OK",
                "LsLiDAR M10",
                {"frequency": "10.0 Hz", "beams": len(s.scan_ranges)},
            ),
            status(
                bat_level,
                "battery_monitor: battery",
                "low" if bat_level else "OK",
                "UCG22-12 x2",
                {"percentage": f"{soc * 100:.1f} %", "voltage": f"{s.battery_voltage:.2f} V"},
            ),
            status(
                0,
                "conveyor_plc: conveyor",
                "loaded" if s.conveyor_loaded else "empty",
                "PLC",
                {"lamp": s.lamp},
            ),
        ],
    }


def tf(s: SimState) -> dict:
    def ts(parent, child, x, y, z, yaw):
        return {
            "header": stamp(s.t, parent),
            "child_frame_id": child,
            "transform": {"translation": {"x": x, "y": y, "z": z}, "rotation": quaternion(yaw)},
        }

    return {
        "transforms": [
            ts("map", "odom", 0.0, 0.0, 0.0, 0.0),
            ts("odom", "base_link", s.x, s.y, 0.0, s.theta),
        ]
    }


def tf_static(s: SimState) -> dict:
    def ts(child, x, z):
        return {
            "header": stamp(0.0, "base_link"),
            "child_frame_id": child,
            "transform": {"translation": {"x": x, "y": 0.0, "z": z}, "rotation": quaternion(0.0)},
        }

    return {"transforms": [ts("laser", 0.0, 0.45), ts("camera", 0.45, 0.5)]}


MAP_RESOLUTION = 0.2  # m per cell of the /map a robot serves


def occupancy_grid(warehouse) -> dict:
    """The warehouse's walls and racks as a nav_msgs/msg/OccupancyGrid (100: occupied)."""
    x0, y0, x1, y1 = warehouse.bounds
    w = int(math.ceil((x1 - x0) / MAP_RESOLUTION))
    h = int(math.ceil((y1 - y0) / MAP_RESOLUTION))
    cells = np.zeros((h, w), dtype=int)
    for _kind, (rx0, ry0, rx1, ry1) in warehouse.static_rects:
        c0, c1 = int((rx0 - x0) / MAP_RESOLUTION), int(math.ceil((rx1 - x0) / MAP_RESOLUTION))
        r0, r1 = int((ry0 - y0) / MAP_RESOLUTION), int(math.ceil((ry1 - y0) / MAP_RESOLUTION))
        cells[max(r0, 0) : r1, max(c0, 0) : c1] = 100
    return {
        "header": stamp(0.0, "map"),
        "info": {
            "map_load_time": {"sec": 0, "nanosec": 0},
            "resolution": MAP_RESOLUTION,
            "width": w,
            "height": h,
            "origin": {
                "position": {"x": x0, "y": y0, "z": 0.0},
                "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
            },
        },
        "data": cells.ravel().tolist(),
    }


def image(t: float, pixels: np.ndarray, frame: str = "camera") -> dict:
    """sensor_msgs/msg/Image of RGB pixels (height, width, 3): rgb8, rows top to bottom."""
    height, width = pixels.shape[:2]
    return {
        "header": stamp(t, frame),
        "height": height,
        "width": width,
        "encoding": "rgb8",
        "is_bigendian": 0,
        "step": width * 3,
        "data": np.ascontiguousarray(pixels, dtype=np.uint8).tobytes(),
    }


def compressed_image(t: float, pixels: np.ndarray, frame: str = "camera") -> dict:
    """sensor_msgs/msg/CompressedImage: the frame as PNG (lossless, and flat colours pack well),
    `format` as compressed_image_transport writes it ("ORIG_PIXFMT; CODEC compressed
    COMPRESSED_PIXFMT", the message's own comment)."""
    import io

    from PIL import Image as PILImage

    out = io.BytesIO()
    PILImage.fromarray(np.ascontiguousarray(pixels, dtype=np.uint8), "RGB").save(
        out, "PNG", compress_level=1
    )
    return {
        "header": stamp(t, frame),
        "format": "rgb8; png compressed rgb8",
        "data": out.getvalue(),
    }
