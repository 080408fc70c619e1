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

# Tables 5.2 (masses and inertias), 5.3 and 5.4 are not in rss6_core::thesis yet; their printed
# values are kept here until they move there (one copy for Python).

#: Table 5.2, identified [m, I_x, I_y, I_z] (kg, kg·m²) as printed: ``platform``; ``wrenches``
#: [m, I_z] per wrench; ``links`` [m, I_x, I_y] per link. (Its platform moments violate the triangle
#: inequality; ``rss6.identify.table_5_2_truth`` lowers I_z to 30.4·10⁻².)
TABLE_5_2_BODIES: dict[str, list[Any]] = {
    "platform": [23.5, 16.1e-2, 14.4e-2, 33.7e-2],
    "wrenches": [
        [67.1e-2, 69.4e-5],
        [68.7e-2, 10.0e-5],
        [68.0e-2, 22.6e-5],
        [67.7e-2, 76.0e-5],
        [68.3e-2, 44.1e-5],
        [68.4e-2, 69.6e-5],
    ],
    "links": [
        [1.33, 63.0e-5, 68.4e-5],
        [1.32, 60.7e-5, 71.8e-5],
        [1.25, 22.4e-5, 35.5e-5],
        [1.24, 12.9e-5, 39.2e-5],
        [1.33, 30.7e-5, 49.7e-5],
        [1.34, 47.0e-5, 50.9e-5],
    ],
}
#: Table 5.3, RMS of the pose errors on the identification trajectory [x, y, z, α, β, γ] (m, rad):
#: ``before`` and ``after`` identification.
TABLE_5_3: dict[str, list[float]] = {
    "before": [1.26e-3, 1.16e-3, 1.55e-3, 2.52e-3, 3.58e-3, 2.80e-3],
    "after": [0.408e-3, 0.235e-3, 0.494e-3, 0.956e-3, 0.797e-3, 0.725e-3],
}
#: Table 5.4, RMS of the pose errors of the identified model on ten validation trajectories, rows
#: [x, y, z, α, β, γ] (m, rad).
TABLE_5_4: list[list[float]] = [
    [v * 1e-3 for v in row]
    for row in (
        [0.517, 0.384, 0.709, 1.091, 0.963, 0.966],
        [0.273, 0.410, 0.522, 1.157, 1.071, 0.932],
        [0.381, 0.403, 0.600, 1.242, 0.830, 1.143],
        [0.341, 0.511, 0.617, 1.136, 0.814, 1.161],
        [0.322, 0.394, 0.464, 1.219, 0.877, 0.835],
        [0.310, 0.301, 0.441, 1.195, 1.111, 1.040],
        [0.360, 0.402, 0.455, 1.263, 1.176, 1.024],
        [0.418, 0.483, 0.460, 1.251, 1.211, 1.015],
        [0.342, 0.510, 0.557, 1.411, 1.156, 0.711],
        [0.318, 0.379, 0.473, 1.219, 1.023, 0.905],
    )
]

#: Table 5.5, variation measure of the identified values over re-identifications (fraction), by
#: name ("platform.m", "platform.Ix", …, "wrench1.m", "wrench1.Iz", "link1.m", "link1.Ix",
#: "link1.Iy", "fc1", "fv1", "lp", "li", "ld").
TABLE_5_5: dict[str, float] = {
    k: v / 100
    for k, v in {
        "platform.m": 0.48,
        "platform.Ix": 5.0,
        "platform.Iy": 24.9,
        "platform.Iz": 8.6,
        "wrench1.m": 0.56,
        "wrench1.Iz": 6.6,
        "wrench2.m": 1.5,
        "wrench2.Iz": 1.4,
        "wrench3.m": 3.4,
        "wrench3.Iz": 5.0,
        "wrench4.m": 3.7,
        "wrench4.Iz": 3.8,
        "wrench5.m": 6.6,
        "wrench5.Iz": 6.6,
        "wrench6.m": 0.79,
        "wrench6.Iz": 1.7,
        "link1.m": 4.1,
        "link1.Ix": 0.04,
        "link1.Iy": 0.11,
        "link2.m": 5.2,
        "link2.Ix": 0.05,
        "link2.Iy": 0.12,
        "link3.m": 20.9,
        "link3.Ix": 0.09,
        "link3.Iy": 0.17,
        "link4.m": 19.1,
        "link4.Ix": 0.16,
        "link4.Iy": 0.06,
        "link5.m": 10.1,
        "link5.Ix": 0.15,
        "link5.Iy": 0.01,
        "link6.m": 12.9,
        "link6.Ix": 0.17,
        "link6.Iy": 0.02,
        "fc1": 15.9,
        "fv1": 11.7,
        "fc2": 21.4,
        "fv2": 13.9,
        "fc3": 9.0,
        "fv3": 16.4,
        "fc4": 17.8,
        "fv4": 15.2,
        "fc5": 15.1,
        "fv5": 21.8,
        "fc6": 23.4,
        "fv6": 13.0,
        "lp": 2.82,
        "li": 0.44,
        "ld": 3.7,
    }.items()
}
