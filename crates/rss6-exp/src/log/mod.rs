//! The one MCAP log format of rss6: one file per run, written chunk by chunk as the run goes (a
//! process killed mid-run leaves every finished chunk readable), readable by Foxglove and by the `mcap`
//! Python package.
//!
//! Topics are `/rss6/<stream>`:
//! * poses as `foxglove.FrameTransform` (JSON schema + JSON): `true_pose` (base → effector_true, the
//!   simulator's truth), `camera_pose` (base → effector_camera: χ_E from a camera frame through the
//!   estimated ᴼχ_C, ᴱχ_t), `desired_pose`, `estimate_pose` (base → effector_desired/_estimate),
//!   `sensor_pose` (sensor → target: the raw frame ᶜχ_t);
//! * six-vectors as `rss6.JointVector` (`timestamp`, `unit`, `values`): `theta_cmd` (rad, drive
//!   convention), `theta` (rad, true joint angles), `kappa` (bit), `torque` (N·m);
//! * `dwell` (`rss6.Dwell`): the means of a finished calibration dwell (index, window, θ_cmd, κ, ᶜχ_t,
//!   sample counts) — the numbers [`crate::dwell::collect`] returned;
//! * metadata records named `rss6` (string pairs; a reader merges them in file order).
//!
//! Log times are nanoseconds of robot time (plus the writer's `t0`).

mod reader;
mod schema;
mod writer;

pub use reader::{read_log, read_log_bytes, LogDwell, LogError, RunLog};
pub use schema::{StreamKind, POSE_STREAMS, VECTOR_STREAMS};
pub use writer::{LogObserver, LogWriter, DEFAULT_CHUNK_SIZE};
