"""MCAP logs of rss6 runs (one file per run), readable in Foxglove.

Platform poses are written as ``foxglove.FrameTransform`` (JSON schema + JSON messages) on separate
topics for the true pose, the camera (measured) pose and the desired pose; joint commands and torques go
on their own channels with a JSON schema. MCAP files are chunked, so a run killed mid-way leaves a file
readable up to its last finished chunk.

>>> import numpy as np, rss6.logs as logs, tempfile, os
>>> path = os.path.join(tempfile.mkdtemp(), "run.mcap")
>>> t = np.arange(3) * 1e-3
>>> poses = np.tile([0.0, 0.0, 0.115, 0.01, -0.02, 0.03], (3, 1))
>>> logs.write_run(path, {"true_pose": (t, poses)})
>>> back = logs.read_run(path)
>>> bool(np.allclose(back["true_pose"][1], poses))
True
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from os import PathLike
from typing import Any, Union

import numpy as np
from numpy.typing import NDArray

from rss6.errors import LogError

__all__ = [
    "POSE_TOPICS",
    "VECTOR_TOPICS",
    "euler_to_quaternion",
    "quaternion_to_euler",
    "read_run",
    "write_run",
]

F64 = NDArray[np.float64]
Series = tuple[F64, F64]
Path = Union[str, "PathLike[str]"]

#: Pose streams written as foxglove.FrameTransform: name -> child frame id.
POSE_TOPICS = {
    "true_pose": "effector_true",
    "camera_pose": "effector_camera",
    "desired_pose": "effector_desired",
    "estimate_pose": "effector_estimate",
}
#: Six-vector streams (joint readings, commands, torques) with their units.
VECTOR_TOPICS = {
    "theta_cmd": "rad",
    "theta": "rad",
    "kappa": "bit",
    "torque": "N*m",
}

_FRAME_TRANSFORM_SCHEMA = {
    "title": "foxglove.FrameTransform",
    "description": "A transform between two reference frames in 3D space",
    "type": "object",
    "properties": {
        "timestamp": {
            "type": "object",
            "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}},
        },
        "parent_frame_id": {"type": "string"},
        "child_frame_id": {"type": "string"},
        "translation": {
            "type": "object",
            "properties": {
                "x": {"type": "number"},
                "y": {"type": "number"},
                "z": {"type": "number"},
            },
        },
        "rotation": {
            "type": "object",
            "properties": {
                "x": {"type": "number"},
                "y": {"type": "number"},
                "z": {"type": "number"},
                "w": {"type": "number"},
            },
        },
    },
}

_VECTOR_SCHEMA = {
    "title": "rss6.JointVector",
    "description": "One value per leg (1..6) at a time stamp",
    "type": "object",
    "properties": {
        "timestamp": {
            "type": "object",
            "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}},
        },
        "unit": {"type": "string"},
        "values": {"type": "array", "items": {"type": "number"}, "minItems": 6, "maxItems": 6},
    },
}


def euler_to_quaternion(pose: Any) -> F64:
    """Quaternions [x, y, z, w] (N, 4) of the rotations R = Rx(α)·Ry(β)·Rz(γ) of poses (N, 6) or (6,)."""
    p = np.atleast_2d(np.asarray(pose, dtype=np.float64))
    a, b, g = p[:, 3] / 2, p[:, 4] / 2, p[:, 5] / 2
    ca, sa, cb, sb, cg, sg = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(g), np.sin(g)
    # q = qx(α) ⊗ qy(β) ⊗ qz(γ)
    w = ca * cb * cg - sa * sb * sg
    x = sa * cb * cg + ca * sb * sg
    y = ca * sb * cg - sa * cb * sg
    z = ca * cb * sg + sa * sb * cg
    return np.stack([x, y, z, w], axis=1)


def quaternion_to_euler(q: Any) -> F64:
    """Euler angles [α, β, γ] (N, 3) with R = Rx(α)·Ry(β)·Rz(γ) from quaternions [x, y, z, w] (N, 4)."""
    q = np.atleast_2d(np.asarray(q, dtype=np.float64))
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    x, y, z, w = q.T
    r00 = 1 - 2 * (y * y + z * z)
    r01 = 2 * (x * y - z * w)
    r02 = 2 * (x * z + y * w)
    r12 = 2 * (y * z - x * w)
    r22 = 1 - 2 * (x * x + y * y)
    beta = np.arcsin(np.clip(r02, -1.0, 1.0))
    alpha = np.arctan2(-r12, r22)
    gamma = np.arctan2(-r01, r00)
    return np.stack([alpha, beta, gamma], axis=1)


def _stamp(t: float) -> dict[str, int]:
    ns = round(t * 1e9)
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def _check_series(name: str, series: Any) -> Series:
    try:
        t, v = series
    except (TypeError, ValueError) as e:
        raise LogError(f"{name}: expected a (times, values) pair") from e
    t = np.asarray(t, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    if t.ndim != 1 or v.shape != (t.shape[0], 6):
        raise LogError(f"{name}: times must be (N,) and values (N, 6), got {t.shape} and {v.shape}")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0):
        raise LogError(f"{name}: times must be finite and non-decreasing")
    return t, v


def write_run(
    path: Path,
    streams: Mapping[str, Series],
    metadata: Mapping[str, str] | None = None,
    *,
    t0: float = 0.0,
) -> None:
    """Writes one run to an MCAP file.

    ``streams`` maps a name of :data:`POSE_TOPICS` or :data:`VECTOR_TOPICS` to ``(times (N,) s,
    values (N, 6))``; poses are [x, y, z, α, β, γ] (m, rad). Topics are ``/rss6/<name>``. ``metadata``
    (string pairs, e.g. controller and trajectory) is stored as an MCAP metadata record "rss6".
    ``t0`` (s) is added to every time stamp.
    """
    from mcap.writer import CompressionType, Writer

    checked = {name: _check_series(name, s) for name, s in streams.items()}
    for name in checked:
        if name not in POSE_TOPICS and name not in VECTOR_TOPICS:
            known = ", ".join([*POSE_TOPICS, *VECTOR_TOPICS])
            raise LogError(f"unknown stream '{name}' (known: {known})")
    try:
        f = open(path, "wb")  # noqa: SIM115 - closed below, also on error
    except OSError as e:
        raise LogError(f"cannot write {path}: {e}") from e
    with f:
        w = Writer(f, compression=CompressionType.ZSTD)
        w.start(profile="", library="rss6")
        ft = w.register_schema(
            name="foxglove.FrameTransform",
            encoding="jsonschema",
            data=json.dumps(_FRAME_TRANSFORM_SCHEMA).encode(),
        )
        jv = w.register_schema(
            name="rss6.JointVector", encoding="jsonschema", data=json.dumps(_VECTOR_SCHEMA).encode()
        )
        # Merge all streams in time order so chunks hold contiguous time ranges.
        events: list[tuple[int, int, bytes]] = []
        for name, (t, v) in checked.items():
            if name in POSE_TOPICS:
                ch = w.register_channel(
                    topic=f"/rss6/{name}", message_encoding="json", schema_id=ft
                )
                q = euler_to_quaternion(v) if len(v) else np.zeros((0, 4))
                for k in range(len(t)):
                    msg = {
                        "timestamp": _stamp(t0 + t[k]),
                        "parent_frame_id": "base",
                        "child_frame_id": POSE_TOPICS[name],
                        "translation": {"x": v[k, 0], "y": v[k, 1], "z": v[k, 2]},
                        "rotation": {"x": q[k, 0], "y": q[k, 1], "z": q[k, 2], "w": q[k, 3]},
                    }
                    ns = round((t0 + t[k]) * 1e9)
                    events.append((ns, ch, json.dumps(msg).encode()))
            else:
                ch = w.register_channel(
                    topic=f"/rss6/{name}", message_encoding="json", schema_id=jv
                )
                unit = VECTOR_TOPICS[name]
                for k in range(len(t)):
                    msg = {"timestamp": _stamp(t0 + t[k]), "unit": unit, "values": v[k].tolist()}
                    ns = round((t0 + t[k]) * 1e9)
                    events.append((ns, ch, json.dumps(msg).encode()))
        events.sort(key=lambda e: (e[0], e[1]))
        for seq, (ns, ch, data) in enumerate(events):
            w.add_message(channel_id=ch, log_time=ns, data=data, publish_time=ns, sequence=seq)
        if metadata:
            w.add_metadata("rss6", {str(k): str(v) for k, v in metadata.items()})
        w.finish()


def read_run(path: Path) -> dict[str, Any]:
    """Reads a file written by :func:`write_run` (or a truncated one, up to its last whole chunk).

    Returns ``{name: (times (N,), values (N, 6))}`` for every stream found, plus ``"metadata"`` (dict)
    if the file has an "rss6" metadata record.
    """
    from mcap.exceptions import McapError
    from mcap.reader import make_reader
    from mcap.stream_reader import StreamReader

    out: dict[str, Any] = {}
    acc: dict[str, tuple[list[float], list[list[float]]]] = {}
    try:
        f = open(path, "rb")  # noqa: SIM115
    except OSError as e:
        raise LogError(f"cannot read {path}: {e}") from e

    def add(topic: str, data: bytes) -> None:
        if not topic.startswith("/rss6/"):
            return
        name = topic[len("/rss6/") :]
        msg = json.loads(data)
        ts = msg["timestamp"]["sec"] + msg["timestamp"]["nsec"] * 1e-9
        if name in POSE_TOPICS:
            tr, ro = msg["translation"], msg["rotation"]
            ang = quaternion_to_euler([[ro["x"], ro["y"], ro["z"], ro["w"]]])[0]
            val = [tr["x"], tr["y"], tr["z"], *ang.tolist()]
        else:
            val = list(msg["values"])
        ts_list, val_list = acc.setdefault(name, ([], []))
        ts_list.append(ts)
        val_list.append(val)

    with f:
        try:
            reader = make_reader(f)
            for _schema, channel, message in reader.iter_messages(log_time_order=True):
                add(channel.topic, message.data)
            for md in reader.iter_metadata():
                if md.name == "rss6":
                    out["metadata"] = dict(md.metadata)
        except (McapError, EOFError, ValueError, KeyError, AssertionError):
            # Truncated file (no summary/footer): stream the records that are complete.
            acc.clear()
            out.pop("metadata", None)
            f.seek(0)
            _read_streaming(StreamReader(f, skip_magic=False, emit_chunks=False), add, out)
    for name, (ts_list, val_list) in acc.items():
        out[name] = (np.asarray(ts_list), np.asarray(val_list, dtype=np.float64).reshape(-1, 6))
    return out


def _read_streaming(reader: Any, add: Any, out: dict[str, Any]) -> None:
    from mcap.records import Channel, Message, Metadata

    channels: dict[int, str] = {}
    try:
        for rec in reader.records:
            if isinstance(rec, Channel):
                channels[rec.id] = rec.topic
            elif isinstance(rec, Message):
                topic = channels.get(rec.channel_id)
                if topic is not None:
                    add(topic, rec.data)
            elif isinstance(rec, Metadata) and rec.name == "rss6":
                out["metadata"] = dict(rec.metadata)
    except Exception:  # noqa: BLE001 - the truncated tail of a killed run: keep what was complete
        return
