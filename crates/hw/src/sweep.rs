//! Width exploration: the smallest per-stage widths that keep the output within a
//! bound, checked exhaustively.
//!
//! Method, for one `v` and one target (a [`Reference`] and a bound in output LSBs):
//!
//! 1. Start every internal fraction width (ROM1 fraction, MUL/base, each BMUL stage)
//!    at [`START_FRAC`] bits and measure exhaustively. For `cos^n`, the target is only
//!    asked for the `n` where an ideal unit (exact lobe, correctly rounded) meets it;
//!    the other `n` are reported as infeasible, since no width can fix the
//!    approximation error of the lobe itself.
//! 2. Binary-search the smallest uniform fraction width `W` (all stages equal) that
//!    meets the target.
//! 3. Greedily, stage by stage from ROM1 to the last squaring, binary-search the
//!    smallest width of that stage with the others fixed.
//!
//! Every check is exhaustive ([`crate::within`]: every code, every `n`), so the
//! configuration reported always meets the target. The binary searches assume that a
//! wider stage is never worse, which rounding can occasionally violate by a hair, and
//! the greedy order finds a small, not necessarily the smallest, total; both are
//! stated in `docs/hardware.md`.

use std::fmt::Write as _;
use std::time::Instant;

use crate::accuracy::{measure, within, Reference, BOUND_SLACK_LSB};
use crate::{rom::coefficient_int_bits, Config, HwError, Unit};

/// Fraction width every internal stage starts from (well above what any target
/// needs; the 64-bit registers allow up to ~55 for the MUL stage).
pub const START_FRAC: u32 = 40;

/// What a sweep row asks for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    /// Compared with what.
    pub reference: Reference,
    /// Maximum error in output LSBs.
    pub bound: f64,
}

/// Internal fraction widths, in pipeline order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Widths {
    /// ROM1 word fraction bits (the word is `coef_int + coef_frac` bits).
    pub coef_frac: u32,
    /// MUL output / base fraction bits.
    pub mul_frac: u32,
    /// Each BMUL stage's fraction bits.
    pub square_frac: Vec<u32>,
}

impl Widths {
    fn uniform(w: u32, v: u32) -> Widths {
        Widths {
            coef_frac: w,
            mul_frac: w,
            square_frac: vec![w; v as usize],
        }
    }

    fn get(&self, i: usize) -> u32 {
        match i {
            0 => self.coef_frac,
            1 => self.mul_frac,
            k => self.square_frac[k - 2],
        }
    }

    fn set(&mut self, i: usize, w: u32) {
        match i {
            0 => self.coef_frac = w,
            1 => self.mul_frac = w,
            k => self.square_frac[k - 2] = w,
        }
    }

    fn len(&self) -> usize {
        2 + self.square_frac.len()
    }
}

/// One row of a sweep table.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepRow {
    /// `v` of this row.
    pub v: u32,
    /// The target.
    pub target: Target,
    /// The `n` for which the target is asked (all for [`Reference::Lobe`]; where the
    /// ideal unit meets it for [`Reference::Power`]), as inclusive ranges.
    pub feasible_n: Vec<(u32, u32)>,
    /// The configuration found, or `None` if even [`START_FRAC`] bits miss the target.
    pub config: Option<Config>,
    /// Its measured maximum error (LSB) over the feasible `n`.
    pub max_error: f64,
    /// Integer bits of the ROM1 word.
    pub coef_int: u32,
    /// Number of exhaustive checks run.
    pub checks: u32,
    /// `(cos, n)` points per check.
    pub points_per_check: u64,
}

fn config_with(base: &Config, coef_int: u32, w: &Widths) -> Config {
    Config {
        coef_bits: coef_int + w.coef_frac,
        mul_frac: w.mul_frac,
        square_frac: w.square_frac.clone(),
        ..base.clone()
    }
}

/// The indices where `mask` is true, as inclusive ranges `(first, last)`.
pub fn mask_ranges(mask: &[bool]) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    let mut start = None;
    for (n, &m) in mask.iter().enumerate() {
        match (m, start) {
            (true, None) => start = Some(n as u32),
            (false, Some(s)) => {
                out.push((s, n as u32 - 1));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, mask.len() as u32 - 1));
    }
    out
}

/// Formats inclusive ranges as `0-20, 31-40` (or `none`).
pub fn format_ranges(r: &[(u32, u32)]) -> String {
    if r.is_empty() {
        return "none".into();
    }
    r.iter()
        .map(|&(a, b)| {
            if a == b {
                format!("{a}")
            } else {
                format!("{a}-{b}")
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Runs the search of the module docs for one target. `base` supplies `v`, `n_bits`,
/// `cos_bits`, the coefficients, `out_bits` and every rounding mode; its widths are
/// ignored. `progress` receives one line per check. Each check is
/// [`Config::exhaustive_points`] of work and a row runs ~30-40 of them, so callers taking
/// `cos_bits`/`n_bits` from users should bound that first (`glint hw sweep` does).
pub fn sweep_row(
    base: &Config,
    target: Target,
    progress: &mut dyn FnMut(&str),
) -> Result<SweepRow, HwError> {
    let v = base.v;
    let start = Widths::uniform(START_FRAC, v);
    let coef_int = coefficient_int_bits(base.coefficients, v, base.n_bits)?;
    let wide = Unit::new(config_with(base, coef_int, &start))?;
    let clock = Instant::now();
    let m = measure(&wide);
    let points = m.points;
    let mut checks = 1u32;
    let mask: Vec<bool> = m
        .per_n
        .iter()
        .map(|e| match target.reference {
            Reference::Lobe => true,
            Reference::Power => e.ideal_power <= target.bound + BOUND_SLACK_LSB,
        })
        .collect();
    let feasible_n = mask_ranges(&mask);
    let label = format!("v={v} {} <= {} LSB", target.reference.label(), target.bound);
    let err_of = |m: &crate::Measurement| {
        m.per_n
            .iter()
            .zip(&mask)
            .filter(|(_, &k)| k)
            .map(|(e, _)| match target.reference {
                Reference::Lobe => e.lobe,
                Reference::Power => e.power,
            })
            .fold(0.0, f64::max)
    };
    let wide_err = err_of(&m);
    progress(&format!(
        "{label}: start {START_FRAC} bits, error {wide_err:.4} LSB ({:.1} s)",
        clock.elapsed().as_secs_f64()
    ));
    if feasible_n.is_empty() || wide_err > target.bound + BOUND_SLACK_LSB {
        return Ok(SweepRow {
            v,
            target,
            feasible_n,
            config: None,
            max_error: wide_err,
            coef_int,
            checks,
            points_per_check: points,
        });
    }

    let mut check = |w: &Widths, what: &str| -> Result<bool, HwError> {
        let t = Instant::now();
        let unit = Unit::new(config_with(base, coef_int, w))?;
        let ok = within(&unit, target.reference, target.bound, Some(&mask));
        checks += 1;
        progress(&format!(
            "{label}: {what} -> {} ({:.1} s)",
            if ok { "pass" } else { "fail" },
            t.elapsed().as_secs_f64()
        ));
        Ok(ok)
    };

    // Smallest uniform width.
    let (mut lo, mut hi) = (1u32, START_FRAC);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if check(&Widths::uniform(mid, v), &format!("uniform {mid}"))? {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    let mut widths = Widths::uniform(hi, v);

    // Greedy per stage.
    let names: Vec<String> = ["coef_frac".to_string(), "mul_frac".to_string()]
        .into_iter()
        .chain((1..=v).map(|k| format!("square_frac[{k}]")))
        .collect();
    for (i, name) in names.iter().enumerate().take(widths.len()) {
        let (mut lo, mut hi) = (1u32, widths.get(i));
        while lo < hi {
            let mid = (lo + hi) / 2;
            let mut trial = widths.clone();
            trial.set(i, mid);
            if check(&trial, &format!("{name} {mid}"))? {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        widths.set(i, hi);
    }

    let config = config_with(base, coef_int, &widths);
    let final_m = measure(&Unit::new(config.clone())?);
    checks += 1;
    Ok(SweepRow {
        v,
        target,
        feasible_n,
        max_error: err_of(&final_m),
        config: Some(config),
        coef_int,
        checks,
        points_per_check: points,
    })
}

/// The rows as a Markdown table.
pub fn markdown_table(rows: &[SweepRow]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| v | target | n where asked | coef (ROM1) | mul_frac | square_frac | max err (LSB) | checks |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    for r in rows {
        let target = format!("{} <= {} LSB", r.target.reference.label(), r.target.bound);
        let asked = match r.target.reference {
            Reference::Lobe => "all".to_string(),
            Reference::Power => format_ranges(&r.feasible_n),
        };
        match &r.config {
            Some(c) => {
                let int = r.coef_int;
                let _ = writeln!(
                    s,
                    "| {} | {target} | {asked} | {} (UQ{}.{}) | {} | {} | {:.4} | {} |",
                    r.v,
                    c.coef_bits,
                    int,
                    c.coef_bits - int,
                    c.mul_frac,
                    c.square_frac
                        .iter()
                        .map(|w| w.to_string())
                        .collect::<Vec<_>>()
                        .join(","),
                    r.max_error,
                    r.checks
                );
            }
            None => {
                let _ = writeln!(
                    s,
                    "| {} | {target} | {asked} | not reached with {START_FRAC}-bit fractions | | | {:.4} | {} |",
                    r.v, r.max_error, r.checks
                );
            }
        }
    }
    s
}
