"""MCAP logs of rss6 runs (one file per run), readable in Foxglove.

Platform poses are written as ``foxglove.FrameTransform`` (JSON schema + JSON messages) on separate
topics for the true pose, the camera (measured) pose and the desired pose; joint commands and torques go
on their own channels with a JSON schema.

Runs are logged as they go (:class:`RunWriter`): the file is chunked, every finished chunk is flushed to
the operating system at once (and at least every ``flush_interval`` s of wall time), so a process killed
mid-run leaves a file readable up to its last finished chunk (:func:`read_log` reports it as
truncated). :func:`write_run` writes a whole run at once on top of it.

>>> import numpy as np, rss6.logs as logs, tempfile, os
>>> path = os.path.join(tempfile.mkdtemp(), "run.mcap")
>>> t = np.arange(3) * 1e-3
>>> poses = np.tile([0.0, 0.0, 0.115, 0.01, -0.02, 0.03], (3, 1))
>>> with logs.RunWriter(path, {"controller": "DSMC"}) as w:
...     w.write("true_pose", t[:2], poses[:2])
...     w.write("true_pose", t[2:], poses[2:])
>>> back = logs.read_log(path)
>>> back.complete, back.metadata["controller"], bool(np.allclose(back.streams["true_pose"][1], poses))
(True, 'DSMC', True)
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import struct
import time
from collections.abc import Mapping
from dataclasses import dataclass
from os import PathLike
from types import TracebackType
from typing import TYPE_CHECKING, Any, BinaryIO, Union

import numpy as np
from numpy.typing import NDArray

from rss6.errors import CorruptLogError, LogError, TruncatedLogError

if TYPE_CHECKING:
    from typing_extensions import Self

__all__ = [
    "POSE_TOPICS",
    "VECTOR_TOPICS",
    "RunLog",
    "RunWriter",
    "euler_to_quaternion",
    "quaternion_to_euler",
    "read_log",
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


def _stamp(ns: int) -> dict[str, int]:
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def _check_series(name: str, series: Any) -> Series:
    try:
        t, v = series
    except (TypeError, ValueError) as e:
        raise LogError(f"{name}: expected a (times, values) pair") from e
    return _check_arrays(name, t, v)


def _check_arrays(name: str, t: Any, v: Any) -> Series:
    if name not in POSE_TOPICS and name not in VECTOR_TOPICS:
        known = ", ".join([*POSE_TOPICS, *VECTOR_TOPICS])
        raise LogError(f"unknown stream '{name}' (known: {known})")
    t = np.asarray(t, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    if t.ndim == 0 and v.shape == (6,):
        t, v = t.reshape(1), v.reshape(1, 6)
    if t.ndim != 1 or v.shape != (t.shape[0], 6):
        raise LogError(f"{name}: times must be (N,) and values (N, 6), got {t.shape} and {v.shape}")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0):
        raise LogError(f"{name}: times must be finite and non-decreasing")
    return t, v


class RunWriter:
    """Writes one run to an MCAP file as it goes (a context manager).

    ``metadata`` (string pairs, e.g. controller and trajectory) is written at once as an MCAP metadata
    record "rss6"; :meth:`add_metadata` appends more records (a reader merges the "rss6" records in
    file order). :meth:`write` appends samples of one stream, :meth:`write_streams` of several (merged
    in time order). Stream names are those of :data:`POSE_TOPICS` and :data:`VECTOR_TOPICS`; topics are
    ``/rss6/<name>``; ``t0`` (s) is added to every time stamp.

    Messages go into ZSTD-compressed chunks of about ``chunk_size`` bytes (uncompressed); each finished
    chunk is written and flushed to the operating system at once, and a chunk in progress is finished
    after ``flush_interval`` s of wall time (``None``: only when full), so a killed process loses at
    most the last chunk. ``fsync=True`` also asks the OS to put each chunk on the disk (survives a power
    cut; slower). Leaving the ``with`` block finishes the file (summary, footer); if it is left by an
    exception, a metadata record ``status: "failed: <error>"`` is added first. Errors are
    :class:`rss6.LogError`.
    """

    def __init__(
        self,
        path: Path,
        metadata: Mapping[str, str] | None = None,
        *,
        t0: float = 0.0,
        chunk_size: int = 256 * 1024,
        flush_interval: float | None = 1.0,
        fsync: bool = False,
    ) -> None:
        from mcap.writer import CompressionType, Writer

        if not (isinstance(chunk_size, int) and chunk_size > 0):
            raise LogError(f"chunk_size must be a positive integer (bytes), got {chunk_size!r}")
        if flush_interval is not None and not flush_interval >= 0:
            raise LogError(f"flush_interval must be >= 0 s or None, got {flush_interval!r}")
        if not np.isfinite(t0):
            raise LogError(f"t0 must be finite, got {t0}")
        self.path = os.fspath(path)
        self._t0 = float(t0)
        self._flush_interval = flush_interval
        self._fsync = fsync
        try:
            self._file: BinaryIO = open(self.path, "wb")  # noqa: SIM115 - closed by close()
        except OSError as e:
            raise LogError(f"cannot write {self.path}: {e}") from e
        self._closed = False
        # Chunk CRCs and the data-section CRC let read_log tell damage from truncation.
        self._w = Writer(
            self._file,
            chunk_size=chunk_size,
            compression=CompressionType.ZSTD,
            enable_crcs=True,
            enable_data_crcs=True,
        )
        self._channels: dict[str, int] = {}
        self._seq = 0
        self._pending = 0  # messages added since the chunk in progress was last forced out
        self._synced = 0  # bytes handed to the OS
        self._last_sync = time.monotonic()
        self.messages = 0
        try:
            self._w.start(profile="", library="rss6")
            self._schemas = {
                "pose": self._w.register_schema(
                    name="foxglove.FrameTransform",
                    encoding="jsonschema",
                    data=json.dumps(_FRAME_TRANSFORM_SCHEMA).encode(),
                ),
                "vector": self._w.register_schema(
                    name="rss6.JointVector",
                    encoding="jsonschema",
                    data=json.dumps(_VECTOR_SCHEMA).encode(),
                ),
            }
            if metadata:
                self.add_metadata(metadata)
            else:
                self._sync(force=True)
        except BaseException:
            self._file.close()
            self._closed = True
            raise

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if exc is None:
            self.close()
        else:
            # Keep the run's own error, not the log's.
            with contextlib.suppress(Exception):
                self.close(status=f"failed: {type(exc).__name__}: {exc}")

    @property
    def closed(self) -> bool:
        """True once the file is finished (or failed to be)."""
        return self._closed

    def _check_open(self) -> None:
        if self._closed:
            raise LogError(f"{self.path}: the log is already closed")

    def _channel(self, name: str) -> int:
        ch = self._channels.get(name)
        if ch is None:
            kind = "pose" if name in POSE_TOPICS else "vector"
            ch = self._w.register_channel(
                topic=f"/rss6/{name}", message_encoding="json", schema_id=self._schemas[kind]
            )
            self._channels[name] = ch
        return ch

    def _encode(self, name: str, t: F64, v: F64) -> list[tuple[int, int, bytes]]:
        ch = self._channel(name)
        ns = [round((self._t0 + tk) * 1e9) for tk in t.tolist()]
        if name in POSE_TOPICS:
            child = POSE_TOPICS[name]
            q = euler_to_quaternion(v).tolist() if len(v) else []
            rows = v.tolist()
            return [
                (
                    n,
                    ch,
                    json.dumps(
                        {
                            "timestamp": _stamp(n),
                            "parent_frame_id": "base",
                            "child_frame_id": child,
                            "translation": {"x": r[0], "y": r[1], "z": r[2]},
                            "rotation": {"x": qk[0], "y": qk[1], "z": qk[2], "w": qk[3]},
                        }
                    ).encode(),
                )
                for n, r, qk in zip(ns, rows, q)
            ]
        unit = VECTOR_TOPICS[name]
        return [
            (n, ch, json.dumps({"timestamp": _stamp(n), "unit": unit, "values": r}).encode())
            for n, r in zip(ns, v.tolist())
        ]

    def _add(self, events: list[tuple[int, int, bytes]]) -> None:
        try:
            for ns, ch, data in events:
                self._w.add_message(
                    channel_id=ch, log_time=ns, data=data, publish_time=ns, sequence=self._seq
                )
                self._seq += 1
            self.messages += len(events)
            self._pending += len(events)
            self._sync()
        except OSError as e:
            raise LogError(f"cannot write {self.path}: {e}") from e

    def write(self, name: str, t: Any, values: Any) -> None:
        """Appends samples of one stream: times ``t`` (N,) s and ``values`` (N, 6) — or one sample,
        a time and a (6,) vector. Poses are [x, y, z, α, β, γ] (m, rad)."""
        self._check_open()
        tc, vc = _check_arrays(name, t, values)
        self._add(self._encode(name, tc, vc))

    def write_streams(self, streams: Mapping[str, Series]) -> None:
        """Appends samples of several streams ``{name: (times (N,), values (N, 6))}``, merged in time
        order (so chunks hold contiguous time ranges)."""
        self._check_open()
        checked = {name: _check_series(name, s) for name, s in streams.items()}
        events: list[tuple[int, int, bytes]] = []
        for name, (t, v) in checked.items():
            events.extend(self._encode(name, t, v))
        events.sort(key=lambda e: (e[0], e[1]))
        self._add(events)

    def add_metadata(self, data: Mapping[str, str], name: str = "rss6") -> None:
        """Appends an MCAP metadata record (string pairs), after finishing the chunk in progress (so
        a record written after some samples also comes after them in the file), and flushes."""
        self._check_open()
        try:
            self._finish_chunk()
            self._w.add_metadata(name, {str(k): str(v) for k, v in data.items()})
            self._sync(force=True)
        except OSError as e:
            raise LogError(f"cannot write {self.path}: {e}") from e

    def _finish_chunk(self) -> None:
        # mcap's Writer.flush finishes the chunk in progress (none if it is empty). Without it (old
        # mcap versions) chunks are finished only when full.
        flush = getattr(self._w, "flush", None)
        if flush is not None:
            flush()
        self._pending = 0

    def flush(self) -> None:
        """Finishes the chunk in progress and hands everything to the OS (and the disk with
        ``fsync``)."""
        self._check_open()
        try:
            self._finish_chunk()
            self._sync(force=True)
        except OSError as e:
            raise LogError(f"cannot write {self.path}: {e}") from e

    def _sync(self, force: bool = False) -> None:
        if (
            not force
            and self._pending
            and self._flush_interval is not None
            and time.monotonic() - self._last_sync >= self._flush_interval
        ):
            self._finish_chunk()
        if force or self._file.tell() > self._synced:
            self._file.flush()
            if self._fsync:
                os.fsync(self._file.fileno())
            self._synced = self._file.tell()
            self._last_sync = time.monotonic()

    def close(self, status: str | None = None) -> None:
        """Finishes the file (last chunk, summary, footer) and closes it; ``status`` (if given) is
        added first as metadata ``{"status": status}``. Closing twice does nothing."""
        if self._closed:
            return
        try:
            if status is not None:
                self.add_metadata({"status": status})
            self._w.finish()
            self._file.flush()
            if self._fsync:
                os.fsync(self._file.fileno())
        except OSError as e:
            raise LogError(f"cannot write {self.path}: {e}") from e
        finally:
            self._closed = True
            self._file.close()


def write_run(
    path: Path,
    streams: Mapping[str, Series],
    metadata: Mapping[str, str] | None = None,
    *,
    t0: float = 0.0,
) -> None:
    """Writes one whole run to an MCAP file (a :class:`RunWriter` used once).

    ``streams`` maps a name of :data:`POSE_TOPICS` or :data:`VECTOR_TOPICS` to ``(times (N,) s,
    values (N, 6))``; poses are [x, y, z, α, β, γ] (m, rad). Topics are ``/rss6/<name>``. ``metadata``
    (string pairs, e.g. controller and trajectory) is stored as an MCAP metadata record "rss6".
    ``t0`` (s) is added to every time stamp.
    """
    checked = {name: _check_series(name, s) for name, s in streams.items()}
    with RunWriter(path, metadata, t0=t0, chunk_size=1024 * 1024, flush_interval=None) as w:
        w.write_streams(checked)


@dataclass
class RunLog:
    """What :func:`read_log` found in an MCAP log.

    ``streams``: ``{name: (times (N,) s, values (N, 6))}`` per stream, sorted by time; ``metadata``:
    the "rss6" metadata records merged in file order; ``records``: every metadata record as
    ``(name, data)`` in file order. ``complete`` is False for a truncated file (no footer: its writer
    stopped mid-run), read up to its last whole record; ``size`` and ``readable`` are the file's bytes
    and those up to the end of that record; ``chunks`` and ``messages`` count what was read;
    ``truncation`` says so in words ("" for a complete file).
    """

    streams: dict[str, Series]
    metadata: dict[str, str]
    records: list[tuple[str, dict[str, str]]]
    complete: bool
    size: int
    readable: int
    chunks: int
    messages: int
    truncation: str = ""

    @property
    def truncated(self) -> bool:
        """True if the file ends before its footer."""
        return not self.complete


_MAGIC = b"\x89MCAP0\r\n"
_FOOTER = 0x02
_CHUNK = 0x06


def _corrupt(path: str, offset: int, why: str) -> CorruptLogError:
    e = CorruptLogError(f"{path}: not a readable MCAP log: {why} (at byte {offset})")
    e.path, e.offset = path, offset
    return e


def _scan(path: str, data: bytes) -> tuple[int, bool, int]:
    """The framing of the records: (bytes up to the end of the last whole record, whether the file
    ends with footer + magic, number of whole chunk records). Raises for a file that is not MCAP."""
    n = len(data)
    if n == 0:
        raise _truncated(path, 0, 0, 0, 0, "the file is empty: its writer stopped before writing")
    if not data.startswith(_MAGIC[: min(n, len(_MAGIC))]) or n < len(_MAGIC):
        if data.startswith(_MAGIC[:n]):
            raise _truncated(path, n, 0, 0, 0, "the file ends inside its start magic")
        raise _corrupt(path, 0, f"bad magic {data[:8]!r}, expected {_MAGIC!r}")
    pos, chunks = len(_MAGIC), 0
    while pos < n:
        if n - pos < 9:
            return pos, False, chunks
        opcode = data[pos]
        (length,) = struct.unpack_from("<Q", data, pos + 1)
        if opcode == 0:
            raise _corrupt(path, pos, "record with opcode 0x00")
        end = pos + 9 + length
        if end > n:
            return pos, False, chunks
        chunks += opcode == _CHUNK
        pos = end
        if opcode == _FOOTER:
            tail = data[pos:]
            if tail == _MAGIC:
                return pos, True, chunks
            if _MAGIC.startswith(tail):
                return pos, False, chunks
            raise _corrupt(path, pos, "the footer is not followed by the end magic")
    return pos, False, chunks


def _truncated(
    path: str, size: int, readable: int, chunks: int, messages: int, why: str
) -> TruncatedLogError:
    e = TruncatedLogError(f"{path}: truncated MCAP log: {why}")
    e.path, e.size, e.readable, e.chunks, e.messages = path, size, readable, chunks, messages
    return e


def read_log(path: Path, *, strict: bool = False) -> RunLog:
    """Reads an MCAP log written by :class:`RunWriter` / :func:`write_run`.

    A truncated file (its writer stopped mid-run: no footer) is read up to its last whole record —
    for a :class:`RunWriter` log, up to its last finished chunk — and reported by ``complete`` False;
    with ``strict=True`` it raises :class:`rss6.TruncatedLogError` instead. A file that is not MCAP or
    whose content is damaged (checksum mismatch, undecodable record or message) raises
    :class:`rss6.CorruptLogError`; an unreadable one :class:`rss6.LogError`.
    """
    from mcap.exceptions import EndOfFile
    from mcap.records import Channel, Message, Metadata
    from mcap.stream_reader import StreamReader

    p = os.fspath(path)
    try:
        with open(p, "rb") as f:
            data = f.read()
    except OSError as e:
        raise LogError(f"cannot read {p}: {e}") from e
    readable, complete, chunks = _scan(p, data)
    buf = io.BytesIO(data if complete else data[:readable])
    reader = StreamReader(buf, skip_magic=False, emit_chunks=False, validate_crcs=True)
    channels: dict[int, str] = {}
    acc: dict[str, tuple[list[int], list[list[float]]]] = {}
    records: list[tuple[str, dict[str, str]]] = []
    messages = 0
    header = False
    try:
        for rec in reader.records:
            header = True
            if isinstance(rec, Channel):
                channels[rec.id] = rec.topic
            elif isinstance(rec, Message):
                topic = channels.get(rec.channel_id)
                if topic is None:
                    raise _corrupt(p, buf.tell(), f"message on unknown channel {rec.channel_id}")
                messages += 1
                _decode(p, buf.tell(), topic, rec.log_time, rec.data, acc)
            elif isinstance(rec, Metadata):
                records.append((rec.name, dict(rec.metadata)))
    except EndOfFile:
        if complete or buf.tell() < readable:
            raise _corrupt(p, buf.tell(), "a record ends early") from None
    except CorruptLogError:
        raise
    except Exception as e:  # any decoding failure of the mcap reader is damage
        raise _corrupt(p, buf.tell(), f"{type(e).__name__}: {e}") from e
    if not header:
        raise _truncated(p, len(data), readable, 0, 0, "it ends before its header record")
    streams: dict[str, Series] = {}
    for name, (ns, vals) in acc.items():
        t = np.asarray(ns, dtype=np.int64)
        order = np.argsort(t, kind="stable")
        streams[name] = (
            np.asarray(t[order] * 1e-9, dtype=np.float64),
            np.asarray(vals, dtype=np.float64).reshape(-1, 6)[order],
        )
    metadata: dict[str, str] = {}
    for name, md in records:
        if name == "rss6":
            metadata.update(md)
    log = RunLog(
        streams=streams,
        metadata=metadata,
        records=records,
        complete=complete,
        size=len(data),
        readable=readable,
        chunks=chunks,
        messages=messages,
    )
    if not complete:
        log.truncation = (
            f"truncated: {readable} of {len(data)} bytes are whole records ({chunks} chunks, "
            f"{messages} messages); no footer — its writer stopped mid-run"
        )
        if strict:
            raise _truncated(p, len(data), readable, chunks, messages, log.truncation)
    return log


def _decode(
    path: str,
    offset: int,
    topic: str,
    log_time: int,
    data: bytes,
    acc: dict[str, tuple[list[int], list[list[float]]]],
) -> None:
    if not topic.startswith("/rss6/"):
        return
    name = topic[len("/rss6/") :]
    if name not in POSE_TOPICS and name not in VECTOR_TOPICS:
        return
    try:
        msg = json.loads(data)
        ts = msg["timestamp"]
        ns = int(ts["sec"]) * 1_000_000_000 + int(ts["nsec"])
        if name in POSE_TOPICS:
            tr, ro = msg["translation"], msg["rotation"]
            ang = quaternion_to_euler([[ro["x"], ro["y"], ro["z"], ro["w"]]])[0]
            val = [float(tr["x"]), float(tr["y"]), float(tr["z"]), *ang.tolist()]
        else:
            val = [float(x) for x in msg["values"]]
            if len(val) != 6:
                raise ValueError(f"{len(val)} values, expected 6")
    except (ValueError, KeyError, TypeError) as e:
        raise _corrupt(
            path, offset, f"bad message on {topic} at log time {log_time} ns: {e}"
        ) from e
    ts_list, val_list = acc.setdefault(name, ([], []))
    ts_list.append(ns)
    val_list.append(val)


def read_run(path: Path, *, strict: bool = False) -> dict[str, Any]:
    """Reads a file written by :func:`write_run` or :class:`RunWriter` (a truncated one up to its
    last whole chunk unless ``strict``; see :func:`read_log`, which also says whether it was).

    Returns ``{name: (times (N,), values (N, 6))}`` for every stream found, plus ``"metadata"`` (dict,
    the "rss6" records merged) if the file has an "rss6" metadata record.
    """
    log = read_log(path, strict=strict)
    out: dict[str, Any] = dict(log.streams)
    if any(name == "rss6" for name, _ in log.records):
        out["metadata"] = log.metadata
    return out
