"""The message layouts, field by field as the Rust structs in `ipc-types`.

This module needs only `ctypes` (not iceoryx2), so that the layout test can
compare it with the Rust structs anywhere. A change in the Rust layout is a
new message version (a new type name); the test
`tests/tests/python_client.rs` fails when the two disagree.
"""

import ctypes
import math

# EstimateStatus values (`SlopeEstimate.status`).
STATUS_NAMES = {
    0: "ok",
    1: "no_ground",
    2: "no_inclined_plane",
    3: "too_few_points",
    4: "bad_frame",
}
# SlopeMethod values (`SlopeEstimate.method`).
METHOD_NAMES = {0: "paper", 1: "least-squares", 2: "tls"}
# Bits of `SlopeEstimate.confidence_reasons`, in bit order (ipc-types/src/confidence.rs).
CONFIDENCE_REASONS = [
    "few_points",
    "rough_plane",
    "small_area",
    "ground_from_mount",
    "near_border",
    "methods_disagree",
    "close_choice",
    "foot_hidden",
    "small_surface",
    "mount_mismatch",
]
# HealthComponent values (`Health.component`).
COMPONENT_NAMES = {1: "estimator", 2: "capture", 3: "replay"}


class SlopeEstimate(ctypes.Structure):
    """`slope.SlopeEstimate.v2` (232 bytes): one estimate per processed frame.

    Planes are `[a, b, c, d]` (unit normal towards the camera side, `d` the
    camera's distance), all zero when absent; NaN marks absent values.
    """

    _fields_ = [
        ("frame_index", ctypes.c_uint64),
        ("capture_stamp_ns", ctypes.c_uint64),
        ("publish_stamp_ns", ctypes.c_uint64),
        ("source_stamp_ns", ctypes.c_uint64),
        ("dropped_frames", ctypes.c_uint64),
        ("status", ctypes.c_uint32),
        ("method", ctypes.c_uint32),
        ("slope_deg", ctypes.c_double),
        ("slope_std_deg", ctypes.c_double),
        ("distance_m", ctypes.c_double),
        ("ground_plane", ctypes.c_double * 4),
        ("inclined_plane", ctypes.c_double * 4),
        ("ground_inliers", ctypes.c_uint32),
        ("inclined_inliers", ctypes.c_uint32),
        ("samples", ctypes.c_uint32),
        ("ground_from_mount", ctypes.c_uint32),
        ("processing_us", ctypes.c_uint64),
        ("confidence", ctypes.c_double),
        ("confidence_reasons", ctypes.c_uint32),
        ("ground_seen_to_m", ctypes.c_float),
        ("ground_rms_m", ctypes.c_double),
        ("inclined_rms_m", ctypes.c_double),
        ("ground_area_m2", ctypes.c_double),
        ("inclined_area_m2", ctypes.c_double),
        ("tracked_slope_deg", ctypes.c_double),
        ("tracked_std_deg", ctypes.c_double),
        ("tracked_frames", ctypes.c_uint32),
        ("tracked_accepted", ctypes.c_uint32),
    ]

    @staticmethod
    def type_name() -> str:
        """The iceoryx2 type name the Rust side pins."""
        return "slope.SlopeEstimate.v2"

    @property
    def status_name(self) -> str:
        return STATUS_NAMES.get(self.status, "bad_frame")

    @property
    def method_name(self) -> str:
        return METHOD_NAMES.get(self.method, "unknown")

    @property
    def ok(self) -> bool:
        return self.status == 0

    @property
    def latency_ms(self) -> float:
        return max(self.publish_stamp_ns - self.capture_stamp_ns, 0) / 1e6

    @property
    def confidence_reason_names(self) -> list:
        names = []
        for bit in range(32):
            if self.confidence_reasons & (1 << bit):
                known = bit < len(CONFIDENCE_REASONS)
                names.append(CONFIDENCE_REASONS[bit] if known else f"bit_{bit}")
        return names

    @property
    def ground_seen_to(self):
        """How far ahead the ground was seen, metres (`ground_seen_to_m`), or None
        without a measured ground or from an estimator older than the field (0).
        Short of the sensor's range where the floor ends before a drop-off."""
        seen = self.ground_seen_to_m
        return seen if math.isfinite(seen) and seen > 0 else None

    def to_dict(self) -> dict:
        """Every field, NaN as None and absent planes as None (as `slope-echo --json`)."""

        def finite(x):
            return x if math.isfinite(x) else None

        def plane(p):
            values = list(p)
            return None if values == [0.0] * 4 else values

        return {
            "frame": self.frame_index,
            "timestamp_ns": self.capture_stamp_ns,
            "publish_stamp_ns": self.publish_stamp_ns,
            "status": self.status_name,
            "method": self.method_name,
            "slope_deg": finite(self.slope_deg),
            "std_deg": finite(self.slope_std_deg),
            "distance_m": finite(self.distance_m),
            "latency_ms": self.latency_ms,
            "dropped_frames": self.dropped_frames,
            "ground_plane": plane(self.ground_plane),
            "inclined_plane": plane(self.inclined_plane),
            "ground_seen_to_m": self.ground_seen_to,
            "confidence": self.confidence,
            "confidence_reasons": self.confidence_reason_names,
            "tracked_slope_deg": finite(self.tracked_slope_deg),
            "tracked_std_deg": finite(self.tracked_std_deg),
        }


class TimingStats(ctypes.Structure):
    """`slope.TimingStats.v1`: median, p95, max (ms, NaN without frames) and count."""

    _fields_ = [
        ("median_ms", ctypes.c_double),
        ("p95_ms", ctypes.c_double),
        ("max_ms", ctypes.c_double),
        ("count", ctypes.c_uint64),
    ]

    @staticmethod
    def type_name() -> str:
        return "slope.TimingStats.v1"


class StageHealth(ctypes.Structure):
    """`slope.StageHealth.v1`: a stage's name (UTF-8, NUL-padded) and timing."""

    _fields_ = [("name", ctypes.c_char * 16), ("timing", TimingStats)]

    @staticmethod
    def type_name() -> str:
        return "slope.StageHealth.v1"


class Health(ctypes.Structure):
    """`slope.Health.v1` (872 bytes): a daemon's report, about once a second."""

    _fields_ = [
        ("stamp_ns", ctypes.c_uint64),
        ("uptime_ms", ctypes.c_uint64),
        ("component", ctypes.c_uint32),
        ("pid", ctypes.c_uint32),
        ("frames_in", ctypes.c_uint64),
        ("frames_out", ctypes.c_uint64),
        ("frames_dropped", ctypes.c_uint64),
        ("reconnects", ctypes.c_uint64),
        ("errors", ctypes.c_uint64),
        ("rate_in_hz", ctypes.c_double),
        ("rate_out_hz", ctypes.c_double),
        ("window_ms", ctypes.c_uint64),
        ("latency", TimingStats),
        ("stage_count", ctypes.c_uint32),
        ("reserved", ctypes.c_uint32),
        ("stages", StageHealth * 12),
        ("last_error_stamp_ns", ctypes.c_uint64),
        ("last_error", ctypes.c_char * 160),
    ]

    @staticmethod
    def type_name() -> str:
        return "slope.Health.v1"

    @property
    def component_name(self) -> str:
        return COMPONENT_NAMES.get(self.component, "unknown")

    def stage_timings(self) -> dict:
        """`{stage name: TimingStats}` of the used stages, in pipeline order."""
        used = self.stages[: min(self.stage_count, 12)]
        return {s.name.decode("utf-8", "replace"): s.timing for s in used}

    @property
    def last_error_text(self) -> str:
        return self.last_error.decode("utf-8", "replace")


# SurfaceRole values (`SurfaceDescription.role`).
ROLE_NAMES = {0: "ground", 1: "step", 2: "ramp", 3: "wall", 4: "elevated", 5: "overhang"}
# SurfaceSupport values (`SurfaceDescription.support`).
SUPPORT_NAMES = {0: "none", 1: "ground", 2: "step", 3: "hidden", 4: "ramp"}
# Bits of `SurfaceDescription.flags`.
IN_CORRIDOR = 1 << 0
MEASURABLE = 1 << 1
JOINS_GROUND = 1 << 2
# `Surfaces.road` and `SurfaceDescription.supported_by` when there is none.
NO_SURFACE = 0xFFFFFFFF
MAX_SURFACES = 16


class SurfaceDescription(ctypes.Structure):
    """`slope.SurfaceDescription.v1` (192 bytes): one surface, in the ground
    frame (heights up from the ground, distances forward, lateral positions
    to the right, metres); NaN marks absent values."""

    _fields_ = [
        ("role", ctypes.c_uint32),
        ("support", ctypes.c_uint32),
        ("supported_by", ctypes.c_uint32),
        ("inliers", ctypes.c_uint32),
        ("flags", ctypes.c_uint32),
        ("segments", ctypes.c_uint32),
        ("slope_deg", ctypes.c_double),
        ("heading_deg", ctypes.c_double),
        ("distance_m", ctypes.c_double),
        ("far_m", ctypes.c_double),
        ("left_m", ctypes.c_double),
        ("right_m", ctypes.c_double),
        ("lowest_m", ctypes.c_double),
        ("highest_m", ctypes.c_double),
        ("area_m2", ctypes.c_double),
        ("rms_m", ctypes.c_double),
        ("noise_ratio", ctypes.c_double),
        ("plane", ctypes.c_double * 4),
        ("outline", (ctypes.c_float * 3) * 4),
    ]

    @staticmethod
    def type_name() -> str:
        return "slope.SurfaceDescription.v1"

    @property
    def role_name(self) -> str:
        return ROLE_NAMES.get(self.role, "unknown")

    @property
    def support_name(self) -> str:
        return SUPPORT_NAMES.get(self.support, "unknown")

    @property
    def in_corridor(self) -> bool:
        return bool(self.flags & IN_CORRIDOR)

    @property
    def measurable(self) -> bool:
        return bool(self.flags & MEASURABLE)

    @property
    def joins_ground(self) -> bool:
        return bool(self.flags & JOINS_GROUND)


class Surfaces(ctypes.Structure):
    """`slope.Surfaces.v1` (3216 bytes): every surface of one frame (the
    largest first), and which is the road ahead."""

    _fields_ = [
        ("frame_index", ctypes.c_uint64),
        ("capture_stamp_ns", ctypes.c_uint64),
        ("publish_stamp_ns", ctypes.c_uint64),
        ("source_stamp_ns", ctypes.c_uint64),
        ("status", ctypes.c_uint32),
        ("count", ctypes.c_uint32),
        ("road", ctypes.c_uint32),
        ("ground_from_mount", ctypes.c_uint32),
        ("up", ctypes.c_double * 3),
        ("forward", ctypes.c_double * 3),
        ("ground_plane", ctypes.c_double * 4),
        ("corridor_half_width_m", ctypes.c_double),
        ("look_ahead_m", ctypes.c_double),
        ("surfaces", SurfaceDescription * MAX_SURFACES),
    ]

    @staticmethod
    def type_name() -> str:
        return "slope.Surfaces.v1"

    @property
    def status_name(self) -> str:
        return STATUS_NAMES.get(self.status, "bad_frame")

    def present(self) -> list:
        """The surfaces present (the first `count`)."""
        return list(self.surfaces[: min(self.count, MAX_SURFACES)])

    def road_surface(self):
        """The road ahead, or None."""
        present = self.present()
        return present[self.road] if self.road < len(present) else None


def layout(struct) -> dict:
    """Size, alignment, type name and `(field, offset, size)` of a structure."""
    return {
        "type_name": struct.type_name(),
        "size": ctypes.sizeof(struct),
        "align": ctypes.alignment(struct),
        "fields": [
            [name, getattr(struct, name).offset, getattr(struct, name).size]
            for name, _ in struct._fields_
        ],
    }
