"""The rss6 exception hierarchy.

Every error raised by rss6 derives from :class:`Rss6Error`. Errors caused by bad input are also
``ValueError`` so generic code can catch them the usual way. The compiled module maps each Rust error
enum (``rss6_core::CoreError``, the controller, plant, calibration and log errors) onto these classes
and sets the fields of the Rust variant as attributes (e.g. ``NotConvergedError.iterations``).
"""

from __future__ import annotations

__all__ = [
    "CalibrationError",
    "ControllerFaultError",
    "CorruptLogError",
    "IdentificationError",
    "InvalidInputError",
    "InvalidParameterError",
    "LogError",
    "NonFiniteError",
    "NotConvergedError",
    "OutOfBranchError",
    "ParamsFileError",
    "Rss6Error",
    "ShapeError",
    "SimulationError",
    "SingularError",
    "TruncatedLogError",
    "UnreachableError",
]


class Rss6Error(Exception):
    """Base class of every error raised by rss6."""


class InvalidInputError(Rss6Error, ValueError):
    """An argument has the wrong shape, type or value."""


class ShapeError(InvalidInputError):
    """An array argument has the wrong shape (the message names the expected and given shapes)."""


class NonFiniteError(InvalidInputError):
    """An input contains NaN or infinity (``CoreError::NonFinite``)."""


class InvalidParameterError(InvalidInputError):
    """A parameter is outside its physical range (``CoreError::InvalidParameter``)."""


class UnreachableError(Rss6Error, ValueError):
    """The pose cannot be reached (``CoreError::Unreachable``).

    Attributes: ``leg`` (1-based leg number), ``excess`` (how far the circle-intersection cosine lies
    beyond 1).
    """

    leg: int
    excess: float


class OutOfBranchError(UnreachableError):
    """The pose is reachable only outside the working branch θ ∈ (−π/2, π/2]
    (``CoreError::OutOfBranch``). Attributes: ``leg`` (1-based), ``theta`` (rad)."""

    theta: float


class NotConvergedError(Rss6Error):
    """An iterative solver hit its iteration bound (``CoreError::NotConverged``).

    Attributes: ``iterations``, ``residual`` (solver units, m for FK).
    """

    iterations: int
    residual: float


class SingularError(Rss6Error):
    """A Jacobian or matrix needed by the computation is singular (``CoreError::Singular``).

    Attribute ``kind``: ``"TypeI"``, ``"TypeII"``, ``"StewartJacobian"``, ``"Euler"`` or ``"Matrix"``.
    """

    kind: str


class ControllerFaultError(Rss6Error):
    """A controller refused its input or entered its fault state (``rss6_ctrl::CtrlError``)."""


class SimulationError(Rss6Error):
    """The plant or the model twin failed (``rss6_sim`` errors)."""


class CalibrationError(Rss6Error):
    """Calibration could not produce a trustworthy answer (``rss6_ident`` errors).

    When the solver ran but its model cannot be trusted (after rejecting gross outliers the fit is
    still inconsistent with the noise model, it did not converge, or it explains the data worse than
    the start) the attributes are ``configurations`` (indices responsible, worst first),
    ``parameters`` (comma-separated names, rank problems) and ``fit_statistic`` (weighted cost per
    degree of freedom, ≈ 1 for a consistent fit).
    """


class IdentificationError(Rss6Error):
    """Dynamic identification could not produce a trustworthy answer: an infeasible exciting
    trajectory (the message names the constraint and the time), no camera frames, a parameter that is
    not identifiable, no convergence.

    Attributes when CLOE raised it: ``names`` (the requested quantities the data cannot identify);
    on no convergence ``iterations``, ``cost_history`` (Φ at the guess and after every accepted
    step) and the last accepted iterate ``last_dynamics``, ``last_pid``.
    """


class LogError(Rss6Error):
    """An MCAP log could not be written or read."""


class TruncatedLogError(LogError):
    """An MCAP log ends before its footer (its writer stopped mid-run, e.g. the process was killed),
    and a complete file was asked for (``rss6.logs.read_log(path, strict=True)``).

    Attributes: ``path``, ``size`` (bytes in the file), ``readable`` (bytes up to the end of the last
    whole record), ``chunks`` and ``messages`` (what a tolerant read recovers).
    """

    path: str
    size: int
    readable: int
    chunks: int
    messages: int


class CorruptLogError(LogError):
    """A file is not an MCAP log or its content is damaged (bad magic, a checksum mismatch, an
    undecodable record or message). Attributes: ``path``, ``offset`` (byte where the damage was
    found)."""

    path: str
    offset: int


class ParamsFileError(Rss6Error):
    """A TOML parameter file could not be written, read or understood."""
