"""The robot's pose from TF (tf2_msgs/msg/TFMessage on /tf and /tf_static), in 2D: x, y and
yaw, the floor being flat. A TF tree has each frame once as a child, so the latest transform of
each (parent, child) pair is the tree; the map pose is the chain from `map` down to the robot's
base: map → odom (a localiser's: amcl republishes it with every scan, nav2_amcl/src/
amcl_node.cpp laserReceived) ∘ odom → base_footprint or base_link (the odometry's: a TurtleBot3's
turtlebot3_node sends odom → base_footprint, turtlebot3_node/param/burger.yaml).

Pure: the tables are filled by the backends, from dicts with the messages' own field names."""

from __future__ import annotations

import math
import threading
from typing import Any

from astiop.ros2.message_objects import to_dict

Pose = tuple[float, float, float]  # x, y (m), yaw (rad)
MAP = "map"
ODOM = "odom"
# REP 120: base_footprint is base_link projected on the floor; both give the same 2D pose on a
# robot that has both, the footprint first as the odometry's own child on a TurtleBot3
BASE_FRAMES = ("base_footprint", "base_link")
STALE_S = 3.0  # a transform not re-sent for this long is no longer in the tree (/tf)
MAX_PAIRS = 512  # a robot's tree is tens of frames: a flood of new names is not kept
MAX_DEPTH = 64


def yaw_of(q: dict[str, Any]) -> float:
    """The heading of a quaternion, normalised first (so 1e308 components do not overflow)."""
    w, x, y, z = (_f(q.get(k, 0.0)) for k in ("w", "x", "y", "z"))
    scale = max(abs(w), abs(x), abs(y), abs(z))
    if not math.isfinite(scale) or scale == 0.0:
        return 0.0
    w, x, y, z = w / scale, x / scale, y / scale, z / scale
    return math.atan2(2 * (w * z + x * y), w * w + x * x - y * y - z * z)


def _f(value: Any) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def compose(a: Pose, b: Pose) -> Pose:
    """b (given in frame A, whose pose in the parent frame is a) in the parent frame."""
    c, s = math.cos(a[2]), math.sin(a[2])
    yaw = math.remainder(a[2] + b[2], 2 * math.pi)
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], yaw)


def inverse(a: Pose) -> Pose:
    c, s = math.cos(a[2]), math.sin(a[2])
    return (-c * a[0] - s * a[1], s * a[0] - c * a[1], math.remainder(-a[2], 2 * math.pi))


def frame(name: Any) -> str:
    """tf2 takes frame names without a leading slash (ROS 1's "/odom" is "odom")."""
    return str(name or "").lstrip("/")


def transform_pose(t: dict[str, Any]) -> Pose:
    """The 2D part of a geometry_msgs/TransformStamped's transform."""
    tr = t.get("transform") or {}
    tl = tr.get("translation") or {}
    return (_f(tl.get("x")), _f(tl.get("y")), yaw_of(tr.get("rotation") or {}))


class TransformTable:
    """The latest transform of each (parent, child) pair seen on one TF topic, and when it came:
    what is kept of a high-rate /tf (never every message). `stale_s` None: /tf_static's, which
    are sent once and hold for ever."""

    def __init__(self, stale_s: float | None = STALE_S):
        self.stale_s = stale_s
        self._lock = threading.Lock()
        self._pairs: dict[tuple[str, str], tuple[dict[str, Any], float]] = {}

    def fold(self, msg: dict[str, Any], at: float) -> None:
        for t in msg.get("transforms") or []:
            if isinstance(t, dict):
                parent, child = (t.get("header") or {}).get("frame_id"), t.get("child_frame_id")
                self._keep(parent, child, t, at)

    def fold_object(self, msg: Any, at: float) -> None:
        """A TFMessage as rclpy deserialized it: each transform made a dict only when read
        (most of a 50 Hz /tf's are replaced before anyone reads them)."""
        for t in msg.transforms:
            self._keep(t.header.frame_id, t.child_frame_id, t, at)

    def _keep(self, parent: Any, child: Any, t: Any, at: float) -> None:
        key = (frame(parent), frame(child))
        if not key[0] or not key[1] or key[0] == key[1]:
            return
        with self._lock:
            if key in self._pairs or len(self._pairs) < MAX_PAIRS:
                self._pairs[key] = (t, at)

    def message(self, now: float) -> dict[str, Any] | None:
        """A TFMessage of the pairs still current; None before any came."""
        with self._lock:
            pairs = list(self._pairs.items())
        if not pairs:
            return None
        out = []
        for key, (t, at) in pairs:
            if self.stale_s is not None and now - at > self.stale_s:
                continue
            if not isinstance(t, dict):
                t = to_dict(t)
                with self._lock:  # made once: kept unless a newer one came meanwhile
                    if self._pairs.get(key, (None, 0.0))[1] == at:
                        self._pairs[key] = (t, at)
            out.append(t)
        return {"transforms": out}


def tree(*messages: dict[str, Any] | None) -> dict[str, tuple[str, Pose]]:
    """child frame -> (its parent, its pose in the parent), from TFMessages (a later message's
    transform of a child wins)."""
    out: dict[str, tuple[str, Pose]] = {}
    for msg in messages:
        for t in (msg or {}).get("transforms") or []:
            if not isinstance(t, dict):
                continue
            parent = frame((t.get("header") or {}).get("frame_id"))
            child = frame(t.get("child_frame_id"))
            pose = transform_pose(t)
            if parent and child and parent != child and all(map(math.isfinite, pose)):
                out[child] = (parent, pose)
    return out


def is_frame(name: str, wanted: str) -> bool:
    """`name` is `wanted`, or `wanted` under a robot's prefix ("tb3_1/base_footprint")."""
    return name == wanted or name.endswith("/" + wanted)


def pose_in(frames: dict[str, tuple[str, Pose]], child: str, root: str) -> Pose | None:
    """`child`'s pose in the ancestor frame `root` (or `root` under a prefix), else None."""
    pose: Pose = (0.0, 0.0, 0.0)
    at = child
    for _ in range(MAX_DEPTH):  # a cycle in a malformed tree ends here
        if at != child and is_frame(at, root):
            return pose
        if at not in frames:
            return None
        parent, step = frames[at]
        pose, at = compose(step, pose), parent
    return None


def base_pose(frames: dict[str, tuple[str, Pose]], root: str) -> tuple[Pose, str] | None:
    """The robot base's pose in `root` and the base frame, found among the transforms seen."""
    for base in BASE_FRAMES:
        for child in sorted(c for c in frames if is_frame(c, base)):
            pose = pose_in(frames, child, root)
            if pose is not None:
                return pose, child
    return None


def odometry_in_map(frames: dict[str, tuple[str, Pose]], odometry: dict[str, Any] | None):
    """map → odom from the tree ∘ odom → base from an Odometry message (a robot whose odometry
    frame's transform to its base is not on /tf): (pose, base frame), else None."""
    if not odometry:
        return None
    odom_frame = frame((odometry.get("header") or {}).get("frame_id"))
    to_odom = pose_in(frames, odom_frame, MAP) if odom_frame else None
    if to_odom is None:
        return None
    p = (odometry.get("pose") or {}).get("pose") or {}
    pos = p.get("position") or {}
    pose = (_f(pos.get("x")), _f(pos.get("y")), yaw_of(p.get("orientation") or {}))
    if not all(map(math.isfinite, pose)):
        return None
    return compose(to_odom, pose), frame(odometry.get("child_frame_id")) or "base"


def map_pose(
    messages: list[dict[str, Any] | None], odometry: dict[str, Any] | None = None
) -> tuple[Pose, str] | None:
    """The base's pose in the map from TF (and the odometry, where TF stops at odom)."""
    frames = tree(*messages)
    return base_pose(frames, MAP) or odometry_in_map(frames, odometry)
