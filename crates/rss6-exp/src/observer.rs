//! The one observer hook of every runner: records, progress, cancellation, logging.

use crate::dwell::ConfigurationData;
use crate::record::Record;

/// Whether a run goes on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    /// Go on.
    Continue,
    /// Stop after this tick: the runner returns [`crate::ExpError::Stopped`].
    Stop,
}

/// Where a run is, shown at the end of each segment (servo and identification: every `segment`
/// seconds of robot time; dwells: after each configuration) and once at the end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Work done: seconds of the run, or configurations finished.
    pub done: f64,
    /// Total work in the same unit.
    pub total: f64,
    /// Robot time (s).
    pub time: f64,
    /// The run has finished (the last call).
    pub finished: bool,
}

/// Sees every tick of a run and its progress. Both methods default to doing nothing.
///
/// A logger flushes at [`Observer::progress`] (so a crash loses at most one segment); a binding checks
/// for Ctrl-C there and returns [`Flow::Stop`].
pub trait Observer {
    /// One tick, after the robot stepped.
    fn record(&mut self, _record: &Record) -> Flow {
        Flow::Continue
    }
    /// The end of a segment (or of the run, `finished`).
    fn progress(&mut self, _progress: &Progress) -> Flow {
        Flow::Continue
    }
    /// A calibration dwell finished: configuration `index`, its window [first, last tick time] (s) and
    /// its means (called before the matching [`Observer::progress`]).
    fn dwell(&mut self, _index: usize, _window: [f64; 2], _data: &ConfigurationData) -> Flow {
        Flow::Continue
    }
}

impl Observer for () {}

impl<O: Observer + ?Sized> Observer for &mut O {
    fn record(&mut self, record: &Record) -> Flow {
        (**self).record(record)
    }
    fn progress(&mut self, progress: &Progress) -> Flow {
        (**self).progress(progress)
    }
    fn dwell(&mut self, index: usize, window: [f64; 2], data: &ConfigurationData) -> Flow {
        (**self).dwell(index, window, data)
    }
}

/// Both observers see everything; the run stops if either asks.
impl<A: Observer, B: Observer> Observer for (A, B) {
    fn record(&mut self, record: &Record) -> Flow {
        let a = self.0.record(record);
        let b = self.1.record(record);
        either(a, b)
    }
    fn progress(&mut self, progress: &Progress) -> Flow {
        let a = self.0.progress(progress);
        let b = self.1.progress(progress);
        either(a, b)
    }
    fn dwell(&mut self, index: usize, window: [f64; 2], data: &ConfigurationData) -> Flow {
        let a = self.0.dwell(index, window, data);
        let b = self.1.dwell(index, window, data);
        either(a, b)
    }
}

fn either(a: Flow, b: Flow) -> Flow {
    if a == Flow::Stop || b == Flow::Stop {
        Flow::Stop
    } else {
        Flow::Continue
    }
}

/// Collects every record in memory.
impl Observer for Vec<Record> {
    fn record(&mut self, record: &Record) -> Flow {
        self.push(*record);
        Flow::Continue
    }
}
