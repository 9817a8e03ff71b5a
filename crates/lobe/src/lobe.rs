//! The closed set of lobes behind one `eval`.

use std::fmt;

use crate::coefficient::{
    energy_fit_coefficient, minimax_coefficient, power_sphere_integral,
    schlick_hemisphere_integral, slope_fit_coefficient,
};

/// Largest shininess exponent accepted. Phong exponents in practice stay below ~1000
/// (the paper's range); 10000 leaves room for very sharp mirrors.
pub const MAX_N: f64 = 10_000.0;

/// Largest `v` accepted, so the fixed power is at most `2^10 = 1024`.
pub const MAX_V: u32 = 10;

/// The floating-point types a [`Lobe`] evaluates in: `f32` and `f64`.
pub trait Real: num_traits::Float + fmt::Debug + Send + Sync + 'static {
    /// Converts from `f64`, rounding to nearest.
    fn from_f64(x: f64) -> Self;
}

impl Real for f32 {
    fn from_f64(x: f64) -> Self {
        x as f32
    }
}

impl Real for f64 {
    fn from_f64(x: f64) -> Self {
        x
    }
}

/// Which lobe: the names users type are `exact`, `k`, `g`, `schlick`, `gauss`, `minimax`
/// (case-insensitive; a few aliases such as `phong`, `energy`, `slope`, `gaussian`).
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Hash,
    PartialOrd,
    Ord,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[strum(
    serialize_all = "lowercase",
    ascii_case_insensitive,
    parse_err_ty = LobeError,
    parse_err_fn = LobeError::unknown_kind
)]
pub enum LobeKind {
    /// `max(c, 0)^n`, the Phong/Blinn reference.
    #[strum(
        to_string = "exact",
        serialize = "phong",
        serialize = "blinn",
        serialize = "pow"
    )]
    Exact,
    /// The paper's energy fit K_v: `a = (n+1)/(2^v+1)`.
    #[strum(to_string = "k", serialize = "energy", serialize = "energy-fit")]
    EnergyFit,
    /// The slope fit G_v (Lyon 1993): `a = n/2^v`.
    #[strum(to_string = "g", serialize = "slope", serialize = "slope-fit")]
    SlopeFit,
    /// Schlick's rational form `c / (n - n·c + c)` for `c > 0`, else 0 (evaluated as
    /// `c / (n(1 - c) + c)`, which does not cancel).
    Schlick,
    /// The spherical-Gaussian form `exp(n·(c - 1))`.
    #[strum(to_string = "gauss", serialize = "gaussian", serialize = "sg")]
    Gauss,
    /// The power form with `a` minimising the maximum absolute error against `cos^n`.
    Minimax,
}

impl LobeKind {
    /// Every kind, in the order tables and plots list them.
    pub const ALL: &'static [LobeKind] = <LobeKind as strum::VariantArray>::VARIANTS;

    /// The names users type, in the order of [`LobeKind::ALL`].
    pub const NAMES: &'static [&'static str] = <LobeKind as strum::VariantNames>::VARIANTS;

    /// The short name users type (`exact`, `k`, `g`, `schlick`, `gauss`, `minimax`).
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// Whether the lobe is a power fit `max(0, 1 - a(1-c))^(2^v)` and so depends on `v`.
    pub fn uses_v(self) -> bool {
        matches!(
            self,
            LobeKind::EnergyFit | LobeKind::SlopeFit | LobeKind::Minimax
        )
    }
}

impl crate::names::Named for LobeKind {
    const WHAT: &'static str = "lobe";
}

/// Why a lobe could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LobeError {
    /// The shininess exponent is NaN, infinite, negative or above [`MAX_N`].
    #[error("invalid shininess n = {0}: expected a finite number in 0..={MAX_N}")]
    InvalidN(f64),
    /// `v` is above [`MAX_V`].
    #[error("invalid v = {0}: expected 0..={MAX_V} (power 2^v at most 1024)")]
    InvalidV(u32),
    /// The lobe name is not one of the known kinds.
    #[error("unknown lobe '{0}': expected one of exact, k, g, schlick, gauss, minimax")]
    UnknownKind(String),
    /// A name that is none of a named enum's ([`crate::names::unknown`] words it).
    #[error("{0}")]
    UnknownName(String),
    /// A [`CosTable`](crate::CosTable) was to be sampled but does not say which
    /// shininess it was made for ([`CosTable::with_shininess`](crate::CosTable::with_shininess)).
    #[error(
        "a cosine table without its shininess n and v cannot be sampled (CosTable::with_shininess)"
    )]
    TableWithoutShininess,
}

impl LobeError {
    /// The error for a lobe name that is none of [`LobeKind`]'s.
    fn unknown_kind(name: &str) -> LobeError {
        LobeError::UnknownKind(name.to_string())
    }
}

/// The evaluation form, with its parameters already converted to `T`.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Form<T> {
    /// `max(c, 0)^n`.
    Exact { n: T },
    /// `max(0, 1 - a(1 - c))^(2^v)`.
    Power { a: T, v: u32 },
    /// `c / (n - n c + c)` for `c > 0`.
    Schlick { n: T },
    /// `exp(n (c - 1))`.
    Gauss { n: T },
}

/// A specular lobe: a validated kind and its parameters, evaluated with [`Lobe::eval`].
///
/// `Lobe` is a small `Copy` value; the render loop holds one and never needs to know
/// which kind it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lobe<T> {
    kind: LobeKind,
    n: f64,
    v: u32,
    a: f64,
    form: Form<T>,
}

impl<T: Real> Lobe<T> {
    /// Builds a lobe of `kind` for shininess `n` and power `2^v`.
    ///
    /// `v` is validated for every kind but only used by the power fits (`k`, `g`,
    /// `minimax`). The minimax fit searches its coefficient here, once (a few ms).
    pub fn new(kind: LobeKind, n: f64, v: u32) -> Result<Self, LobeError> {
        if !n.is_finite() || !(0.0..=MAX_N).contains(&n) {
            return Err(LobeError::InvalidN(n));
        }
        if v > MAX_V {
            return Err(LobeError::InvalidV(v));
        }
        let a = match kind {
            LobeKind::EnergyFit => energy_fit_coefficient(n, v),
            LobeKind::SlopeFit => slope_fit_coefficient(n, v),
            LobeKind::Minimax => minimax_coefficient(n, v),
            LobeKind::Exact | LobeKind::Schlick | LobeKind::Gauss => f64::NAN,
        };
        let tn = T::from_f64(n);
        let form = match kind {
            LobeKind::Exact => Form::Exact { n: tn },
            LobeKind::EnergyFit | LobeKind::SlopeFit | LobeKind::Minimax => Form::Power {
                a: T::from_f64(a),
                v,
            },
            LobeKind::Schlick => Form::Schlick { n: tn },
            LobeKind::Gauss => Form::Gauss { n: tn },
        };
        Ok(Lobe {
            kind,
            n,
            v,
            a,
            form,
        })
    }

    /// The kind of lobe.
    pub fn kind(&self) -> LobeKind {
        self.kind
    }

    /// The shininess exponent `n` it approximates (or is, for `exact`).
    pub fn n(&self) -> f64 {
        self.n
    }

    /// `v`, the power fits' exponent being `2^v`.
    pub fn v(&self) -> u32 {
        self.v
    }

    /// The coefficient `a` of a power fit, `None` for the other kinds.
    pub fn coefficient(&self) -> Option<f64> {
        self.kind.uses_v().then_some(self.a)
    }

    /// `∫ eval dω` over the whole sphere of directions, in closed form (f64).
    ///
    /// `eval` is a function of `c = cos γ` on `[-1, 1]`, so this is `2π ∫_{-1}^{1}
    /// eval(c) dc`. `exact`: `2π/(n+1)` (`4π` at `n = 0`, where `max(c, 0)^0 = 1` on
    /// the whole sphere); the power fits with `x = 1 - c`, `m = 2^v`:
    /// `2π (1 - (1 - a·min(1/a, 2))^(m+1)) / (a(m+1))`, which is `2π/(a(m+1))` wherever
    /// `a >= 1/2`, so `2π/(n+1)` for K_v whenever `n >= (2^v - 1)/2` (docs/lobes.md,
    /// "Sampling"); `schlick`: `2π ((n ln n)/(n-1)^2 - 1/(n-1))` (`π` at `n = 1`);
    /// `gauss`: `2π (1 - e^(-2n))/n`.
    pub fn sphere_integral(&self) -> f64 {
        use std::f64::consts::TAU;
        let n = self.n;
        match self.kind {
            LobeKind::Exact if n == 0.0 => 2.0 * TAU,
            LobeKind::Exact => TAU / (n + 1.0),
            LobeKind::EnergyFit | LobeKind::SlopeFit | LobeKind::Minimax => {
                power_sphere_integral(self.a, 1 << self.v)
            }
            LobeKind::Schlick => TAU * schlick_hemisphere_integral(n),
            LobeKind::Gauss if n == 0.0 => 2.0 * TAU,
            LobeKind::Gauss => TAU * -(-2.0 * n).exp_m1() / n,
        }
    }

    /// Evaluates the lobe at `c = cos γ`.
    ///
    /// `c` is clamped to `[-1, 1]`; NaN gives 0. The result always lies in `[0, 1]`.
    #[inline]
    pub fn eval(&self, c: T) -> T {
        let zero = T::zero();
        let one = T::one();
        if c.is_nan() {
            return zero;
        }
        let c = c.max(-one).min(one);
        let y = match self.form {
            Form::Exact { n } => c.max(zero).powf(n),
            Form::Power { a, v } => {
                let mut b = one - a * (one - c);
                if b <= zero {
                    return zero;
                }
                for _ in 0..v {
                    b = b * b;
                }
                b
            }
            Form::Schlick { n } => {
                if c > zero {
                    // n(1 - c) rather than n - n c: 1 - c is exact for c >= 1/2
                    // (Sterbenz), while n - n c cancels and loses ~log2(n) bits.
                    c / (n * (one - c) + c)
                } else {
                    zero
                }
            }
            Form::Gauss { n } => (n * (c - one)).exp(),
        };
        // The forms above already lie in [0, 1] for c in [-1, 1]; the clamp guards
        // against rounding only (e.g. Schlick's division).
        y.max(zero).min(one)
    }

    /// Evaluates the lobe for every element of `cos` with [`eval`](Self::eval), one
    /// element at a time: the reference the batch kernels are tested against.
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn eval_slice_scalar(&self, cos: &[T], out: &mut [T]) {
        assert_eq!(
            cos.len(),
            out.len(),
            "eval_slice: input and output lengths differ"
        );
        for (o, &c) in out.iter_mut().zip(cos) {
            *o = self.eval(c);
        }
    }
}
