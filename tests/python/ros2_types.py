"""The ROS 2 messages slope-ros2 publishes, as Eclipse Cyclone DDS IDL types
(the Python `cyclonedds` package), written from the .msg files: slope_msgs's
in ros2/slope_msgs/msg/, the standard ones (Jazzy) as ROS 2 ships them.

DDS names follow the ROS 2 rmw layers: package::msg::dds_::Name_.
`fields(cls)` gives a type's fields as (name, ROS type) for comparing with
the .msg files (tests/python/ros2_msgs_check.py).
"""

import typing
from dataclasses import dataclass

from cyclonedds.idl import IdlStruct
from cyclonedds.idl import types as t


def _dds(ros: str) -> str:
    package, name = ros.split("/msg/")
    return f"{package}::msg::dds_::{name}_"


# builtin_interfaces, std_msgs, geometry_msgs


@dataclass
class Time(IdlStruct, typename=_dds("builtin_interfaces/msg/Time")):
    sec: t.int32
    nanosec: t.uint32


@dataclass
class Duration(IdlStruct, typename=_dds("builtin_interfaces/msg/Duration")):
    sec: t.int32
    nanosec: t.uint32


@dataclass
class Header(IdlStruct, typename=_dds("std_msgs/msg/Header")):
    stamp: Time
    frame_id: str


@dataclass
class ColorRGBA(IdlStruct, typename=_dds("std_msgs/msg/ColorRGBA")):
    r: t.float32
    g: t.float32
    b: t.float32
    a: t.float32


@dataclass
class Point(IdlStruct, typename=_dds("geometry_msgs/msg/Point")):
    x: t.float64
    y: t.float64
    z: t.float64


@dataclass
class Point32(IdlStruct, typename=_dds("geometry_msgs/msg/Point32")):
    x: t.float32
    y: t.float32
    z: t.float32


@dataclass
class Vector3(IdlStruct, typename=_dds("geometry_msgs/msg/Vector3")):
    x: t.float64
    y: t.float64
    z: t.float64


@dataclass
class Quaternion(IdlStruct, typename=_dds("geometry_msgs/msg/Quaternion")):
    x: t.float64
    y: t.float64
    z: t.float64
    w: t.float64


@dataclass
class Pose(IdlStruct, typename=_dds("geometry_msgs/msg/Pose")):
    position: Point
    orientation: Quaternion


@dataclass
class Transform(IdlStruct, typename=_dds("geometry_msgs/msg/Transform")):
    translation: Vector3
    rotation: Quaternion


@dataclass
class TransformStamped(IdlStruct, typename=_dds("geometry_msgs/msg/TransformStamped")):
    header: Header
    child_frame_id: str
    transform: Transform


@dataclass
class TFMessage(IdlStruct, typename=_dds("tf2_msgs/msg/TFMessage")):
    transforms: t.sequence[TransformStamped]


# slope_msgs (ros2/slope_msgs/msg)


@dataclass
class SlopeEstimate(IdlStruct, typename=_dds("slope_msgs/msg/SlopeEstimate")):
    header: Header
    frame_index: t.uint64
    capture_stamp_ns: t.uint64
    publish_stamp_ns: t.uint64
    source_stamp_ns: t.uint64
    dropped_frames: t.uint64
    status: t.uint32
    method: t.uint32
    slope_deg: t.float64
    slope_std_deg: t.float64
    distance_m: t.float64
    ground_plane: t.array[t.float64, 4]
    inclined_plane: t.array[t.float64, 4]
    ground_inliers: t.uint32
    inclined_inliers: t.uint32
    samples: t.uint32
    ground_from_mount: t.uint32
    processing_us: t.uint64
    confidence: t.float64
    confidence_reasons: t.uint32
    ground_seen_to_m: t.float32
    ground_rms_m: t.float64
    inclined_rms_m: t.float64
    ground_area_m2: t.float64
    inclined_area_m2: t.float64
    tracked_slope_deg: t.float64
    tracked_std_deg: t.float64
    tracked_frames: t.uint32
    tracked_accepted: t.uint32


@dataclass
class Surface(IdlStruct, typename=_dds("slope_msgs/msg/Surface")):
    role: t.uint32
    support: t.uint32
    supported_by: t.uint32
    inliers: t.uint32
    flags: t.uint32
    segments: t.uint32
    slope_deg: t.float64
    heading_deg: t.float64
    distance_m: t.float64
    far_m: t.float64
    left_m: t.float64
    right_m: t.float64
    lowest_m: t.float64
    highest_m: t.float64
    area_m2: t.float64
    rms_m: t.float64
    noise_ratio: t.float64
    plane: t.array[t.float64, 4]
    outline: t.array[Point32, 4]


@dataclass
class Surfaces(IdlStruct, typename=_dds("slope_msgs/msg/Surfaces")):
    header: Header
    frame_index: t.uint64
    capture_stamp_ns: t.uint64
    publish_stamp_ns: t.uint64
    source_stamp_ns: t.uint64
    status: t.uint32
    road: t.uint32
    ground_from_mount: t.uint32
    up: t.array[t.float64, 3]
    forward: t.array[t.float64, 3]
    ground_plane: t.array[t.float64, 4]
    corridor_half_width_m: t.float64
    look_ahead_m: t.float64
    surfaces: t.sequence[Surface]


# diagnostic_msgs


@dataclass
class KeyValue(IdlStruct, typename=_dds("diagnostic_msgs/msg/KeyValue")):
    key: str
    value: str


@dataclass
class DiagnosticStatus(IdlStruct, typename=_dds("diagnostic_msgs/msg/DiagnosticStatus")):
    level: t.byte
    name: str
    message: str
    hardware_id: str
    values: t.sequence[KeyValue]


@dataclass
class DiagnosticArray(IdlStruct, typename=_dds("diagnostic_msgs/msg/DiagnosticArray")):
    header: Header
    status: t.sequence[DiagnosticStatus]


# visualization_msgs (Jazzy's Marker: with the texture and mesh_file fields)


@dataclass
class CompressedImage(IdlStruct, typename=_dds("sensor_msgs/msg/CompressedImage")):
    header: Header
    format: str
    data: t.sequence[t.uint8]


@dataclass
class UVCoordinate(IdlStruct, typename=_dds("visualization_msgs/msg/UVCoordinate")):
    u: t.float32
    v: t.float32


@dataclass
class MeshFile(IdlStruct, typename=_dds("visualization_msgs/msg/MeshFile")):
    filename: str
    data: t.sequence[t.uint8]


@dataclass
class Marker(IdlStruct, typename=_dds("visualization_msgs/msg/Marker")):
    header: Header
    ns: str
    id: t.int32
    type: t.int32
    action: t.int32
    pose: Pose
    scale: Vector3
    color: ColorRGBA
    lifetime: Duration
    frame_locked: bool
    points: t.sequence[Point]
    colors: t.sequence[ColorRGBA]
    texture_resource: str
    texture: CompressedImage
    uv_coordinates: t.sequence[UVCoordinate]
    text: str
    mesh_resource: str
    mesh_file: MeshFile
    mesh_use_embedded_materials: bool


@dataclass
class MarkerArray(IdlStruct, typename=_dds("visualization_msgs/msg/MarkerArray")):
    markers: t.sequence[Marker]


ALL = [
    Time, Duration, Header, ColorRGBA, Point, Point32, Vector3, Quaternion, Pose, Transform,
    TransformStamped, TFMessage, SlopeEstimate, Surface, Surfaces, KeyValue,
    DiagnosticStatus, DiagnosticArray, CompressedImage, UVCoordinate, MeshFile, Marker,
    MarkerArray,
]


def ros_name(cls) -> str:
    """slope_msgs/msg/SlopeEstimate of slope_msgs::msg::dds_::SlopeEstimate_."""
    package, _, _, name = cls.__idl_typename__.split("::")
    return f"{package}/msg/{name[:-1]}"


def _type_text(hint) -> str:
    if isinstance(hint, type) and issubclass(hint, IdlStruct):
        return ros_name(hint)
    if hint is str:
        return "string"
    if hint is bool:
        return "bool"
    meta = getattr(hint, "__metadata__", None)
    if meta is None:
        raise ValueError(f"unexpected type {hint!r}")
    kind = meta[0]
    if isinstance(kind, str):
        return kind
    if isinstance(kind, t.array):
        return f"{_type_text(kind.subtype)}[{kind.length}]"
    if isinstance(kind, t.sequence):
        return f"{_type_text(kind.subtype)}[]"
    raise ValueError(f"unexpected type {hint!r}")


def fields(cls) -> list:
    """[(name, ROS type)] of an IDL type, in order: float64[4], string,
    std_msgs/msg/Header, geometry_msgs/msg/Point[]."""
    hints = typing.get_type_hints(cls, include_extras=True)
    return [[name, _type_text(hint)] for name, hint in hints.items()]
