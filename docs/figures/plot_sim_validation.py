"""Plots the plant-vs-twin pose difference written by `cargo run -p rss6-sim --example validation`.

usage: python3 docs/figures/plot_sim_validation.py sim_validation.csv docs/figures/sim_validation.png
"""

import sys

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

src, dst = sys.argv[1], sys.argv[2]
d = np.genfromtxt(src, delimiter=",", names=True)
fig = Figure(figsize=(8, 8))
FigureCanvasAgg(fig)
ax = fig.subplots(3, 1, sharex=True)
for k in ("dx_mm", "dy_mm", "dz_mm"):
    ax[0].plot(d["time_s"], d[k], label=k.split("_")[0])
ax[0].set_ylabel("position diff (mm)")
ax[0].legend(loc="upper right")
for k in ("dalpha_mrad", "dbeta_mrad", "dgamma_mrad"):
    ax[1].plot(d["time_s"], d[k], label=k.split("_")[0])
ax[1].set_ylabel("angle diff (mrad)")
ax[1].legend(loc="upper right")
for k in ("x_mm", "y_mm", "z_mm"):
    z = k == "z_mm"
    ax[2].plot(
        d["time_s"],
        d[k] - (115.0 if z else 0.0),
        label=k.split("_")[0] + (" - 115" if z else ""),
    )
ax[2].set_ylabel("plant pose (mm)")
ax[2].set_xlabel("time (s)")
ax[2].legend(loc="upper right")
fig.suptitle("rapier plant vs analytic model twin (cf. thesis Fig. 5.5-5.6)")
fig.tight_layout()
fig.savefig(dst, dpi=110)
