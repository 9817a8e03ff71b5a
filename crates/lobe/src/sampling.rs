//! Importance sampling of every lobe: `sample(u1, u2) -> direction`, `pdf(direction)`
//! and `eval(direction)`, consistent with each other, in the manner of pbrt-v4's BxDF
//! interface (`f`, `Sample_f`, `PDF`; src/pbrt/bxdfs.h).
//!
//! A lobe is a function of `c = cos γ` around an axis, so in the frame whose `z` is
//! the axis a direction is drawn as `x = 1 - cos γ` from the lobe's marginal (solid
//! angle is `dω = dc dφ`, so the density in `c` is the lobe itself) and an azimuth
//! `φ = 2π u2`. Writing `x` rather than `c` keeps sharp lobes precise in f32 (`sin γ
//! = sqrt(x(2-x))`). With `m = 2^v`, `a` the power fits' coefficient:
//!
//! | lobe | `x` from `u` | cost |
//! |---|---|---|
//! | `exact` | `1 - (1-u)^(1/(n+1))` | one `powf` |
//! | `k`, `g`, `minimax`, `a >= 1/2` | `(1 - (1-u)^(1/(m+1)))/a` | one `powf` |
//! | the same, `a < 1/2` (support cut at `c = -1`) | `-expm1(ln1p(-s·u)/(m+1))/a`, `s = 1 - (1-2a)^(m+1)` | `ln_1p` + `exp_m1` |
//! | `gauss` | `-ln1p(-s·u)/n`, `s = 1 - e^(-2n)` | one `ln_1p` |
//! | `schlick` | tabulated inverse CDF ([`tabulated`]) | table lookup + one `sqrt` |
//!
//! The closed-form pdfs are `eval(c) / ∫ eval dω`
//! ([`Lobe::sphere_integral`]), so `eval / pdf` is a constant and the estimator has
//! no variance from the lobe's shape. See docs/lobes.md, "Sampling", for the
//! derivations and the measured figures.

use std::f64::consts::TAU;
use std::sync::Arc;

use crate::coefficient::power_support_mass;
use crate::lobe::Real;
use crate::{Lobe, LobeKind};

mod scatter;
mod specular;
pub(crate) mod tabulated;

pub use scatter::{blinn_jacobian, reflect_about, Frame, LobeSample, Scatter};
pub use specular::{SpecularSampler, DEFENSIVE_SHARE, DOMINANCE};
use tabulated::{PiecewiseLinear, TABLE_TOLERANCE};

/// Bound on the relative difference between a tabulated sampler's density and the
/// lobe's own normalised density: the table's chord is within 1e-4 of the lobe
/// (relative), and normalising the chord instead of the lobe can add as
/// much again. Tested in `crates/lobe/tests/sampling.rs`.
pub const TABULATED_PDF_MAX_REL_ERROR: f64 = 2.0 * TABLE_TOLERANCE;

/// A lobe around an axis that can be sampled: the three functions a path tracer
/// needs, in the frame whose `z` is the axis (the mirror direction R for Phong
/// geometry, the normal for Blinn, where what is drawn is the half vector; see
/// [`Scatter`] for both in world space).
///
/// Implementors give the three functions of `cos γ`; the direction forms are
/// provided. Every implementation keeps them consistent: `pdf_cos` is exactly the
/// density of the directions `sample` draws, and `sample` never draws a direction
/// where `pdf_cos` is 0.
pub trait AxisLobe<T: Real> {
    /// The lobe's value at `c = cos γ` (the `f` of an estimator `f / pdf`).
    fn eval_cos(&self, c: T) -> T;

    /// The density per steradian of [`sample`](Self::sample)'s directions at
    /// `c = cos γ`.
    fn pdf_cos(&self, c: T) -> T;

    /// `x = 1 - cos γ` of a sample, from `u ∈ [0, 1)` (values outside are clamped,
    /// NaN gives 0): the inverse CDF of the lobe's marginal in `x`.
    fn sample_one_minus_cos(&self, u: T) -> T;

    /// A direction in the axis frame (`z` is the axis) from two uniform numbers in
    /// `[0, 1)`: `u1` picks `cos γ`, `u2` the azimuth.
    #[inline]
    fn sample(&self, u1: T, u2: T) -> [T; 3] {
        direction(self.sample_one_minus_cos(u1), u2)
    }

    /// The density per steradian of a unit direction in the axis frame.
    #[inline]
    fn pdf(&self, dir: [T; 3]) -> T {
        self.pdf_cos(dir[2])
    }

    /// The lobe's value at a unit direction in the axis frame.
    #[inline]
    fn eval(&self, dir: [T; 3]) -> T {
        self.eval_cos(dir[2])
    }
}

/// The unit direction at `x = 1 - cos γ` and azimuth `2π u2` around `z`.
#[inline]
pub fn direction<T: Real>(x: T, u2: T) -> [T; 3] {
    let one = T::one();
    let s = (x * (T::from_f64(2.0) - x)).max(T::zero()).sqrt();
    let (sin_phi, cos_phi) = (T::from_f64(TAU) * u2).sin_cos();
    [s * cos_phi, s * sin_phi, one - x]
}

/// `u` clamped to `[0, 1)`; NaN gives 0.
#[inline]
pub(crate) fn unit_open<T: Real>(u: T) -> T {
    let below_one = T::one() - T::epsilon() / T::from_f64(2.0);
    if u > T::zero() {
        u.min(below_one)
    } else {
        T::zero()
    }
}

/// How a lobe's `x = 1 - cos γ` is drawn.
#[derive(Clone, Debug, PartialEq)]
enum Method<T> {
    /// Uniform on `0 <= x < x_max` (`x_max` = 1: the hemisphere; 2: the sphere) with
    /// constant density `pdf`: lobes that are constant there (`exact` at `n = 0`,
    /// `schlick` at `n = 0`) or within 1e-12 of it.
    Uniform { x_max: T, pdf: T },
    /// `cos γ = (1-u)^(1/(n+1))`.
    Exact { inv_n1: T },
    /// The power form with `a >= 1/2`: `x = (1 - (1-u)^(1/(m+1)))/a`.
    Power { inv_a: T, inv_m1: T },
    /// The power form with `a < 1/2`, cut at `x = 2`:
    /// `x = -expm1(ln1p(-s u)/(m+1))/a`.
    PowerCut { inv_a: T, inv_m1: T, s: T },
    /// `exp(-n x)` on `[0, 2]`: `x = -ln1p(-s u)/n`.
    Exponential { inv_n: T, s: T },
    /// A tabulated inverse CDF (Schlick).
    Table(Arc<PiecewiseLinear>),
}

/// A lobe with its sampler: [`AxisLobe`] for every [`LobeKind`].
///
/// Built once per lobe (Schlick's table takes well under a millisecond; the rest is
/// a few divisions), then shared by every thread; sampling allocates nothing.
///
/// ```
/// use glint_lobe::{AxisLobe, Lobe, LobeKind, LobeSampler};
///
/// let k = Lobe::<f32>::new(LobeKind::EnergyFit, 100.0, 4).unwrap();
/// let s = LobeSampler::new(&k);
/// let dir = s.sample(0.3, 0.7); // around z
/// assert!((dir.iter().map(|d| d * d).sum::<f32>() - 1.0).abs() < 1e-6);
/// // eval / pdf is the lobe's integral over the sphere, 2π/(n+1) for K_v.
/// let weight = s.eval(dir) / s.pdf(dir);
/// assert!((weight - std::f32::consts::TAU / 101.0).abs() < 1e-5);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct LobeSampler<T> {
    lobe: Lobe<T>,
    method: Method<T>,
    /// `1 / ∫ eval dω` for the closed forms (`pdf = eval · inv_integral`).
    inv_integral: T,
}

impl<T: Real> LobeSampler<T> {
    /// The sampler of `lobe`. Never fails: a valid [`Lobe`] always has one.
    pub fn new(lobe: &Lobe<T>) -> Self {
        let integral = lobe.sphere_integral();
        let t = T::from_f64;
        let n = lobe.n();
        let uniform = |x_max: f64| Method::Uniform {
            x_max: t(x_max),
            pdf: t(1.0 / (TAU * x_max)),
        };
        let method = match lobe.kind() {
            LobeKind::Exact if n == 0.0 => uniform(2.0),
            LobeKind::Exact => Method::Exact {
                inv_n1: t(1.0 / (n + 1.0)),
            },
            LobeKind::EnergyFit | LobeKind::SlopeFit | LobeKind::Minimax => {
                let a = lobe.coefficient().unwrap_or(0.0);
                let m1 = f64::from(1u32 << lobe.v()) + 1.0;
                if a * m1 < 1e-12 {
                    // Constant to within 2a(m+1) < 2e-12 on the sphere.
                    uniform(2.0)
                } else if a >= 0.5 {
                    Method::Power {
                        inv_a: t(1.0 / a),
                        inv_m1: t(1.0 / m1),
                    }
                } else {
                    Method::PowerCut {
                        inv_a: t(1.0 / a),
                        inv_m1: t(1.0 / m1),
                        s: t(power_support_mass(a, 1 << lobe.v())),
                    }
                }
            }
            LobeKind::Gauss if n < 1e-12 => uniform(2.0),
            LobeKind::Gauss => Method::Exponential {
                inv_n: t(1.0 / n),
                s: t(-(-2.0 * n).exp_m1()),
            },
            LobeKind::Schlick if n == 0.0 => uniform(1.0),
            LobeKind::Schlick => {
                // c / (n(1-c) + c) at c = 1 - x, as Lobe::eval computes it.
                let f = move |x: f64| {
                    let c = 1.0 - x;
                    if c > 0.0 {
                        c / (n * x + c)
                    } else {
                        0.0
                    }
                };
                Method::Table(Arc::new(PiecewiseLinear::build(f, 1.0, TABLE_TOLERANCE)))
            }
        };
        LobeSampler {
            lobe: *lobe,
            method,
            inv_integral: t(1.0 / integral),
        }
    }

    /// The lobe sampled.
    pub fn lobe(&self) -> &Lobe<T> {
        &self.lobe
    }

    /// `∫ eval dω` over the sphere ([`Lobe::sphere_integral`]): for the closed-form
    /// samplers, `eval / pdf` equals it at every sampled direction.
    pub fn integral(&self) -> f64 {
        self.lobe.sphere_integral()
    }

    /// Whether the sampler is a tabulated inverse CDF (Schlick's) rather than a
    /// closed form.
    pub fn is_tabulated(&self) -> bool {
        matches!(self.method, Method::Table(_))
    }

    /// For a tabulated sampler: its number of bins and the largest relative error of
    /// its density's chord against the lobe found while building (at most 1e-4; the
    /// normalised density is within [`TABULATED_PDF_MAX_REL_ERROR`] of the lobe's).
    pub fn table_stats(&self) -> Option<(usize, f64)> {
        match &self.method {
            Method::Table(t) => Some((t.bins(), t.checked_error())),
            _ => None,
        }
    }

    /// For a tabulated sampler, its nodes `x = 1 - cos γ` and the density per unit
    /// `x` at them (for tests and reports).
    pub fn table_nodes(&self) -> Option<(&[f64], &[f64])> {
        match &self.method {
            Method::Table(t) => Some(t.nodes()),
            _ => None,
        }
    }
}

impl<T: Real> AxisLobe<T> for LobeSampler<T> {
    #[inline]
    fn eval_cos(&self, c: T) -> T {
        self.lobe.eval(c)
    }

    #[inline]
    fn pdf_cos(&self, c: T) -> T {
        match &self.method {
            Method::Uniform { x_max, pdf } => {
                // The whole sphere (c clamped to [-1, 1] as eval does), or c > 0.
                // NaN fails both tests and gives 0.
                let whole = *x_max >= T::from_f64(2.0);
                if (whole && !c.is_nan()) || T::one() - c < *x_max {
                    *pdf
                } else {
                    T::zero()
                }
            }
            Method::Table(t) => {
                // c clamped to [-1, 1] as eval does; NaN stays NaN and gives 0.
                let c = c.to_f64().unwrap_or(f64::NAN);
                T::from_f64(t.pdf(1.0 - c.clamp(-1.0, 1.0)) / TAU)
            }
            _ => self.lobe.eval(c) * self.inv_integral,
        }
    }

    #[inline]
    fn sample_one_minus_cos(&self, u: T) -> T {
        let u = unit_open(u);
        let one = T::one();
        let two = T::from_f64(2.0);
        match &self.method {
            // u < 1, so x < x_max: Schlick at n = 0 is 0 at c = 0.
            Method::Uniform { x_max, .. } => u * *x_max,
            // c = (1-u)^(1/(n+1)) >= 2^-24 (f32): x = 1 - c < 1 keeps c > 0.
            Method::Exact { inv_n1 } => one - (one - u).powf(*inv_n1),
            Method::Power { inv_a, inv_m1 } => (one - (one - u).powf(*inv_m1)) * *inv_a,
            Method::PowerCut { inv_a, inv_m1, s } => {
                (-((-*s * u).ln_1p() * *inv_m1).exp_m1() * *inv_a).min(two)
            }
            Method::Exponential { inv_n, s } => (-(-*s * u).ln_1p() * *inv_n).min(two),
            Method::Table(t) => {
                let x = T::from_f64(t.sample(u.to_f64().unwrap_or(0.0)));
                // The density is 0 at x = 1 (c = 0); keep c > 0 after rounding to T.
                x.min(one - T::epsilon() / two)
            }
        }
    }
}
