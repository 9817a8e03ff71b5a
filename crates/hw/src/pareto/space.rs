//! The design space: which designs are explored, and how each is sized for its error
//! target before it is synthesised.
//!
//! - **K_v** (energy fit; v = 4 at 0.5, 1, 2 LSB, v = 3 and 5 at 1 LSB): the widths of `glint hw sweep` for a bound
//!   against the unit's own lobe (`sweep_row`, exhaustive), then the same widths with
//!   ROM1 and generic multipliers (Fig. 4 as drawn), with a constant multiplier and
//!   squarers, and with a constant multiplier and truncated squarers (the fewest guard
//!   columns that still meet the bound); at v = 4 also the constant multiplier with
//!   generic multipliers (what suits hard multipliers), at v = 4, 1 LSB the two-table
//!   source and ROM1 with squarers; at v = 4 the minimax ROM; and the paper's unit as
//!   `Config::default()` (the reference point).
//! - **exact `cos^n`**: tables (interpolated or not) sized by a greedy search for a
//!   bound against `cos^n` over every `n` (0.5, 1, 2, 4, 8 LSB).
//! - **Schlick**: quotient and input widths sized for a bound against Schlick's own
//!   form (0.5, 1, 2 LSB); against `cos^n` Schlick is 50+ LSB away at any width.
//! - **Equal terms** (space 3, issue 46): K_v (v = 3, 4, 5) sized by the same greedy
//!   search against the same `cos^n` budgets as the exact unit ([`POWER_BUDGETS`]:
//!   error over n 16-1023, where K_v can meet them; K_v is 34-38 LSB off for n < 16
//!   at 8 bits), as ROM1 with generic multipliers, constant multiplier with truncated
//!   squarers and constant multiplier with generic multipliers; the exact unit sized at
//!   the same budgets (over every n).

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::hdl::{HdlUnit, Ports, PowParams, PowerUnit, SchlickParams};
use crate::{
    sweep_row, within, CoefSource, Coefficients, Config, Design, HwError, Reference, Squarer,
    Target, Unit, BOUND_SLACK_LSB, DESIGN_COS_BITS, DESIGN_N_BITS,
};

/// One design to cost, with what it was sized for.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// A short unique name, e.g. `kv4-const-sym-o8-lobe1`.
    pub id: String,
    /// The target it was sized for, e.g. `lobe <= 1`, `cos^n <= 2`, `reference`.
    pub target: String,
    /// The design.
    pub design: Design,
}

/// The greedy search of `sweep.rs` over any integer parameters: start from `start`
/// (which must pass, else `None`), then, parameter by parameter, binary-search the
/// smallest value in `lo[i]..=current` that still passes with the others fixed.
pub fn shrink(
    start: &[u32],
    lo: &[u32],
    ok: &mut dyn FnMut(&[u32]) -> Result<bool, HwError>,
) -> Result<Option<Vec<u32>>, HwError> {
    if !ok(start)? {
        return Ok(None);
    }
    let mut cur = start.to_vec();
    for i in 0..cur.len() {
        let (mut a, mut b) = (lo[i], cur[i]);
        while a < b {
            let mid = (a + b) / 2;
            let mut t = cur.clone();
            t[i] = mid;
            if ok(&t)? {
                b = mid;
            } else {
                a = mid + 1;
            }
        }
        cur[i] = b;
    }
    Ok(Some(cur))
}

fn kv_base(v: u32, out_bits: u32, coefficients: Coefficients) -> Config {
    Config {
        v,
        n_bits: DESIGN_N_BITS,
        cos_bits: DESIGN_COS_BITS,
        coefficients,
        square_frac: vec![1; v as usize],
        out_bits,
        ..Config::default()
    }
}

fn fmt_bound(b: f64) -> String {
    format!("{b}")
}

/// The K_v designs of one sweep row.
fn kv_row(
    v: u32,
    out: u32,
    bound: f64,
    coefficients: Coefficients,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<Candidate>, HwError> {
    let target = Target {
        reference: Reference::Lobe,
        bound,
    };
    let row = sweep_row(&kv_base(v, out, coefficients), target, &mut |_| {})?;
    let Some(cfg) = row.config else {
        progress(&format!("kv v={v} out={out} lobe<={bound}: not reached"));
        return Ok(Vec::new());
    };
    let tag = format!("o{out}-lobe{}", fmt_bound(bound));
    let t = format!("lobe <= {}", fmt_bound(bound));
    let mk = |name: &str, c: Config| Candidate {
        id: format!("kv{v}-{name}-{tag}"),
        target: t.clone(),
        design: Design::Kv(c),
    };
    let with = |source: CoefSource, squarer: Squarer, guard: u32| Config {
        coef_source: source,
        squarer,
        square_guard: guard,
        ..cfg.clone()
    };
    if coefficients == Coefficients::Minimax {
        return Ok(vec![mk("minimax-rom-gen", cfg.clone())]);
    }
    let mut out_rows = vec![
        mk("rom-gen", cfg.clone()),
        mk("const-sym", with(CoefSource::Const, Squarer::Symmetric, 2)),
    ];
    // The fewest guard columns for which the truncated squarers still meet the bound.
    for guard in 1..=12 {
        let c = with(CoefSource::Const, Squarer::Truncated, guard);
        if within(&Unit::new(c.clone())?, Reference::Lobe, bound, None) {
            out_rows.push(mk("const-trunc", c));
            break;
        }
    }
    if v == 4 {
        // Hard multipliers (ECP5) favour generic multipliers over LUT squarers.
        out_rows.push(mk(
            "const-gen",
            with(CoefSource::Const, Squarer::Generic, 2),
        ));
    }
    if v == 4 && bound == 1.0 {
        out_rows.push(mk(
            "table-sym",
            with(CoefSource::Table, Squarer::Symmetric, 2),
        ));
        out_rows.push(mk("rom-sym", with(CoefSource::Rom, Squarer::Symmetric, 2)));
    }
    progress(&format!(
        "kv v={v} out={out} lobe<={bound}: {} designs (widths {}/{}/{:?})",
        out_rows.len(),
        cfg.coef_bits,
        cfg.mul_frac,
        cfg.square_frac
    ));
    Ok(out_rows)
}

/// The `cos^n` budgets (output LSBs) every family is sized for, per output width.
pub const POWER_BUDGETS: [(u32, &[f64]); 2] = [
    (8, &[2.6, 3.0, 4.0, 5.0, 6.0, 8.0]),
    (10, &[10.0, 12.0, 16.0]),
];

/// Error of a K_v design against `cos^n` over n 16-1023, within `budget`?
fn kv_meets(c: &Config, budget: f64) -> Result<bool, HwError> {
    Ok(Design::Kv(c.clone()).errors()?.power_16_up() <= budget + BOUND_SLACK_LSB)
}

/// The K_v designs sized by the greedy search of `sweep.rs` for `budget` LSB against
/// `cos^n` (the `n` where an ideal K_v unit meets it), kept only if the design meets
/// the budget over every n 16-1023.
fn kv_power_row(
    v: u32,
    out: u32,
    budget: f64,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<Candidate>, HwError> {
    let target = Target {
        reference: Reference::Power,
        bound: budget,
    };
    let row = sweep_row(
        &kv_base(v, out, Coefficients::EnergyFit),
        target,
        &mut |_| {},
    )?;
    let cfg = match row.config {
        Some(cfg) if kv_meets(&cfg, budget)? => cfg,
        _ => {
            progress(&format!(
                "kv v={v} out={out} cos^n<={budget}: not reached for n 16-1023"
            ));
            return Ok(Vec::new());
        }
    };
    let tag = format!("o{out}-pow{}", fmt_bound(budget));
    let t = format!("cos^n <= {} (n >= 16)", fmt_bound(budget));
    let mk = |name: &str, c: Config| Candidate {
        id: format!("kv{v}-{name}-{tag}"),
        target: t.clone(),
        design: Design::Kv(c),
    };
    let with = |source: CoefSource, squarer: Squarer, guard: u32| Config {
        coef_source: source,
        squarer,
        square_guard: guard,
        ..cfg.clone()
    };
    let mut rows = vec![
        mk("rom-gen", cfg.clone()),
        mk("const-gen", with(CoefSource::Const, Squarer::Generic, 2)),
    ];
    for guard in 1..=12 {
        let c = with(CoefSource::Const, Squarer::Truncated, guard);
        match kv_meets(&c, budget) {
            Ok(true) => {
                rows.push(mk("const-trunc", c));
                break;
            }
            Ok(false) => {}
            // Narrow last squarings (below the output width) admit no truncated array.
            Err(e) => {
                progress(&format!(
                    "kv v={v} out={out} cos^n<={budget}: no truncated squarers ({e})"
                ));
                break;
            }
        }
    }
    progress(&format!(
        "kv v={v} out={out} cos^n<={budget}: {} designs (widths {}/{}/{:?})",
        rows.len(),
        cfg.coef_bits,
        cfg.mul_frac,
        cfg.square_frac
    ));
    Ok(rows)
}

/// The exact unit sized for `budget` against `cos^n` over every n (interpolated and
/// plain tables), as candidates.
fn pow_rows(
    o: u32,
    budget: f64,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<Candidate>, HwError> {
    let mut out = Vec::new();
    for interp in [true, false] {
        let name = if interp { "interp" } else { "plain" };
        match pow_sized(o, budget, interp)? {
            Some(params) => {
                progress(&format!("pow {name} out={o} cos^n<={budget}: {params:?}"));
                out.push(Candidate {
                    id: format!("pow-{name}-o{o}-pow{}", fmt_bound(budget)),
                    target: format!("cos^n <= {}", fmt_bound(budget)),
                    design: Design::Pow {
                        out_bits: o,
                        params,
                    },
                });
            }
            None => progress(&format!(
                "pow {name} out={o} cos^n<={budget}: not reached with the largest tables"
            )),
        }
    }
    Ok(out)
}

/// Runs one sizing step, or reads its result from `steps` (one JSON file a step), so
/// an interrupted sizing resumes after its last finished step. A result that cannot be
/// stored is still returned (the next run sizes that step again).
fn step(
    steps: Option<&Path>,
    name: &str,
    run: impl FnOnce() -> Result<Vec<Candidate>, HwError>,
) -> Result<Vec<Candidate>, HwError> {
    let file = steps.map(|d| d.join(format!("{name}.json")));
    if let Some(text) = file.as_ref().and_then(|f| std::fs::read_to_string(f).ok()) {
        if let Ok(c) = serde_json::from_str::<Vec<Candidate>>(&text) {
            return Ok(c);
        }
    }
    let c = run()?;
    if let (Some(file), Ok(text)) = (&file, serde_json::to_string_pretty(&c)) {
        if let Some(dir) = file.parent() {
            let _ = std::fs::create_dir_all(dir);
        }
        let _ = glint_io::write_atomic(file, |w| w.write_all(text.as_bytes()));
    }
    Ok(c)
}

/// Space 3's designs beyond the first space: K_v and the exact unit at every budget of
/// [`POWER_BUDGETS`] (the exact unit's budgets already in the first space are skipped).
/// Each sizing step is kept in `steps` (see [`candidates`]).
pub fn equal_budget_candidates(
    steps: Option<&Path>,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<Candidate>, HwError> {
    let mut out = Vec::new();
    for (o, budgets) in POWER_BUDGETS {
        for &budget in budgets {
            for v in [3u32, 4, 5] {
                out.extend(step(steps, &format!("kvpow-v{v}-o{o}-{budget}"), || {
                    kv_power_row(v, o, budget, progress)
                })?);
            }
            if ![0.5, 1.0, 2.0, 4.0, 8.0].contains(&budget) {
                out.extend(step(steps, &format!("pow-o{o}-{budget}"), || {
                    pow_rows(o, budget, progress)
                })?);
            }
        }
    }
    Ok(out)
}

/// The Schlick unit sized for `budget` against its own form, as a candidate.
fn schlick_rows(
    o: u32,
    budget: f64,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<Candidate>, HwError> {
    Ok(match schlick_sized(o, budget)? {
        Some(params) => {
            progress(&format!("schlick out={o} lobe<={budget}: {params:?}"));
            vec![Candidate {
                id: format!("schlick-o{o}-lobe{}", fmt_bound(budget)),
                target: format!("lobe <= {}", fmt_bound(budget)),
                design: Design::Schlick {
                    out_bits: o,
                    params,
                },
            }]
        }
        None => {
            progress(&format!("schlick out={o} lobe<={budget}: not reached"));
            Vec::new()
        }
    })
}

fn ports(out: u32) -> Ports {
    Ports {
        cos_bits: DESIGN_COS_BITS,
        n_bits: DESIGN_N_BITS,
        out_bits: out,
    }
}

/// The smallest cos^n tables (greedy) within `budget` LSB of `cos^n` for every `n`.
fn pow_sized(out: u32, budget: f64, interp: bool) -> Result<Option<PowParams>, HwError> {
    let params = |p: &[u32]| PowParams {
        log_index: p[0],
        exp_index: p[1],
        log_frac: p[2],
        exp_frac: p[3],
        log_interp: interp,
        exp_interp: interp,
    };
    let mut ok = |p: &[u32]| -> Result<bool, HwError> {
        let q = params(p);
        if q.validate().is_err() {
            return Ok(false);
        }
        let u = PowerUnit::with_params(ports(out), q)?;
        Ok(u.max_error_vs_power() <= budget + BOUND_SLACK_LSB)
    };
    let start: [u32; 4] = if interp {
        [10, 10, 26, 22]
    } else {
        [12, 12, 26, 22]
    };
    Ok(shrink(&start, &[1, 1, 8, 4], &mut ok)?.map(|p| params(&p)))
}

/// The narrowest Schlick divider within `budget` LSB of Schlick's own form.
fn schlick_sized(out: u32, budget: f64) -> Result<Option<SchlickParams>, HwError> {
    let params = |p: &[u32]| SchlickParams {
        quot_frac: p[0],
        x_frac: p[1],
    };
    let mut ok = |p: &[u32]| -> Result<bool, HwError> {
        let d = Design::Schlick {
            out_bits: out,
            params: params(p),
        };
        Ok(d.errors()?.lobe <= budget + BOUND_SLACK_LSB)
    };
    Ok(shrink(&[20, 14], &[2, 4], &mut ok)?.map(|p| params(&p)))
}

/// Every candidate of the exploration (`quick`: three fixed designs at 8 bits, one a
/// family, no sizing, for CI). Sizing runs exhaustive checks: minutes for the full space
/// (an hour on a loaded machine); with `steps`, each step's result is kept there as it
/// finishes and read back by the next call, so an interrupted sizing resumes.
pub fn candidates(
    quick: bool,
    steps: Option<&Path>,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<Candidate>, HwError> {
    let mut out = Vec::new();
    let reference = |o: u32| Candidate {
        id: format!("kv4-fig4-ref-o{o}"),
        target: "reference (Fig. 4, Config::default())".into(),
        design: Design::Kv(Config {
            out_bits: o,
            ..Config::default()
        }),
    };
    if quick {
        // Three designs, one a family, each through every step of the full run: the
        // K_v unit with the new circuits (constant multiplier, symmetric squarers),
        // the exact unit with its two tables, the Schlick divider. The Fig. 4 unit
        // (ROM1, the slowest to synthesise) is left to the full run; CI co-simulates it
        // with the other front designs.
        out.push(Candidate {
            id: "kv4-const-sym-o8-default".into(),
            target: "default widths".into(),
            design: Design::Kv(Config {
                coef_source: CoefSource::Const,
                squarer: Squarer::Symmetric,
                ..Config::default()
            }),
        });
        out.push(Candidate {
            id: "pow-interp-o8-default".into(),
            target: "default tables".into(),
            design: Design::Pow {
                out_bits: 8,
                params: PowParams::default(),
            },
        });
        out.push(Candidate {
            id: "schlick-o8-default".into(),
            target: "default widths".into(),
            design: Design::Schlick {
                out_bits: 8,
                params: SchlickParams::default(),
            },
        });
        return Ok(out);
    }
    for o in [8u32, 10] {
        out.push(reference(o));
        for (v, bound) in [(4, 0.5), (4, 1.0), (4, 2.0), (3, 1.0), (5, 1.0)] {
            out.extend(step(steps, &format!("kv-v{v}-o{o}-lobe{bound}"), || {
                kv_row(v, o, bound, Coefficients::EnergyFit, progress)
            })?);
        }
        out.extend(step(steps, &format!("kv-minimax-v4-o{o}-lobe1"), || {
            kv_row(4, o, 1.0, Coefficients::Minimax, progress)
        })?);
        for budget in [0.5, 1.0, 2.0, 4.0, 8.0] {
            out.extend(step(steps, &format!("pow-o{o}-{budget}"), || {
                pow_rows(o, budget, progress)
            })?);
        }
        for budget in [0.5, 1.0, 2.0] {
            out.extend(step(steps, &format!("schlick-o{o}-{budget}"), || {
                schlick_rows(o, budget, progress)
            })?);
        }
    }
    out.extend(equal_budget_candidates(steps, progress)?);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_finished_sizing_step_is_read_back_not_run_again() {
        let dir = tempfile::tempdir().unwrap();
        let steps = dir.path().join("sizing");
        let made = || Candidate {
            id: "x".into(),
            target: "t".into(),
            design: Design::Kv(Config::default()),
        };
        let runs = std::cell::Cell::new(0);
        let run = || {
            runs.set(runs.get() + 1);
            Ok(vec![made()])
        };
        assert_eq!(step(Some(&steps), "a", run).unwrap(), vec![made()]);
        assert_eq!(step(Some(&steps), "a", run).unwrap(), vec![made()]);
        assert_eq!(runs.get(), 1);
        // Another step, or no step directory, runs.
        step(Some(&steps), "b", run).unwrap();
        step(None, "a", run).unwrap();
        assert_eq!(runs.get(), 3);
        // A damaged file is sized again.
        std::fs::write(steps.join("a.json"), "[{").unwrap();
        step(Some(&steps), "a", run).unwrap();
        assert_eq!(runs.get(), 4);
    }

    #[test]
    fn shrink_finds_the_corner_of_a_monotone_region() {
        // Passes iff a + 2b >= 10 and b >= 2: from (10, 10) the greedy order gives
        // a = 0 (b = 10 still), then b = 5.
        let mut calls = 0;
        let mut ok = |p: &[u32]| {
            calls += 1;
            Ok(p[0] + 2 * p[1] >= 10 && p[1] >= 2)
        };
        assert_eq!(
            shrink(&[10, 10], &[0, 0], &mut ok).unwrap(),
            Some(vec![0, 5])
        );
        assert!(calls > 2);
        let mut never = |_: &[u32]| Ok(false);
        assert_eq!(shrink(&[3], &[0], &mut never).unwrap(), None);
    }
}
