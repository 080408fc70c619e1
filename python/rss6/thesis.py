"""The numbers the thesis publishes, read from the compiled core (``rss6_core::thesis``) so that
Python and Rust share one copy.

Units are SI (m, rad, kg, s) except Tables 6.1/6.2, which keep the printed units (mm for x, y, z and
1e-3 rad for α, β, γ). Pose-indexed lists are ordered [x, y, z, α, β, γ].

>>> from rss6 import thesis
>>> thesis.TABLE_4_2["eta"]
5e-05
>>> thesis.TABLE_6_1["rmse"]["DSMC"][0]
0.44
"""

from __future__ import annotations

from typing import Any

from rss6 import _rss6

__all__ = [
    "SECTION_6_5",
    "TABLE_4_1",
    "TABLE_4_2",
    "TABLE_4_3",
    "TABLE_4_4",
    "TABLE_4_5",
    "TABLE_5_1",
    "TABLE_5_2",
    "TABLE_5_2_BODIES",
    "TABLE_5_3",
    "TABLE_5_4",
    "TABLE_5_5",
    "TABLE_6_1",
    "TABLE_6_2",
    "VISUAL_PID",
]

_T: dict[str, dict[str, Any]] = _rss6.thesis_tables()

#: Table 4.1, measurement noise (1σ): ``kappa_bits`` (bit), ``position`` (m), ``angle`` (rad),
#: ``angle_deg`` (deg, as printed).
TABLE_4_1: dict[str, float] = dict(_T["table_4_1"])
#: Table 4.2, σ of the simulated parameter errors: ``length`` (m), ``eta`` (rad/bit), ``dtheta``
#: (rad), ``ext_position`` (m), ``ext_angle`` (rad).
TABLE_4_2: dict[str, float] = dict(_T["table_4_2"])
#: Table 4.3 (implicit): ``param_error`` and ``residual`` as (before, after), ``configurations``,
#: ``iterations``.
TABLE_4_3: dict[str, Any] = dict(_T["table_4_3"])
#: Table 4.4 (RPBA), same keys as :data:`TABLE_4_3`.
TABLE_4_4: dict[str, Any] = dict(_T["table_4_4"])
#: Table 4.5, RMS relative pose errors [x, y, z, α, β, γ] (m, rad): ``uncalibrated``, ``implicit``,
#: ``RPBA``.
TABLE_4_5: dict[str, list[float]] = dict(_T["table_4_5"])
#: Table 5.1, [m, I_x, I_y, I_z] (kg, kg·m²) of the ``platform``, each ``wrench`` and each ``link``.
TABLE_5_1: dict[str, list[float]] = dict(_T["table_5_1"])
#: Table 5.2: built-in PID [l_p, l_i, l_d] (drive units) ``pid_initial``, ``pid_identified``, and
#: the identified joint friction ``coulomb``, ``viscous`` (joints 1..6).
TABLE_5_2: dict[str, list[float]] = dict(_T["table_5_2"])
#: §5.6.2, gains of the outer visual PID (eq. 5.4): ``kp``, ``ki`` (1/s), ``kd`` (s).
VISUAL_PID: dict[str, float] = dict(_T["visual_pid"])
#: §6.5: ``control_period`` (s), ``experiment1_omega`` (rad/s), ``experiment2_omega0`` (rad/s),
#: ``experiment2_harmonics``.
SECTION_6_5: dict[str, float] = dict(_T["section_6_5"])
#: Table 6.1 (Experiment 1): {"rmse"|"mae": {"KJSC"|"KCSC"|"DSMC": [x, y, z (mm), α, β, γ (1e-3 rad)]}}.
TABLE_6_1: dict[str, dict[str, list[float]]] = dict(_T["table_6_1"])
#: Table 6.2 (Experiment 2), same layout as :data:`TABLE_6_1`.
TABLE_6_2: dict[str, dict[str, list[float]]] = dict(_T["table_6_2"])

#: Table 5.2, identified [m, I_x, I_y, I_z] (kg, kg·m²) as printed: ``platform``; ``wrenches``
#: [m, I_z] per wrench; ``links`` [m, I_x, I_y] per link. (Its platform moments violate the triangle
#: inequality; ``rss6.identify.table_5_2_truth`` lowers I_z to 30.4·10⁻².)
TABLE_5_2_BODIES: dict[str, list[Any]] = dict(_T["table_5_2_bodies"])
#: Table 5.3, RMS of the pose errors on the identification trajectory [x, y, z, α, β, γ] (m, rad):
#: ``before`` and ``after`` identification.
TABLE_5_3: dict[str, list[float]] = dict(_T["table_5_3"])
#: Table 5.4, RMS of the pose errors of the identified model on ten validation trajectories, rows
#: [x, y, z, α, β, γ] (m, rad).
_ROWS_5_4: Any = _T["table_5_4"]
TABLE_5_4: list[list[float]] = [[float(v) for v in r] for r in _ROWS_5_4]
#: Table 5.5, variation measure of the identified values over re-identifications (fraction), by
#: name ("platform.m", "platform.Ix", …, "wrench1.m", "wrench1.Iz", "link1.m", "link1.Ix",
#: "link1.Iy", "fc1", "fv1", "lp", "li", "ld").
TABLE_5_5: dict[str, float] = {k: v / 100 for k, v in _T["table_5_5_percent"].items()}
