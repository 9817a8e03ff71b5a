//! Exhaustive error measurement of a [`Unit`] against the exact lobe and `cos^n`.
//!
//! Definition (used everywhere in glint-hw): the unit's output code for `k_s·I` at
//! full scale `F = 2^out_bits - 1` is compared with the exact real value `F · L(c, n)`,
//! where `c` is the exact value of the input code and `L` is
//!
//! - [`Reference::Lobe`]: the exact f64 power lobe `max(0, 1 - a(n)(1 - c))^(2^v)` with
//!   the ROM's real coefficient `a(n)` (K_v for the energy fit), over every code `c` in
//!   `[-1, 1]`;
//! - [`Reference::Power`]: `cos^n = c^n`, over every code in `[0, 1]` (γ from 0 to 90
//!   degrees, the lobe's domain).
//!
//! The error is `|output - F·L|` in output LSBs, so a perfect unit (the exact value
//! correctly rounded) has an error of at most 0.5 LSB. The maximum is over every code
//! and every `n` of the ROM: exhaustive.

use rayon::prelude::*;

use crate::Unit;

/// Slack added to every bound when comparing, to absorb the f64 reference's own
/// rounding (its relative error is ~1e-13, far below this).
pub const BOUND_SLACK_LSB: f64 = 1e-9;

/// What the output is compared with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Reference {
    /// The exact f64 power lobe with the ROM's real coefficients (K_v for `k`).
    Lobe,
    /// The exact `cos^n`.
    Power,
}

impl Reference {
    /// Short label for tables.
    pub fn label(self) -> &'static str {
        match self {
            Reference::Lobe => "lobe",
            Reference::Power => "cos^n",
        }
    }
}

/// The worst errors for one `n`, in output LSBs.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct ErrorsAtN {
    /// Max error against the exact lobe, over codes in `[-1, 1]`.
    pub lobe: f64,
    /// The `cos` code where `lobe` occurs.
    pub lobe_cos: i64,
    /// Max error against `cos^n`, over codes in `[0, 1]`.
    pub power: f64,
    /// The `cos` code where `power` occurs.
    pub power_cos: i64,
    /// Max error against `cos^n` of an ideal unit: the exact lobe correctly rounded to
    /// the output code. Pure approximation error; no hardware can do better with this
    /// lobe except by luck.
    pub ideal_power: f64,
}

/// The exhaustive measurement of a unit: the worst errors for every `n`.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// Index `n`.
    pub per_n: Vec<ErrorsAtN>,
    /// Number of `(cos, n)` points evaluated.
    pub points: u64,
}

/// A worst case: the error, and where.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Worst {
    /// Error in output LSBs.
    pub error: f64,
    /// Shininess `n`.
    pub n: u32,
    /// `cos` code.
    pub cos: i64,
}

impl Measurement {
    /// Worst error against the exact lobe over all `n` in `ns`.
    pub fn worst_lobe(&self, ns: std::ops::RangeInclusive<u32>) -> Worst {
        self.worst(ns, |e| (e.lobe, e.lobe_cos))
    }

    /// Worst error against `cos^n` over all `n` in `ns`.
    pub fn worst_power(&self, ns: std::ops::RangeInclusive<u32>) -> Worst {
        self.worst(ns, |e| (e.power, e.power_cos))
    }

    /// Worst error of the ideal unit against `cos^n` over all `n` in `ns`.
    pub fn worst_ideal_power(&self, ns: std::ops::RangeInclusive<u32>) -> Worst {
        self.worst(ns, |e| (e.ideal_power, 0))
    }

    fn worst(
        &self,
        ns: std::ops::RangeInclusive<u32>,
        pick: impl Fn(&ErrorsAtN) -> (f64, i64),
    ) -> Worst {
        let mut best = Worst {
            error: 0.0,
            n: *ns.start(),
            cos: 0,
        };
        for n in ns {
            if let Some(e) = self.per_n.get(n as usize) {
                let (error, cos) = pick(e);
                if error > best.error {
                    best = Worst { error, n, cos };
                }
            }
        }
        best
    }
}

/// Everything the inner loop needs, read once.
struct Prepared<'a> {
    unit: &'a Unit,
    coeffs: &'a [f64],
    v: u32,
    one: i64,
    full: u64,
    full_f: f64,
}

impl<'a> Prepared<'a> {
    fn new(unit: &'a Unit) -> Self {
        Prepared {
            unit,
            coeffs: unit.rom().exact(),
            v: unit.config().v,
            one: unit.cos_one(),
            full: unit.full_scale(),
            full_f: unit.full_scale() as f64,
        }
    }

    /// Calls `visit(n, output, exact lobe · F, c^n · F)` for every `n` of the ROM at
    /// the code `cos`; `c^n` by repeated multiplication (relative error <= n·2^-53).
    #[inline(always)]
    fn visit(&self, cos: i64, mut visit: impl FnMut(usize, f64, f64, f64)) {
        let c = cos as f64 / self.one as f64;
        let t = (self.one - cos) as f64 / self.one as f64;
        let mut pw = 1.0f64;
        for (n, &a) in self.coeffs.iter().enumerate() {
            let out = self
                .unit
                .output_code(self.unit.lobe_code(cos, n as u32), self.full)
                as f64;
            let mut l = 1.0 - a * t;
            if l <= 0.0 {
                l = 0.0;
            } else {
                for _ in 0..self.v {
                    l *= l;
                }
            }
            visit(n, out, l * self.full_f, pw * self.full_f);
            pw *= c;
        }
    }
}

/// Measures `unit` exhaustively (every code in `[-1, 1]`, every `n`, `k_s·I` at full
/// scale), in parallel. The work is [`Unit::exhaustive_points`], which grows as
/// `2^(cos_bits + n_bits)`: callers taking widths from users should bound it first
/// (`glint hw check` refuses more than `2^32` points).
pub fn measure(unit: &Unit) -> Measurement {
    let p = Prepared::new(unit);
    let count = p.coeffs.len();
    let per_n = (-p.one..=p.one)
        .into_par_iter()
        .fold(
            || vec![ErrorsAtN::default(); count],
            |mut acc, cos| {
                p.visit(cos, |n, out, lobe, power| {
                    let e = &mut acc[n];
                    let el = (out - lobe).abs();
                    if el > e.lobe {
                        e.lobe = el;
                        e.lobe_cos = cos;
                    }
                    if cos >= 0 {
                        let ep = (out - power).abs();
                        if ep > e.power {
                            e.power = ep;
                            e.power_cos = cos;
                        }
                        // Round half up, like the hardware's Nearest.
                        let ideal = ((lobe + 0.5).floor() - power).abs();
                        e.ideal_power = e.ideal_power.max(ideal);
                    }
                });
                acc
            },
        )
        .reduce(
            || vec![ErrorsAtN::default(); count],
            |mut a, b| {
                for (x, y) in a.iter_mut().zip(b) {
                    // Ties keep the smaller code, so the result does not depend on how
                    // rayon split the work.
                    if y.lobe > x.lobe || (y.lobe == x.lobe && y.lobe_cos < x.lobe_cos) {
                        x.lobe = y.lobe;
                        x.lobe_cos = y.lobe_cos;
                    }
                    if y.power > x.power || (y.power == x.power && y.power_cos < x.power_cos) {
                        x.power = y.power;
                        x.power_cos = y.power_cos;
                    }
                    x.ideal_power = x.ideal_power.max(y.ideal_power);
                }
                a
            },
        );
    Measurement {
        per_n,
        points: u64::try_from(unit.exhaustive_points()).unwrap_or(u64::MAX),
    }
}

/// Whether the unit's error against `reference` stays within `bound_lsb` (plus
/// [`BOUND_SLACK_LSB`]) for every code of the reference's range and every `n` with
/// `include_n[n]` (all `n` if `None`). Stops at the first violation. Up to
/// [`Unit::exhaustive_points`] of work, like [`measure`].
pub fn within(
    unit: &Unit,
    reference: Reference,
    bound_lsb: f64,
    include_n: Option<&[bool]>,
) -> bool {
    let p = Prepared::new(unit);
    let bound = bound_lsb + BOUND_SLACK_LSB;
    let lo = match reference {
        Reference::Lobe => -p.one,
        Reference::Power => 0,
    };
    let keep = |n: usize| match include_n {
        None => true,
        Some(m) => m.get(n).copied().unwrap_or(false),
    };
    !(lo..=p.one).into_par_iter().any(|cos| {
        let mut bad = false;
        p.visit(cos, |n, out, lobe, power| {
            let target = match reference {
                Reference::Lobe => lobe,
                Reference::Power => power,
            };
            if (out - target).abs() > bound && keep(n) {
                bad = true;
            }
        });
        bad
    })
}
