//! The verdict of docs/hardware.md computed from `pareto.csv`: every family's fronts
//! per target, the cheapest K_v and exact `cos^n` designs within each `cos^n` budget
//! and their ratio, and the bands of those ratios. `glint hw verdict --csv` prints it;
//! a test compares it with what docs/hardware.md holds between [`BEGIN_MARKER`] and
//! [`END_MARKER`], so no figure can drift from the data.
//!
//! Errors are the CSV's: against `cos^n` over `n` 16-1023 (the maximum of
//! `err_pow_n16_63`, `err_pow_n64_255`, `err_pow_n256_1023`) and over `n` 1-1023 (also
//! `err_pow_n1_15`). A design whose cost cell is empty (not measured) takes part in no
//! comparison on that target and is counted as unmeasured.

use std::fmt::Write as _;

use super::csv_io::{CsvRow, CSV_HEADER};
use super::ParetoError;

/// The line before the generated verdict in docs/hardware.md.
pub const BEGIN_MARKER: &str =
    "<!-- verdict:begin (glint hw verdict --csv docs/pareto/pareto.csv) -->";
/// The line after it.
pub const END_MARKER: &str = "<!-- verdict:end -->";

/// The `cos^n` budgets (output LSBs) of the equal-budget comparison, per output width.
pub fn budgets(out_bits: u32) -> &'static [f64] {
    match out_bits {
        8 => &[2.6, 3.0, 4.0, 5.0, 6.0, 8.0],
        10 => &[10.0, 12.0, 16.0],
        _ => &[],
    }
}

/// A cost target of the verdict: its name and the CSV column(s) it reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CostTarget {
    /// `nand2_eq` (yosys gate count, ROM bits as one transistor each).
    Gates,
    /// `ice40_luts`.
    Ice40,
    /// `ecp5_lut_equiv` (LUT4s + 2 per CCU2 + 2 per LUT-RAM; MULT18 and BRAM apart).
    Ecp5,
    /// ECP5 slices, lower bound: `ceil(max(ecp5_lut_equiv, ecp5_ffs) / 2)` (a slice
    /// holds two LUT4s and two flip-flops; MULT18 and BRAM apart).
    Ecp5Slices,
    /// ECP5 in one figure: the slices above plus each MULT18 and block RAM priced at
    /// its share of an LFE5U-85F ([`SLICES_PER_MULT18`], [`SLICES_PER_EBR`]).
    Ecp5Priced,
    /// ECP5 synthesised without DSPs (`synth_ecp5 -nodsp`, the control): slices as
    /// [`CostTarget::Ecp5Slices`] counts them plus block RAMs priced as in
    /// [`CostTarget::Ecp5Priced`].
    Ecp5NoDsp,
}

/// Every cost target, in table order.
pub const COST_TARGETS: [CostTarget; 6] = [
    CostTarget::Gates,
    CostTarget::Ice40,
    CostTarget::Ecp5,
    CostTarget::Ecp5Slices,
    CostTarget::Ecp5Priced,
    CostTarget::Ecp5NoDsp,
];

/// Slices of the largest ECP5, the LFE5U-85F: 84K LUT4s (83,640), two per slice.
/// Lattice, "ECP5 and ECP5-5G Family Data Sheet", FPGA-DS-02012, Table 1.1.
pub const ECP5_85F_SLICES: f64 = 41_820.0;
/// A MULT18 priced as the LFE5U-85F's slices over its 156 18x18 multipliers (the same
/// table): what one multiplier displaces of the die, on the device with the most
/// multipliers per slice (the price most favourable to the design using more of them).
pub const SLICES_PER_MULT18: f64 = ECP5_85F_SLICES / 156.0;
/// A block RAM (EBR, 18 kbit) priced as the LFE5U-85F's slices over its 208 EBRs.
pub const SLICES_PER_EBR: f64 = ECP5_85F_SLICES / 208.0;

impl CostTarget {
    /// The column heading.
    pub fn label(self) -> &'static str {
        match self {
            CostTarget::Gates => "gates (NAND2)",
            CostTarget::Ice40 => "iCE40 (LUTs)",
            CostTarget::Ecp5 => "ECP5 (LUT-eq.)",
            CostTarget::Ecp5Slices => "ECP5 (slices, lower bound)",
            CostTarget::Ecp5Priced => "ECP5 (slices + MULT18 + BRAM priced)",
            CostTarget::Ecp5NoDsp => "ECP5 -nodsp (slices + BRAM priced)",
        }
    }
}

/// One design as the verdict reads it.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// `id`.
    pub id: String,
    /// `family`.
    pub family: String,
    /// `out_bits`.
    pub out_bits: u32,
    /// Error against `cos^n`, `n` 16-1023 (LSB).
    pub err16: f64,
    /// Error against `cos^n`, `n` 1-1023 (LSB).
    pub err1: f64,
    /// Error against `cos^n`, `n` 1-15 (LSB): what a path for `n < 16` beside K_v must meet.
    pub err_low: f64,
    /// Cost per [`COST_TARGETS`] (`None`: not measured).
    pub cost: [Option<f64>; 6],
    /// `ecp5_mult18` and `ecp5_brams` (`None`: not measured).
    pub ecp5_hard: Option<(u32, u32)>,
}

fn col(name: &str) -> usize {
    CSV_HEADER
        .iter()
        .position(|&h| h == name)
        .expect("a column of CSV_HEADER")
}

fn bad(row: &CsvRow, column: &str, value: &str) -> ParetoError {
    ParetoError::File {
        path: "pareto.csv".into(),
        message: format!("row {}: column {column}: {value:?} is not a number", row.id),
    }
}

fn num(row: &CsvRow, column: &str) -> Result<Option<f64>, ParetoError> {
    let text = row.fields[col(column)].trim();
    if text.is_empty() {
        return Ok(None);
    }
    text.parse::<f64>()
        .map(Some)
        .map_err(|_| bad(row, column, text))
}

fn need(row: &CsvRow, column: &str) -> Result<f64, ParetoError> {
    num(row, column)?.ok_or_else(|| bad(row, column, ""))
}

impl Point {
    /// Reads the verdict's figures from a CSV row.
    pub fn from_row(row: &CsvRow) -> Result<Point, ParetoError> {
        let err16 = ["err_pow_n16_63", "err_pow_n64_255", "err_pow_n256_1023"]
            .iter()
            .try_fold(0.0f64, |m, c| Ok::<_, ParetoError>(m.max(need(row, c)?)))?;
        let err_low = need(row, "err_pow_n1_15")?;
        let err1 = err16.max(err_low);
        let luts = num(row, "ecp5_lut_equiv")?;
        let ffs = num(row, "ecp5_ffs")?;
        let slices = match (luts, ffs) {
            (Some(l), Some(f)) => Some((l.max(f) / 2.0).ceil()),
            _ => None,
        };
        let hard = match (num(row, "ecp5_mult18")?, num(row, "ecp5_brams")?) {
            (Some(m), Some(b)) => Some((m as u32, b as u32)),
            _ => None,
        };
        let priced = match (slices, hard) {
            (Some(s), Some((m, b))) => {
                Some(s + f64::from(m) * SLICES_PER_MULT18 + f64::from(b) * SLICES_PER_EBR)
            }
            _ => None,
        };
        let nodsp = match (
            num(row, "ecp5_nodsp_lut_equiv")?,
            num(row, "ecp5_nodsp_ffs")?,
            num(row, "ecp5_nodsp_brams")?,
        ) {
            (Some(l), Some(f), Some(b)) => Some((l.max(f) / 2.0).ceil() + b * SLICES_PER_EBR),
            _ => None,
        };
        Ok(Point {
            id: row.id.clone(),
            family: row.fields[col("family")].clone(),
            out_bits: need(row, "out_bits")? as u32,
            err16,
            err1,
            err_low,
            cost: [
                num(row, "nand2_eq")?,
                num(row, "ice40_luts")?,
                luts,
                slices,
                priced,
                nodsp,
            ],
            ecp5_hard: hard,
        })
    }
}

/// Which error axis: `n` 16-1023 or `n` 1-1023.
fn err(p: &Point, from_n1: bool) -> f64 {
    if from_n1 {
        p.err1
    } else {
        p.err16
    }
}

/// The designs of `family` at `out_bits` on the front of cost on target `t` against
/// the error axis, sorted by error (measured designs only).
pub fn front<'a>(
    points: &'a [Point],
    family: &str,
    out_bits: u32,
    t: usize,
    from_n1: bool,
) -> Vec<&'a Point> {
    let group: Vec<&Point> = points
        .iter()
        .filter(|p| p.family == family && p.out_bits == out_bits && p.cost[t].is_some())
        .collect();
    let mut f: Vec<&Point> = group
        .iter()
        .filter(|p| {
            let (c, e) = (p.cost[t].unwrap_or(f64::MAX), err(p, from_n1));
            !group.iter().any(|q| {
                let (cq, eq) = (q.cost[t].unwrap_or(f64::MAX), err(q, from_n1));
                cq <= c && eq <= e && (cq < c || eq < e)
            })
        })
        .copied()
        .collect();
    f.sort_by(|a, b| err(a, from_n1).total_cmp(&err(b, from_n1)));
    f
}

/// The cheapest measured design of `family` at `out_bits` on target `t` within
/// `budget` LSB (ties: the smaller error, then the id).
pub fn cheapest<'a>(
    points: &'a [Point],
    family: &str,
    out_bits: u32,
    t: usize,
    budget: f64,
    from_n1: bool,
) -> Option<&'a Point> {
    points
        .iter()
        .filter(|p| p.family == family && p.out_bits == out_bits)
        .filter(|p| p.cost[t].is_some() && err(p, from_n1) <= budget)
        .min_by(|a, b| {
            (a.cost[t].unwrap_or(f64::MAX), err(a, from_n1), &a.id)
                .partial_cmp(&(b.cost[t].unwrap_or(f64::MAX), err(b, from_n1), &b.id))
                .unwrap_or(std::cmp::Ordering::Equal)
        })
}

/// K_v's cost over the exact unit's at one budget, target and axis (`None` where
/// either has no measured design within the budget).
pub fn ratio(
    points: &[Point],
    out_bits: u32,
    t: usize,
    budget: f64,
    from_n1: bool,
) -> Option<(f64, &Point, &Point)> {
    let k = cheapest(points, "kv", out_bits, t, budget, from_n1)?;
    let e = cheapest(points, "pow", out_bits, t, budget, from_n1)?;
    Some((k.cost[t]? / e.cost[t]?, k, e))
}

/// The cheapest measured exact unit at `out_bits` on target `t` within `budget` LSB
/// of `cos^n` over `n` 1-15: the path a K_v renderer needs beside K_v for `n < 16`
/// (K_v is 34-38 LSB off there at 8 bits). The CSV holds no unit made for `n < 16`
/// alone, so this is an upper bound on that path's cost.
pub fn low_path(points: &[Point], out_bits: u32, t: usize, budget: f64) -> Option<&Point> {
    points
        .iter()
        .filter(|p| p.family == "pow" && p.out_bits == out_bits)
        .filter(|p| p.cost[t].is_some() && p.err_low <= budget)
        .min_by(|a, b| {
            (a.cost[t].unwrap_or(f64::MAX), a.err_low, &a.id)
                .partial_cmp(&(b.cost[t].unwrap_or(f64::MAX), b.err_low, &b.id))
                .unwrap_or(std::cmp::Ordering::Equal)
        })
}

/// Over `n` 1-1023: the cheapest K_v design within `budget` over `n` 16-1023 plus its
/// `n < 16` path ([`low_path`]), over the cheapest exact unit within `budget` over
/// `n` 1-1023, on target `t`: (ratio, K_v design, `n < 16` path, exact unit).
pub fn ratio_n1(
    points: &[Point],
    out_bits: u32,
    t: usize,
    budget: f64,
) -> Option<(f64, &Point, &Point, &Point)> {
    let k = cheapest(points, "kv", out_bits, t, budget, false)?;
    let l = low_path(points, out_bits, t, budget)?;
    let e = cheapest(points, "pow", out_bits, t, budget, true)?;
    Some(((k.cost[t]? + l.cost[t]?) / e.cost[t]?, k, l, e))
}

fn cost_text_of(c: f64, hard: Option<(u32, u32)>, t: usize) -> String {
    let hard = match (COST_TARGETS[t], hard) {
        (CostTarget::Ecp5 | CostTarget::Ecp5Slices, Some((m, b))) => {
            format!(
                " + {m} MULT18{}",
                if b > 0 {
                    format!(" + {b} BRAM")
                } else {
                    String::new()
                }
            )
        }
        _ => String::new(),
    };
    format!("{c:.0}{hard}")
}

fn cost_text(p: &Point, t: usize) -> String {
    cost_text_of(p.cost[t].unwrap_or(f64::NAN), p.ecp5_hard, t)
}

/// The cost text of a K_v design and its `n < 16` path together.
fn pair_text(k: &Point, l: &Point, t: usize) -> String {
    let hard = match (k.ecp5_hard, l.ecp5_hard) {
        (Some((m1, b1)), Some((m2, b2))) => Some((m1 + m2, b1 + b2)),
        _ => None,
    };
    let c = k.cost[t].unwrap_or(f64::NAN) + l.cost[t].unwrap_or(f64::NAN);
    cost_text_of(c, hard, t)
}

/// The header of a budget table: one column per cost target.
fn budget_header(s: &mut String) {
    let mut head = String::from("| budget (LSB) |");
    let mut rule = String::from("|---|");
    for t in COST_TARGETS {
        let _ = write!(head, " {} |", t.label());
        rule.push_str("---|");
    }
    let _ = writeln!(s, "{head}\n{rule}");
}

/// The table over `n` 1-1023 with K_v's `n < 16` path costed.
fn n1_table(s: &mut String, points: &[Point], out_bits: u32) {
    let _ = writeln!(
        s,
        "\n**{out_bits}-bit output, error against `cos^n` over n 1-1023**: K_v is far off \
         `cos^n` below n = 16, so a K_v renderer that serves n >= 1 needs a second path for \
         n < 16; it is costed here as the cheapest exact unit within the budget over n 1-15 \
         (an upper bound: the CSV holds no unit made for n < 16 alone). Cheapest K_v within \
         the budget over n 16-1023 + that path / cheapest exact unit within the budget over \
         n 1-1023 (ids, cost), and the ratio; the K_v-only ratios above are the lower bound.\n"
    );
    budget_header(s);
    for &b in budgets(out_bits) {
        let mut line = format!("| {b} |");
        for t in 0..COST_TARGETS.len() {
            let cell = match ratio_n1(points, out_bits, t, b) {
                Some((r, k, l, e)) => format!(
                    " **{r:.2}×**: {} + {} {} / {} {} |",
                    k.id,
                    l.id,
                    pair_text(k, l, t),
                    e.id,
                    cost_text(e, t)
                ),
                None => " no comparison |".to_string(),
            };
            line.push_str(&cell);
        }
        let _ = writeln!(s, "{line}");
    }
}

/// The equal-budget table of one output width and error axis.
fn budget_table(s: &mut String, points: &[Point], out_bits: u32, from_n1: bool) {
    let axis = if from_n1 { "1" } else { "16" };
    let _ = writeln!(
        s,
        "\n**{out_bits}-bit output, error against `cos^n` over n {axis}-1023**: cheapest K_v \
         / cheapest exact unit within each budget (id, cost, error), and K_v's cost over \
         the exact unit's (< 1: K_v is cheaper).\n"
    );
    budget_header(s);
    for &b in budgets(out_bits) {
        let mut line = format!("| {b} |");
        for t in 0..COST_TARGETS.len() {
            let cell = match ratio(points, out_bits, t, b, from_n1) {
                Some((r, k, e)) => format!(
                    " **{r:.2}×**: {} {} ({:.2}) / {} {} ({:.2}) |",
                    k.id,
                    cost_text(k, t),
                    err(k, from_n1),
                    e.id,
                    cost_text(e, t),
                    err(e, from_n1)
                ),
                None => {
                    let k = cheapest(points, "kv", out_bits, t, b, from_n1);
                    let e = cheapest(points, "pow", out_bits, t, b, from_n1);
                    match (k, e) {
                        (None, Some(e)) => format!(
                            " no K_v within {b} / {} {} ({:.2}) |",
                            e.id,
                            cost_text(e, t),
                            err(e, from_n1)
                        ),
                        (Some(k), None) => format!(
                            " {} {} ({:.2}) / no exact unit |",
                            k.id,
                            cost_text(k, t),
                            err(k, from_n1)
                        ),
                        _ => " neither |".to_string(),
                    }
                }
            };
            line.push_str(&cell);
        }
        let _ = writeln!(s, "{line}");
    }
}

/// The bands: per target, the budgets where K_v is cheaper and the range of ratios
/// (`ratio_at(t, budget)`; `axis` names the error axis and what K_v's cost includes).
fn bands(s: &mut String, out_bits: u32, axis: &str, ratio_at: &dyn Fn(usize, f64) -> Option<f64>) {
    for (t, target) in COST_TARGETS.iter().enumerate() {
        let rs: Vec<(f64, f64)> = budgets(out_bits)
            .iter()
            .filter_map(|&b| ratio_at(t, b).map(|r| (b, r)))
            .collect();
        let fmt = |v: &[(f64, f64)]| {
            v.iter()
                .map(|(b, _)| format!("{b}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let cheaper: Vec<(f64, f64)> = rs.iter().copied().filter(|r| r.1 < 1.0).collect();
        let dearer: Vec<(f64, f64)> = rs.iter().copied().filter(|r| r.1 >= 1.0).collect();
        let span = |v: &[(f64, f64)]| {
            let lo = v.iter().map(|r| r.1).fold(f64::MAX, f64::min);
            let hi = v.iter().map(|r| r.1).fold(f64::MIN, f64::max);
            (lo, hi)
        };
        let mut line = format!("- {out_bits} bits, {axis}, {}: ", target.label());
        if rs.is_empty() {
            line.push_str("no budget has both a K_v and an exact design measured.");
        } else {
            if !cheaper.is_empty() {
                let (lo, hi) = span(&cheaper);
                let text = if format!("{lo:.2}") == format!("{hi:.2}") {
                    format!("{lo:.2}×, i.e. {:.1}× smaller", 1.0 / lo)
                } else {
                    format!(
                        "{lo:.2}-{hi:.2}×, i.e. {:.1}-{:.1}× smaller",
                        1.0 / hi,
                        1.0 / lo
                    )
                };
                let _ = write!(line, "K_v cheaper at {} LSB ({text}); ", fmt(&cheaper));
            }
            if !dearer.is_empty() {
                let (lo, hi) = span(&dearer);
                let (lo, hi) = ((lo - 1.0) * 100.0, (hi - 1.0) * 100.0);
                let pct = if format!("{lo:.0}") == format!("{hi:.0}") {
                    format!("+{lo:.0} %")
                } else {
                    format!("+{lo:.0} to +{hi:.0} %")
                };
                let _ = write!(line, "K_v dearer at {} LSB ({pct}); ", fmt(&dearer));
            }
            let none: Vec<String> = budgets(out_bits)
                .iter()
                .filter(|&&b| !rs.iter().any(|r| r.0 == b))
                .map(|b| format!("{b}"))
                .collect();
            if !none.is_empty() {
                let _ = write!(
                    line,
                    "no comparison at {} LSB (a family has no measured design within it); ",
                    none.join(", ")
                );
            }
            line.truncate(line.trim_end_matches("; ").len());
            line.push('.');
        }
        let _ = writeln!(s, "{line}");
    }
}

/// The fronts (error against `cos^n`, n 16-1023) of every family on every target.
fn fronts(s: &mut String, points: &[Point], out_bits: u32) {
    let _ = writeln!(
        s,
        "\n**{out_bits}-bit fronts** (error over n 16-1023; cost; the K_v front is where \
         each K_v point is its family's best):\n"
    );
    let _ = writeln!(
        s,
        "| target | family | front: id cost (error) |\n|---|---|---|"
    );
    for (t, target) in COST_TARGETS.iter().enumerate() {
        for family in ["kv", "pow", "schlick"] {
            let f = front(points, family, out_bits, t, false);
            if f.is_empty() {
                continue;
            }
            let list: Vec<String> = f
                .iter()
                .map(|p| format!("{} {} ({:.2})", p.id, cost_text(p, t), p.err16))
                .collect();
            let _ = writeln!(s, "| {} | {family} | {} |", target.label(), list.join("; "));
        }
    }
}

/// The verdict's generated text (Markdown) from the rows of a `pareto.csv`.
pub fn verdict_markdown(rows: &[CsvRow]) -> Result<String, ParetoError> {
    let points: Vec<Point> = rows.iter().map(Point::from_row).collect::<Result<_, _>>()?;
    let mut s = String::new();
    let unmeasured: Vec<&str> = points
        .iter()
        .filter(|p| p.cost[..5].iter().any(Option::is_none))
        .map(|p| p.id.as_str())
        .collect();
    let nodsp = points.iter().filter(|p| p.cost[5].is_some()).count();
    let _ = write!(
        s,
        "{} designs in the CSV, {} with the gates, iCE40 and ECP5 costs measured, {nodsp} \
         with the ECP5 -nodsp control",
        points.len(),
        points.len() - unmeasured.len(),
    );
    let _ = writeln!(
        s,
        "{}.",
        if unmeasured.is_empty() {
            String::new()
        } else {
            format!(
                "; not (fully) measured, so left out where a cost is missing: {}",
                unmeasured.join(", ")
            )
        }
    );
    for out_bits in [8u32, 10] {
        if !points.iter().any(|p| p.out_bits == out_bits) {
            continue;
        }
        budget_table(&mut s, &points, out_bits, false);
        let _ = writeln!(s);
        bands(&mut s, out_bits, "n 16-1023", &|t, b| {
            ratio(&points, out_bits, t, b, false).map(|r| r.0)
        });
        n1_table(&mut s, &points, out_bits);
        let _ = writeln!(s);
        bands(
            &mut s,
            out_bits,
            "n 1-1023 (K_v + its n < 16 path)",
            &|t, b| ratio_n1(&points, out_bits, t, b).map(|r| r.0),
        );
        fronts(&mut s, &points, out_bits);
    }
    Ok(s)
}

/// The text between [`BEGIN_MARKER`] and [`END_MARKER`] in `doc` (without the marker
/// lines), or `None` if either is missing.
pub fn between_markers(doc: &str) -> Option<&str> {
    let start = doc.find(BEGIN_MARKER)? + BEGIN_MARKER.len();
    let rest = &doc[start..];
    let end = rest.find(END_MARKER)?;
    Some(rest[..end].trim_matches('\n'))
}
