//! Least-squares slope of the potentiometer angles between two camera frames
//! ([`super::ServoConfig::potentiometer_rate`]).

use rss6_core::Vec6;

/// Running sums of a least-squares line θ(t) = a + b t per joint (t relative to the last frame).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct RateFit {
    n: f64,
    st: f64,
    stt: f64,
    sy: Vec6,
    sty: Vec6,
    last: Vec6,
}

impl RateFit {
    /// Adds a sample if the reading changed (the potentiometers update every other joint tick).
    pub(super) fn add(&mut self, t: f64, theta: &Vec6) {
        if self.n > 0.0 && *theta == self.last {
            return;
        }
        self.last = *theta;
        self.n += 1.0;
        self.st += t;
        self.stt += t * t;
        self.sy += theta;
        self.sty += theta * t;
    }

    /// Slope b per joint (rad/s) and Σ(t − t̄)² (s²), if at least 3 samples spread in time.
    pub(super) fn slope(&self) -> Option<(Vec6, f64)> {
        let sxx = self.stt - self.st * self.st / self.n.max(1.0);
        if self.n < 3.0 || sxx <= 0.0 {
            return None;
        }
        let b = (self.sty - self.sy * (self.st / self.n)) / sxx;
        Some((b, sxx))
    }

    pub(super) fn clear(&mut self) {
        let last = self.last;
        *self = RateFit::default();
        self.last = last;
    }
}
