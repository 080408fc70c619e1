//! Closed-loop output-error identification (CLOE, thesis §5.3, eq. 5.3–5.9): the simulated loop of
//! Fig. 5.1 as a function of the identification vector A, its exact forward sensitivities, a
//! physically consistent parametrisation, and the Levenberg–Marquardt estimator on them.

mod closed_loop;
mod config;
mod consistent;
mod estimator;
mod friction;
mod hac;
mod lm_step;
mod observability;
mod options;
mod result;
mod sens_state;
mod truth;

pub use closed_loop::{simulate, simulate_from, simulate_recording, Recording};
pub use config::{parameter_names, LoopConfig, LoopParams, LoopRun, StateJacobians, N_A};
pub use consistent::{Consistent, N_PSI};
pub use estimator::{cloe, cloe_observed};
pub use observability::{output_observability, OutputObservability};
pub use options::{CloeData, CloeOptions, HAC_LAGS};
pub use result::{Alias, CloeResult, CloeStop, SETTLE_STEPS};
pub use truth::{table_5_2_truth, DRIVE_UNIT_TO_NM};
