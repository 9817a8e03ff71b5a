//! Throughput measurement of the batch kernels, shared by the benchmark
//! (`crates/lobe/benches/lobes.rs`) and `glint bench lobes`.
//!
//! Each [`Workload`] maps a slice of cosines to a slice of results; [`measure`] times
//! it and reports evaluations per second, single thread. The references run in the
//! same process on the same data: libm `powf` (`max(c, 0)^n`, one call per element)
//! and a plain copy of the same bytes (4 bytes read and 4 written per element, the
//! memory-bandwidth bound of any kernel).
//!
//! ```
//! use std::time::Duration;
//! use glint_lobe::measure::{cosines, measure, Workload};
//! use glint_lobe::{Lobe, LobeKind};
//!
//! let k = Lobe::<f32>::new(LobeKind::EnergyFit, 100.0, 4).unwrap();
//! let cos = cosines(1024);
//! let rate = measure(&Workload::Lobe(k), &cos, Duration::from_millis(5));
//! assert!(rate.evals_per_sec > 0.0);
//! ```

use std::hint::black_box;
use std::time::{Duration, Instant};

use crate::Lobe;

/// What to time.
#[derive(Clone, Copy, Debug)]
pub enum Workload {
    /// [`Lobe::eval_slice`] (the SIMD kernels for f32).
    Lobe(Lobe<f32>),
    /// [`eval_slice_with`](crate::eval_slice_with) on a given path (which must be
    /// supported; unsupported paths leave the output untouched).
    LobeOnPath(Lobe<f32>, crate::KernelPath),
    /// [`Lobe::eval_slice_scalar`]: `eval` one element at a time.
    LobeScalar(Lobe<f32>),
    /// libm's `powf`: `max(c, 0)^n`, one call per element.
    LibmPowf {
        /// The exponent.
        n: f32,
    },
    /// `out.copy_from_slice(cos)`: the same bytes moved, nothing computed.
    Copy,
}

impl Workload {
    /// Runs the workload once over `cos`.
    #[inline]
    pub fn run(&self, cos: &[f32], out: &mut [f32]) {
        match self {
            Workload::Lobe(lobe) => lobe.eval_slice(cos, out),
            Workload::LobeOnPath(lobe, path) => {
                // Only an unsupported path or a length mismatch can fail; both leave
                // `out` as it was, which the caller sees as a zero-cost run.
                let _ = crate::eval_slice_with(lobe, *path, cos, out);
            }
            Workload::LobeScalar(lobe) => lobe.eval_slice_scalar(cos, out),
            Workload::LibmPowf { n } => {
                let n = black_box(*n);
                for (o, &c) in out.iter_mut().zip(cos) {
                    *o = c.max(0.0).powf(n);
                }
            }
            Workload::Copy => out.copy_from_slice(cos),
        }
    }
}

/// The result of [`measure`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rate {
    /// Evaluations (elements) per second, from the fastest sample.
    pub evals_per_sec: f64,
    /// Evaluations per second, median sample.
    pub median_evals_per_sec: f64,
    /// Number of timed samples.
    pub samples: usize,
}

/// Fewest timed samples per measurement.
pub const MIN_SAMPLES: usize = 7;

/// Target length of one timed sample. Short samples are rarely interrupted by other
/// processes, and the fastest one is reported (interruptions only ever slow a
/// sample down), so short samples give stable figures on a shared machine.
pub const SAMPLE_TIME: Duration = Duration::from_millis(1);

/// Times `workload` over `cos` for about `budget` in total (after a warm-up of a
/// tenth of it) in samples of about [`SAMPLE_TIME`] (at least one call and at least
/// [`MIN_SAMPLES`] samples) and returns its throughput.
///
/// Input and output are copied to / allocated at 64-byte aligned addresses, as a
/// renderer's buffers would be, so results do not depend on where the allocator
/// happened to put them.
pub fn measure(workload: &Workload, cos: &[f32], budget: Duration) -> Rate {
    let mut input_buf = vec![0.0f32; cos.len() + 16];
    let at = input_buf.as_ptr().align_offset(64).min(16);
    input_buf[at..at + cos.len()].copy_from_slice(cos);
    let cos = &input_buf[at..at + cos.len()];
    let mut out_buf = vec![0.0f32; cos.len() + 16];
    let at = out_buf.as_ptr().align_offset(64).min(16);
    let out = &mut out_buf[at..at + cos.len()];
    let len = cos.len().max(1);
    // Warm up (caches, page faults, CPU frequency) and size the samples.
    let start = Instant::now();
    let mut calls = 0u64;
    while calls == 0 || start.elapsed() < budget / 10 {
        workload.run(black_box(cos), black_box(&mut *out));
        calls += 1;
    }
    let per_call = start.elapsed().as_secs_f64() / calls as f64;
    let reps = ((SAMPLE_TIME.as_secs_f64() / per_call.max(1e-9)) as u64).max(1);
    let sample = per_call * reps as f64;
    let samples = ((budget.as_secs_f64() / sample) as usize).max(MIN_SAMPLES);
    let mut rates: Vec<f64> = (0..samples)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..reps {
                workload.run(black_box(cos), black_box(&mut *out));
            }
            let secs = t.elapsed().as_secs_f64().max(1e-12);
            (reps as f64 * len as f64) / secs
        })
        .collect();
    black_box(&*out);
    rates.sort_by(f64::total_cmp);
    Rate {
        evals_per_sec: rates[samples - 1],
        median_evals_per_sec: rates[samples / 2],
        samples,
    }
}

/// `len` cosines of angles spread evenly over `[0°, 90°]` (where a lobe is
/// evaluated in a renderer), in a scrambled order so no branch predictor or
/// pattern helps a workload.
pub fn cosines(len: usize) -> Vec<f32> {
    let step = 0.618_033_988_749_894_9_f64; // golden ratio fraction: low-discrepancy
    (0..len)
        .map(|i| {
            let u = (i as f64 * step).fract();
            (u * std::f64::consts::FRAC_PI_2).cos() as f32
        })
        .collect()
}
