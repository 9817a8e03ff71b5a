//! Sampling a renderer's [`Specular`] term, a closed-form lobe or a table over the
//! quantised cosine (a hardware unit's output for every code).
//!
//! A table has no inverse CDF of its own, so it is sampled as the lobe it was made
//! for, K_v with the table's `n` and `v` ([`CosTable::with_shininess`]), while `eval`
//! stays the table's: the estimator `table(c) / pdf_K(c)` is unbiased wherever the
//! density is positive where the table is, and its weights stay bounded where the
//! table stays within a small factor of K_v. A unit's table of K_v does (it lights a
//! code only where K_v is at least about one output step). A table that exceeds
//! [`DOMINANCE`] times K_v somewhere it is lit (a wider lobe, or codes lit beyond
//! K_v's support `x = 1 - c < 1/a`) gets a defensive mixture instead (Hesterberg,
//! "Weighted average importance sampling and defensive mixture distributions",
//! Technometrics 37(2), 1995): a share [`DEFENSIVE_SHARE`] of the samples is drawn
//! uniformly over the cap the table lights, so no lit direction has a vanishing
//! density and every weight is at most `2π·2 / DEFENSIVE_SHARE`.

use std::f64::consts::TAU;
use std::sync::Arc;

use crate::{CosTable, Lobe, LobeError, LobeKind, Specular};

use super::{unit_open, AxisLobe, LobeSampler};

/// The largest ratio `table / K_v` over the lit codes that K_v sampling alone accepts.
pub const DOMINANCE: f64 = 8.0;

/// The share of uniform samples of the defensive mixture.
pub const DEFENSIVE_SHARE: f32 = 0.01;

/// The uniform component of a defensive mixture: `x = 1 - c` uniform on `[0, x_edge]`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Defensive {
    x_edge: f32,
    /// `DEFENSIVE_SHARE / (2π x_edge)`.
    pdf: f32,
}

/// A [`Specular`] term with its sampler: [`AxisLobe`] with `eval` from the specular
/// term and `sample`/`pdf` from a [`LobeSampler`] (the lobe's own, or K_v's for a
/// table; see the module docs for a table that K_v does not cover).
///
/// ```
/// use glint_lobe::{AxisLobe, CosTable, Lobe, LobeKind, Specular};
///
/// // A Q1.14 table of K_4(60), as a hardware unit would give it.
/// let k = Lobe::<f32>::new(LobeKind::EnergyFit, 60.0, 4).unwrap();
/// let table = CosTable::from_fn(14, |code| k.eval(code as f32 / 16384.0))
///     .unwrap()
///     .with_shininess(60.0, 4);
/// let s = Specular::from(table).sampler().unwrap();
/// assert!(!s.is_defensive());
/// let dir = s.sample(0.4, 0.1);
/// assert!(s.pdf(dir) > 0.0 && s.eval(dir) > 0.0);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct SpecularSampler {
    specular: Specular,
    sampler: LobeSampler<f32>,
    defensive: Option<Defensive>,
}

impl SpecularSampler {
    /// The sampler of `specular`. Errors if it is a table without
    /// [`shininess`](CosTable::shininess), or with an invalid one.
    pub fn new(specular: &Specular) -> Result<SpecularSampler, LobeError> {
        let (sampler, defensive) = match specular {
            Specular::Lobe(l) => (LobeSampler::new(l), None),
            Specular::Table(t) => {
                let (n, v) = t.shininess().ok_or(LobeError::TableWithoutShininess)?;
                let k = Lobe::<f32>::new(LobeKind::EnergyFit, n, v)?;
                (LobeSampler::new(&k), defensive(t, n, v)?)
            }
        };
        Ok(SpecularSampler {
            specular: specular.clone(),
            sampler,
            defensive,
        })
    }

    /// A sampler for a bare table: K_v(n) with the given `n` and `v`.
    pub fn for_table(table: Arc<CosTable>, n: f64, v: u32) -> Result<SpecularSampler, LobeError> {
        let table = Arc::new(Arc::unwrap_or_clone(table).with_shininess(n, v));
        SpecularSampler::new(&Specular::Table(table))
    }

    /// The specular term evaluated.
    pub fn specular(&self) -> &Specular {
        &self.specular
    }

    /// The lobe sampler drawn from (for a table, K_v's).
    pub fn sampler(&self) -> &LobeSampler<f32> {
        &self.sampler
    }

    /// Whether a share of the samples is drawn uniformly over the table's lit cap
    /// (the table is not within [`DOMINANCE`] times K_v where it is lit).
    pub fn is_defensive(&self) -> bool {
        self.defensive.is_some()
    }
}

/// The defensive component a table needs, if any: where some lit code's value
/// exceeds `DOMINANCE` times K_v at the lowest cosine that rounds to the code.
fn defensive(table: &CosTable, n: f64, v: u32) -> Result<Option<Defensive>, LobeError> {
    let Some(first) = table.first_nonzero_code() else {
        return Ok(None);
    };
    let k = Lobe::<f64>::new(LobeKind::EnergyFit, n, v)?;
    let one = 1i32 << table.frac_bits();
    let scale = f64::from(one);
    // Code i holds the cosines within half a code of i / 2^f, clamped to [-1, 1].
    let low_cos = |code: i32| ((f64::from(code) - 0.5) / scale).max(-1.0);
    let dominated = (first..=one).all(|code| {
        let t = f64::from(table.value(code));
        t == 0.0 || t <= DOMINANCE * k.eval(low_cos(code))
    });
    if dominated {
        return Ok(None);
    }
    let x_edge = (1.0 - low_cos(first)) as f32;
    Ok(Some(Defensive {
        x_edge,
        pdf: (f64::from(DEFENSIVE_SHARE) / (TAU * f64::from(x_edge))) as f32,
    }))
}

impl AxisLobe<f32> for SpecularSampler {
    #[inline]
    fn eval_cos(&self, c: f32) -> f32 {
        self.specular.eval(c)
    }

    #[inline]
    fn pdf_cos(&self, c: f32) -> f32 {
        let p = self.sampler.pdf_cos(c);
        match self.defensive {
            None => p,
            Some(d) => {
                let x = 1.0 - c.clamp(-1.0, 1.0);
                let uniform = if x <= d.x_edge { d.pdf } else { 0.0 };
                (1.0 - DEFENSIVE_SHARE) * p + uniform
            }
        }
    }

    #[inline]
    fn sample_one_minus_cos(&self, u: f32) -> f32 {
        match self.defensive {
            None => self.sampler.sample_one_minus_cos(u),
            Some(d) => {
                let u = unit_open(u);
                if u < DEFENSIVE_SHARE {
                    u / DEFENSIVE_SHARE * d.x_edge
                } else {
                    let rest = (u - DEFENSIVE_SHARE) / (1.0 - DEFENSIVE_SHARE);
                    self.sampler.sample_one_minus_cos(rest)
                }
            }
        }
    }
}
