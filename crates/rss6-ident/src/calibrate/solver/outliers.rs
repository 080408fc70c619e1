//! Gross outliers: the configuration that stands out of a fit, the one a fit bent toward itself
//! (found by refitting without each configuration), and rejected ones taken back.

use super::{assess, levenberg_marquardt, start, verdict, Fit, LmEnd, Reduction, Selected};
use crate::calibrate::min_configurations;
use crate::calibrate::options::CalibrationOptions;
use crate::calibrate::problem::Usable;
use crate::calibrate::result::RejectedConfiguration;
use crate::error::Method;
use crate::model::Layout;
use nalgebra::DVector;

/// The gross outlier of a fit, if any: (usable index, normalised residual, threshold). A χ² test
/// that only fires on a configuration that stands out: above `outlier_threshold` and above
/// `outlier_ratio` × the median (a gross error smears into every residual of a least-squares fit,
/// while a model error or scrambled data raise them all alike: those are left to the fit statistic).
pub(super) fn outlier(fit: &Fit, opts: &CalibrationOptions) -> Option<(usize, f64, f64)> {
    let threshold = opts
        .outlier_threshold
        .max(opts.outlier_ratio * fit.median());
    fit.worst_first()
        .first()
        .filter(|w| w.1 > threshold)
        .map(|&(l, z)| (l, z, threshold))
}

/// The configuration whose removal alone makes a failed fit acceptable, if there is one:
/// (usable index, its normalised residual under the fit without it, that fit's outlier threshold).
/// A gross error pulls a least-squares fit toward itself (LM may not even converge), so its own
/// residual need not stand out; refitting without each configuration in turn finds it. Among the
/// removals whose fit passes the verdict, the one with the lowest fit statistic is returned.
/// Costs one solve per configuration: run only when the fit would otherwise be refused.
pub(super) fn deletion_outlier(
    layout: Layout,
    sel: &Selected,
    x0: &DVector<f64>,
    red: &Reduction,
    opts: &CalibrationOptions,
) -> Option<(usize, f64, f64)> {
    let first = usize::from(layout.method == Method::Rpba); // RPBA's reference stays
    let mut best: Option<(usize, f64, f64, f64)> = None;
    for l in first..sel.usable.len() {
        let drop = sel.usable.index[l];
        let mut trial = Selected {
            usable: sel.usable.only(|i| i != drop),
            dropped: Vec::new(),
        };
        if trial.usable.len() < min_configurations(layout.method) {
            return None;
        }
        let Ok((mut p, r, j)) = start(layout, &mut trial, x0, opts) else {
            continue;
        };
        let Ok(end) = levenberg_marquardt(&mut p, red, x0.clone(), r, j, opts, &mut |_| {}) else {
            continue;
        };
        let Ok(fit) = assess(&mut p, &end, red.q.ncols()) else {
            continue;
        };
        let used = trial.usable.index.clone();
        if verdict(layout.method, &fit, &end, &used, &[], opts).is_some() {
            continue;
        }
        // Its residual under the fit that did not see it.
        let mut with = Selected {
            usable: sel.usable.clone(),
            dropped: Vec::new(),
        };
        let Ok((mut pw, _, _)) = start(layout, &mut with, x0, opts) else {
            continue;
        };
        let Some(z) = assess(&mut pw, &end, red.q.ncols())
            .ok()
            .and_then(|f| f.blocks.iter().find(|b| b.0 == l).map(|b| b.1))
        else {
            continue;
        };
        let threshold = opts
            .outlier_threshold
            .max(opts.outlier_ratio * fit.median());
        if z > threshold && best.is_none_or(|b| fit.statistic() < b.3) {
            best = Some((l, z, threshold, fit.statistic()));
        }
    }
    best.map(|(l, z, t, _)| (l, z, t))
}

/// The rejected configurations (data indices) that fit the accepted fit `fit` (at `end`, on the
/// configurations `used`): each is added back alone and its normalised residual compared with the
/// outlier threshold of `fit`.
#[allow(clippy::too_many_arguments)]
pub(super) fn readmitted(
    layout: Layout,
    all: &Usable,
    used: &[usize],
    rejected: &[RejectedConfiguration],
    x0: &DVector<f64>,
    end: &LmEnd,
    fit: &Fit,
    red: &Reduction,
    opts: &CalibrationOptions,
) -> Vec<usize> {
    let threshold = opts
        .outlier_threshold
        .max(opts.outlier_ratio * fit.median());
    let mut back = Vec::new();
    for r in rejected {
        let mut trial = Selected {
            usable: all.only(|i| i == r.index || used.contains(&i)),
            dropped: Vec::new(),
        };
        let Ok((mut p, _, _)) = start(layout, &mut trial, x0, opts) else {
            continue;
        };
        let Some(l) = trial.usable.index.iter().position(|&i| i == r.index) else {
            continue;
        };
        if let Ok(f) = assess(&mut p, end, red.q.ncols()) {
            if f.blocks.iter().any(|&(b, z)| b == l && z <= threshold) {
                back.push(r.index);
            }
        }
    }
    back
}
