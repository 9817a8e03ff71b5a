//! Wall-clock times of the stages of a render, for `--timings` reports.

use std::fmt;
use std::time::{Duration, Instant};

/// Named stage durations in the order they ran.
///
/// ```
/// let mut t = glint_core::Timings::default();
/// let x = t.time("sum", || (1..=10).sum::<u32>());
/// assert_eq!(x, 55);
/// assert_eq!(t.stages()[0].0, "sum");
/// assert!(t.to_string().contains("sum"));
/// ```
#[derive(Clone, Debug, Default)]
pub struct Timings {
    stages: Vec<(&'static str, Duration)>,
}

impl Timings {
    /// Runs `f`, recording its wall time as `stage`, and returns its result.
    pub fn time<T>(&mut self, stage: &'static str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        self.record(stage, start.elapsed());
        out
    }

    /// Records `duration` for `stage` (added to the stage's time if it ran before).
    pub fn record(&mut self, stage: &'static str, duration: Duration) {
        match self.stages.iter_mut().find(|(s, _)| *s == stage) {
            Some((_, d)) => *d += duration,
            None => self.stages.push((stage, duration)),
        }
    }

    /// Appends `other`'s stages (e.g. a field's, glint-volume's `Field::timings`).
    pub fn extend(&mut self, other: &Timings) {
        for &(s, d) in &other.stages {
            self.record(s, d);
        }
    }

    /// The stages and their durations, in the order they first ran.
    pub fn stages(&self) -> &[(&'static str, Duration)] {
        &self.stages
    }

    /// The time of `stage`, zero when it did not run.
    pub fn get(&self, stage: &str) -> Duration {
        self.stages
            .iter()
            .filter(|(s, _)| *s == stage)
            .map(|(_, d)| *d)
            .sum()
    }

    /// The sum of the stages.
    pub fn total(&self) -> Duration {
        self.stages.iter().map(|(_, d)| *d).sum()
    }
}

impl fmt::Display for Timings {
    /// One line per stage, `stage  12.34 ms`, then the total.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let w = self.stages.iter().map(|(s, _)| s.len()).max().unwrap_or(0);
        let w = w.max("total".len());
        for (s, d) in &self.stages {
            writeln!(f, "{s:<w$} {:9.2} ms", d.as_secs_f64() * 1e3)?;
        }
        write!(
            f,
            "{:<w$} {:9.2} ms",
            "total",
            self.total().as_secs_f64() * 1e3
        )
    }
}
