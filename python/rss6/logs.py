"""MCAP logs of rss6 runs (one file per run), readable in Foxglove and by the ``mcap`` package.

There is one log format, written and read in Rust (rss6-exp's ``log`` module): poses as
``foxglove.FrameTransform`` (JSON schema + JSON) on ``/rss6/<name>`` — ``true_pose``, ``camera_pose``,
``desired_pose``, ``estimate_pose`` (frame base → effector_*), ``sensor_pose`` (the raw ᶜχ_t, frame
sensor → target) — six-vectors as ``rss6.JointVector`` — ``theta_cmd`` (rad, drive convention),
``theta``, ``kappa`` (bit), ``torque`` (N·m) — and calibration dwells (``/rss6/dwell``). The servo and
the calibration collector log through the same writer (``servo.track(..., mcap=path)``,
``calibrate.collect(..., mcap=path)``).

Runs are logged as they go (:class:`RunWriter`): the file is chunked, every finished chunk is handed
to the operating system (and a chunk in progress is finished at least every ``flush_interval`` s of
wall time), so a process killed mid-run leaves a file readable up to its last finished chunk
(:func:`read_log` reports it as truncated). :func:`write_run` writes a whole run at once.

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
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from os import PathLike
from types import TracebackType
from typing import TYPE_CHECKING, Any, Union

import numpy as np
from numpy.typing import NDArray

from rss6 import _rss6
from rss6.errors import LogError, TruncatedLogError

if TYPE_CHECKING:
    from typing_extensions import Self

__all__ = [
    "POSE_TOPICS",
    "VECTOR_TOPICS",
    "RunLog",
    "RunWriter",
    "read_log",
    "read_run",
    "write_run",
]

F64 = NDArray[np.float64]
Series = tuple[F64, F64]
Path = Union[str, "PathLike[str]"]

#: Pose streams written as foxglove.FrameTransform: name -> (parent, child) frame ids.
POSE_TOPICS = {
    "true_pose": ("base", "effector_true"),
    "camera_pose": ("base", "effector_camera"),
    "desired_pose": ("base", "effector_desired"),
    "estimate_pose": ("base", "effector_estimate"),
    "sensor_pose": ("sensor", "target"),
}
#: Six-vector streams (joint readings, commands, torques) with their units.
VECTOR_TOPICS = {
    "theta_cmd": "rad",
    "theta": "rad",
    "kappa": "bit",
    "torque": "N*m",
}


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
    """Writes one run to an MCAP file as it goes (a context manager), with the Rust writer
    (:class:`rss6._rss6.LogWriter`).

    ``metadata`` (string pairs, e.g. controller and trajectory) is written at once as an MCAP metadata
    record "rss6"; :meth:`add_metadata` appends more records (a reader merges the "rss6" records in
    file order). :meth:`write` appends samples of one stream, :meth:`write_streams` of several (merged
    in time order). Stream names are those of :data:`POSE_TOPICS` and :data:`VECTOR_TOPICS`; topics are
    ``/rss6/<name>``; ``t0`` (s) is added to every time stamp.

    Messages go into ZSTD-compressed chunks of about ``chunk_size`` bytes (uncompressed), with CRCs;
    each finished chunk is handed to the operating system, and a chunk in progress is finished after
    ``flush_interval`` s of wall time (``None``: only when full), so a killed process loses at most
    the last chunk. ``fsync=True`` also asks the OS to put each flush on the disk (survives a power
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
        size: object = chunk_size  # checked at run time: callers may pass anything
        if not (isinstance(size, int) and size > 0):
            raise LogError(f"chunk_size must be a positive integer (bytes), got {chunk_size!r}")
        if flush_interval is not None and not flush_interval >= 0:
            raise LogError(f"flush_interval must be >= 0 s or None, got {flush_interval!r}")
        if not np.isfinite(t0):
            raise LogError(f"t0 must be finite, got {t0}")
        self.path = os.fspath(path)
        self._flush_interval = flush_interval
        self._fsync = fsync
        self._w = _rss6.LogWriter(self.path, chunk_size=chunk_size, t0=float(t0))
        self._closed = False
        self._synced = 0  # bytes handed to the OS at the last flush (a whole-record boundary)
        self._last_sync = time.monotonic()
        try:
            if metadata:
                self.add_metadata(metadata)
            else:
                self.flush()
        except BaseException:
            with contextlib.suppress(Exception):
                self._w.finish()
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

    @property
    def messages(self) -> int:
        """Messages written so far."""
        return int(self._w.messages)

    def _check_open(self) -> None:
        if self._closed:
            raise LogError(f"{self.path}: the log is already closed")

    def _after_write(self) -> None:
        if (
            self._flush_interval is not None
            and time.monotonic() - self._last_sync >= self._flush_interval
        ):
            self.flush()

    def write(self, name: str, t: Any, values: Any) -> None:
        """Appends samples of one stream: times ``t`` (N,) s and ``values`` (N, 6) — or one sample,
        a time and a (6,) vector. Poses are [x, y, z, α, β, γ] (m, rad)."""
        self._check_open()
        tc, vc = _check_arrays(name, t, values)
        self._w.write(name, tc, vc)
        self._after_write()

    def write_streams(self, streams: Mapping[str, Series]) -> None:
        """Appends samples of several streams ``{name: (times (N,), values (N, 6))}``, merged in time
        order (so chunks hold contiguous time ranges)."""
        self._check_open()
        checked: dict[str, tuple[Any, Any]] = {
            name: _check_series(name, s) for name, s in streams.items()
        }
        self._w.write_streams(checked)
        self._after_write()

    def add_metadata(self, data: Mapping[str, str], name: str = "rss6") -> None:
        """Appends an MCAP metadata record (string pairs), after finishing the chunk in progress (so
        a record written after some samples also comes after them in the file), and flushes."""
        self._check_open()
        self._w.add_metadata({str(k): str(v) for k, v in data.items()}, name)
        self.flush()

    def flush(self) -> None:
        """Finishes the chunk in progress and hands everything to the OS (and the disk with
        ``fsync``)."""
        self._check_open()
        self._w.flush(self._fsync)
        try:
            self._synced = os.path.getsize(self.path)
        except OSError as e:
            raise LogError(f"cannot write {self.path}: {e}") from e
        self._last_sync = time.monotonic()

    def close(self, status: str | None = None) -> None:
        """Finishes the file (last chunk, summary, footer) and closes it; ``status`` (if given) is
        added first as metadata ``{"status": status}``. Closing twice does nothing."""
        if self._closed:
            return
        try:
            self._w.finish(status)
        finally:
            self._closed = True


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
    ``truncation`` says so in words ("" for a complete file). ``dwells``: the calibration dwells
    (means of a collection, see :func:`rss6.calibrate.read_mcap`) as dicts with ``index``,
    ``window``, ``theta_cmd``, ``kappa``, ``sensor_pose`` (None without camera frames),
    ``kappa_samples``, ``camera_frames`` and ``defect`` (why it cannot be used, or None).
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
    dwells: list[dict[str, Any]] = field(default_factory=list)

    @property
    def truncated(self) -> bool:
        """True if the file ends before its footer."""
        return not self.complete


def read_log(path: Path, *, strict: bool = False) -> RunLog:
    """Reads an MCAP log written by rss6 (:class:`RunWriter`, :func:`write_run`, ``servo.track`` or
    ``calibrate.collect`` with ``mcap=``), with the Rust reader.

    A truncated file (its writer stopped mid-run: no footer) is read up to its last whole record —
    for a :class:`RunWriter` log, up to its last finished chunk — and reported by ``complete`` False;
    with ``strict=True`` it raises :class:`rss6.TruncatedLogError` instead. A file that is not MCAP or
    whose content is damaged (checksum mismatch, undecodable record or message) raises
    :class:`rss6.CorruptLogError`; an unreadable one :class:`rss6.LogError`.
    """
    p = os.fspath(path)
    d = _rss6.read_log(p)
    log = RunLog(
        streams={name: (t, v) for name, (t, v) in d["streams"].items()},
        metadata=dict(d["metadata"]),
        records=[(name, dict(md)) for name, md in d["records"]],
        complete=bool(d["complete"]),
        size=int(d["size"]),
        readable=int(d["readable"]),
        chunks=int(d["chunks"]),
        messages=int(d["messages"]),
        dwells=list(d["dwells"]),
    )
    if not log.complete:
        log.truncation = (
            f"truncated: {log.readable} of {log.size} bytes are whole records ({log.chunks} "
            f"chunks, {log.messages} messages); no footer — its writer stopped mid-run"
        )
        if strict:
            e = TruncatedLogError(f"{p}: truncated MCAP log: {log.truncation}")
            e.path, e.size, e.readable = p, log.size, log.readable
            e.chunks, e.messages = log.chunks, log.messages
            raise e
    return log


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
