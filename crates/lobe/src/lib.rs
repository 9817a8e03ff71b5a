//! Specular lobes for shading: the exact Phong/Blinn power `cos^n γ` and the cheap
//! approximations of it studied by glint.
//!
//! ```
//! use glint_lobe::{Lobe, LobeKind};
//!
//! // The paper's energy fit K_4 for a shininess of 100.
//! let k = Lobe::<f64>::new(LobeKind::EnergyFit, 100.0, 4).unwrap();
//! let exact = Lobe::<f64>::new(LobeKind::Exact, 100.0, 4).unwrap();
//! let c = 5f64.to_radians().cos();
//! assert!((k.eval(c) - exact.eval(c)).abs() < 0.05);
//! assert_eq!(k.eval(1.0), 1.0);
//!
//! // Bad parameters are rejected with a typed error.
//! assert!(Lobe::<f32>::new(LobeKind::EnergyFit, -1.0, 4).is_err());
//! ```
//!
//! Every lobe maps `c = cos γ` to `[0, 1]`, with value 1 at `c = 1`. The power fits
//! share one form, `f_a(c) = max(0, 1 - a·(1 - c))^(2^v)`, and differ only in `a`:
//! `(n+1)/(2^v+1)` for the energy fit (Pavlov, Romanyuk and Dumenko), `n/2^v` for the
//! slope fit (Lyon 1993), and the value minimising the maximum absolute error for the
//! minimax fit (see [`minimax_coefficient`]).
//!
//! ## Sampling
//!
//! A path tracer samples the lobe as well as evaluating it. [`LobeSampler`] gives every
//! lobe `sample(u1, u2) -> direction`, `pdf(direction)` and `eval(direction)`
//! ([`AxisLobe`]) in the frame whose `z` is the lobe's axis, consistent with each
//! other: closed-form inverse CDFs for `exact`, the power fits and `gauss`, a
//! tabulated one for `schlick` (within [`TABULATED_PDF_MAX_REL_ERROR`] of the lobe,
//! and sampled exactly, so estimates stay unbiased). [`Scatter`] puts a lobe at a
//! scattering event in world space, for Phong (around the mirror direction) or Blinn
//! geometry (the half vector around the normal, with the reflection's Jacobian), and
//! [`Specular::sampler`] samples a hardware unit's table as K_v. K_v's integral over
//! the sphere is `2π/(n+1)`, that of `cos^n`, for every `n >= (2^v - 1)/2`
//! ([`Lobe::sphere_integral`]). docs/lobes.md ("Sampling") has the derivations and
//! the measured figures.
//!
//! ```
//! use glint_lobe::{AxisLobe, Geometry, Lobe, LobeKind, LobeSampler, Scatter};
//!
//! let k = Lobe::<f32>::new(LobeKind::EnergyFit, 100.0, 4).unwrap();
//! let sampler = LobeSampler::new(&k);
//!
//! // One scattering event: Blinn geometry at a normal, seen from `wo`.
//! let at = Scatter::new(Geometry::Blinn, [0.0, 0.0, 1.0], [0.6, 0.0, 0.8]).unwrap();
//! let (u1, u2) = (0.37, 0.81); // from the caller's random numbers
//! if let Some(s) = at.sample(&sampler, u1, u2) {
//!     // The estimator's weight for the lobe: value / pdf.
//!     let weight = s.value / s.pdf;
//!     assert!(weight.is_finite() && weight > 0.0);
//!     assert!((at.pdf(&sampler, s.wi) - s.pdf).abs() <= 1e-3 * s.pdf);
//! }
//!
//! // Energy: K_v integrates to 2π/(n+1) over the sphere, as cos^n does.
//! assert!((k.sphere_integral() - std::f64::consts::TAU / 101.0).abs() < 1e-12);
//! ```

#![warn(missing_docs)]

mod batch;
mod coefficient;
mod geometry;
mod lobe;
pub mod names;
mod sampling;
mod table;

pub use batch::measure;
pub use batch::{eval_slice_with, pow_slice, BatchError, KernelPath};
pub use coefficient::{
    energy_fit_coefficient, golden_max, max_abs_error, minimax_coefficient, power_lobe_integral,
    slope_fit_coefficient, ErrorPeak,
};
pub use geometry::{blinn_cos, phong_cos, reflect, Geometry};
pub use lobe::{Lobe, LobeError, LobeKind, Real, MAX_N, MAX_V};
pub use sampling::{
    blinn_jacobian, direction, reflect_about, AxisLobe, Frame, LobeSample, LobeSampler, Scatter,
    SpecularSampler, DEFENSIVE_SHARE, DOMINANCE, TABULATED_PDF_MAX_REL_ERROR,
};
pub use table::{CosTable, Specular, TableError, MAX_TABLE_FRAC_BITS};
