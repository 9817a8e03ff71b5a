//! docs/accuracy.md: tables, figures and a verdict on each of the paper's claims, all
//! computed when the report is generated (no number in it is typed by hand).

use std::f64::consts::FRAC_PI_2;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use glint_lobe::{Lobe, LobeKind};
use rayon::prelude::*;

use crate::curves::{fmt_num, Curves};
use crate::error::AnalysisError;
use crate::metrics::{exact, maximise, metrics_of, LobeMetrics};
use crate::output::Staging;
use crate::summary::summary_markdown;
use crate::tolerance::cheapest_v;
use crate::{summary_rows, write_figures, PAPER_FIG3_NS, PAPER_N, PAPER_V};

/// The sweep of the verdicts: every integer n in 1..=SWEEP_MAX.
const SWEEP_MAX: u32 = 1000;
/// One display quantum of 8-bit output, 1/255: an error below it cannot change a pixel.
const DISPLAY_QUANTUM: f64 = 1.0 / 255.0;

/// Per n of the sweep: the metrics of K_4 and G_4.
struct SweepRow {
    n: u32,
    k: LobeMetrics,
    g: LobeMetrics,
}

fn sweep(v: u32) -> Result<Vec<SweepRow>, AnalysisError> {
    (1..=SWEEP_MAX)
        .into_par_iter()
        .map(|n| {
            let nf = f64::from(n);
            Ok(SweepRow {
                n,
                k: metrics_of(&Lobe::new(LobeKind::EnergyFit, nf, v)?),
                g: metrics_of(&Lobe::new(LobeKind::SlopeFit, nf, v)?),
            })
        })
        .collect()
}

/// The integers where `pred` holds, as ranges "1–15, 17–1000" (or "none").
fn ranges(rows: &[SweepRow], pred: impl Fn(&SweepRow) -> bool) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut start: Option<u32> = None;
    let mut prev = 0;
    for r in rows {
        if pred(r) {
            if start.is_none() {
                start = Some(r.n);
            }
            prev = r.n;
        } else if let Some(s) = start.take() {
            out.push(span(s, prev));
        }
    }
    if let Some(s) = start {
        out.push(span(s, prev));
    }
    if out.is_empty() {
        "none".into()
    } else {
        out.join(", ")
    }
}

fn span(a: u32, b: u32) -> String {
    if a == b {
        a.to_string()
    } else {
        format!("{a}–{b}")
    }
}

fn count(rows: &[SweepRow], pred: impl Fn(&SweepRow) -> bool) -> usize {
    rows.iter().filter(|r| pred(r)).count()
}

/// The largest positive and negative error of a lobe (signed), with their angles.
fn signed_peaks(lobe: &Lobe<f64>) -> ((f64, f64), (f64, f64)) {
    let n = lobe.n();
    let err = |g: f64| lobe.eval(g.cos()) - exact(n, g);
    let grid: Vec<f64> = (0..=20000)
        .map(|i| FRAC_PI_2 * f64::from(i) / 20000.0)
        .collect();
    let (xp, yp) = maximise(&err, &grid, 0.0, FRAC_PI_2);
    let (xn, yn) = maximise(&|g| -err(g), &grid, 0.0, FRAC_PI_2);
    ((yp, xp.to_degrees()), (-yn, xn.to_degrees()))
}

/// Multiplications of `c^n` by binary exponentiation for an integer n:
/// `floor(log2 n)` squarings and `popcount(n) - 1` further products.
fn pow_multiplies(n: u32) -> u32 {
    if n <= 1 {
        0
    } else {
        (31 - n.leading_zeros()) + n.count_ones() - 1
    }
}

fn machine() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, m)| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

fn f4(x: f64) -> String {
    format!("{x:.4}")
}

/// Regenerates `DIR/accuracy.md` and the figures in `DIR/figures/` (PNG and SVG), all
/// or nothing. `command` is the command written at the top of the report.
pub fn write_report(docs: &Path, command: &str) -> Result<Vec<PathBuf>, AnalysisError> {
    let staging = Staging::new(docs)?;
    let v = PAPER_V;
    let rows = sweep(v)?;
    let table = summary_rows(&PAPER_FIG3_NS, &[v])?;
    let figdir = staging.path().join("figures");
    std::fs::create_dir_all(&figdir).map_err(|source| AnalysisError::Io {
        what: "creating",
        path: figdir.clone(),
        source,
    })?;
    write_figures(&figdir, &[Curves::sample(PAPER_N, v)?])?;
    let mut d = String::new();
    intro(&mut d, command, v);
    claim1(&mut d, &rows, &table, v)?;
    claim2(&mut d, &rows);
    claim3(&mut d, &rows, v)?;
    summary_and_method(&mut d, &table, v);
    staging.write("accuracy.md", d.as_bytes())?;
    staging.commit()
}

// Writing into a String cannot fail; the results of write! are ignored below.

/// The page's title, how to regenerate it, and the model.
fn intro(w: &mut String, command: &str, v: u32) {
    let _ = writeln!(w, "# Accuracy of the specular lobes against cos^n γ\n");
    let _ = writeln!(
        w,
        "Regenerate this page and its figures with **`{command}`** (it runs \
         `cargo run --release -p glint-cli -- analyze --report docs`). Every number and \
         verdict below is computed by `glint-analysis` when the page is generated; none is \
         typed by hand. The numbers are deterministic f64 results; generated on: {} \
         (2 cores).\n",
        machine()
    );
    let _ = writeln!(
        w,
        "The model and the claims are in [paper.md](paper.md) (Pavlov, Romanyuk, \
         Dumenko). K_v(n, γ) = max(0, 1 − (n+1)/(2^v+1)·(1 − cos γ))^(2^v) is the paper's \
         energy fit; G_v uses a = n/2^v (slope fit, Lyon 1993); `minimax` is the same \
         form with the a that minimises the maximum absolute error; Schlick is \
         c/(n − nc + c); `gauss` is exp(n(c − 1)). Errors are `lobe − cos^n γ` over \
         γ ∈ [0°, 90°]. For the paper's setting v = {v} (power 16).\n"
    );
}

/// Claim 1: the maximum error of K_4 against G_4's, at n = 100 and over every n.
fn claim1(
    w: &mut String,
    rows: &[SweepRow],
    table: &[LobeMetrics],
    v: u32,
) -> Result<(), AnalysisError> {
    let at = |n: u32| &rows[(n - 1) as usize];
    let k100 = Lobe::<f64>::new(LobeKind::EnergyFit, PAPER_N, v)?;
    let g100 = Lobe::<f64>::new(LobeKind::SlopeFit, PAPER_N, v)?;
    let (kp, kn) = signed_peaks(&k100);
    let (gp, gn) = signed_peaks(&g100);
    let k1 = at(100);
    let _ = writeln!(w, "## Verdicts\n");
    let _ = writeln!(
        w,
        "### Claim 1: the maximum error of K_4 is lower than that of G_4\n"
    );
    let holds100 = k1.k.max_abs.value < k1.g.max_abs.value;
    let _ = writeln!(
        w,
        "**At n = 100 (the paper's case): {}.** Max |K_4 − cos^100| = {} at γ = {:.2}°, \
         max |G_4 − cos^100| = {} at γ = {:.2}° (K_4's is {:.0}% of G_4's). The \
         \"symmetrising\" the paper names is real: K_4's error has both signs (+{} at \
         {:.2}°, {} at {:.2}°) while G_4's is one-signed (largest +{:.1e}, lowest {} at \
         {:.2}°). The truly symmetric fit is the minimax one ({} at n = 100).\n",
        if holds100 { "holds" } else { "does not hold" },
        f4(k1.k.max_abs.value),
        k1.k.max_abs.angle_deg,
        f4(k1.g.max_abs.value),
        k1.g.max_abs.angle_deg,
        100.0 * k1.k.max_abs.value / k1.g.max_abs.value,
        f4(kp.0),
        kp.1,
        f4(kn.0),
        kn.1,
        gp.0,
        f4(gn.0),
        gn.1,
        f4(table
            .iter()
            .find(|r| r.kind == LobeKind::Minimax && r.n == 100.0)
            .map(|r| r.max_abs.value)
            .unwrap_or(f64::NAN)),
    );
    let kless = |r: &SweepRow| r.k.max_abs.value < r.g.max_abs.value;
    let gless = |r: &SweepRow| r.g.max_abs.value < r.k.max_abs.value;
    let tie = |r: &SweepRow| !kless(r) && !gless(r);
    let _ = writeln!(
        w,
        "**Over every integer n in 1..={SWEEP_MAX}:** K_4 has the lower max abs error for \
         n ∈ {} ({} of {SWEEP_MAX} values); G_4 has it for n ∈ {}; they tie for n ∈ {} \
         (n = 2^v = 16 makes both fits cos^16 exactly). **Verdict: {}**\n",
        ranges(rows, kless),
        count(rows, kless),
        ranges(rows, gless),
        ranges(rows, tie),
        if count(rows, gless) == 0 {
            "holds for every n tested (except the exact tie at n = 2^v)."
        } else {
            "holds only for the n listed for K_4 above."
        },
    );
    let rel_less = |r: &SweepRow| r.k.max_rel.value < r.g.max_rel.value;
    let _ = writeln!(
        w,
        "The Ukrainian original says *relative* error (\"максимальна відносна похибка\") \
         while its figure plots the absolute one. Relative error over the region \
         cos^n ≥ 1e-3: at n = 100 K_4 {} vs G_4 {} (both at the edge of the region, where \
         the lobes fall to 0 faster than cos^n); K_4 is lower for n ∈ {}.\n",
        f4(k1.k.max_rel.value),
        f4(k1.g.max_rel.value),
        ranges(rows, rel_less),
    );

    Ok(())
}

/// Claim 2: G_4 better at the epicentre, K_4 in the bloom zone.
fn claim2(w: &mut String, rows: &[SweepRow]) {
    let at = |n: u32| &rows[(n - 1) as usize];
    let k1 = at(100);
    let _ = writeln!(
        w,
        "### Claim 2: G_4 is better at the epicentre, K_4 in the bloom zone\n"
    );
    let epi = |r: &SweepRow| r.g.epicentre.value < r.k.epicentre.value;
    let bloom = |r: &SweepRow| match (r.k.bloom, r.g.bloom) {
        (Some(k), Some(g)) => k.value < g.value,
        _ => false,
    };
    let both = |r: &SweepRow| epi(r) && bloom(r);
    let _ = writeln!(
        w,
        "Epicentre = where cos^n ≥ 0.5, bloom = where 1e-2 ≤ cos^n < 0.5; each is the max \
         abs error there.\n\n\
         | n | K_4 epicentre | G_4 epicentre | K_4 bloom | G_4 bloom |\n|---:|---:|---:|---:|---:|"
    );
    for n in [10u32, 32, 100, 350, 1000] {
        let r = at(n);
        let b = |m: &LobeMetrics| m.bloom.map(|p| f4(p.value)).unwrap_or_default();
        let _ = writeln!(
            w,
            "| {n} | {} | {} | {} | {} |",
            f4(r.k.epicentre.value),
            f4(r.g.epicentre.value),
            b(&r.k),
            b(&r.g)
        );
    }
    let _ = writeln!(
        w,
        "\n**Verdict:** G_4 is more accurate at the epicentre for n ∈ {}; K_4 is more \
         accurate in the bloom zone for n ∈ {}; both halves hold together for n ∈ {} ({} of \
         {SWEEP_MAX} values). At n = 100 the epicentre errors are {} (G_4) vs {} (K_4) and \
         the bloom errors {} (K_4) vs {} (G_4). K_4's epicentre error ({}) is as large as \
         its bloom error: it buys its better bloom and lower maximum with a brighter, \
         wider core (positive error over the core, see Fig. 2).\n",
        ranges(rows, epi),
        ranges(rows, bloom),
        ranges(rows, both),
        count(rows, both),
        f4(k1.g.epicentre.value),
        f4(k1.k.epicentre.value),
        f4(k1.k.bloom.map(|p| p.value).unwrap_or(f64::NAN)),
        f4(k1.g.bloom.map(|p| p.value).unwrap_or(f64::NAN)),
        f4(k1.k.epicentre.value),
    );
}

/// Claim 3: degree 16 instead of up to 1000, and constant.
fn claim3(w: &mut String, rows: &[SweepRow], v: u32) -> Result<(), AnalysisError> {
    let _ = writeln!(
        w,
        "### Claim 3: degree 16 instead of up to 1000, and constant\n"
    );
    let max_pow = (1..=SWEEP_MAX).map(pow_multiplies).max().unwrap_or(0);
    let arg_max_pow = (1..=SWEEP_MAX)
        .filter(|&n| pow_multiplies(n) == max_pow)
        .map(|n| n.to_string())
        .collect::<Vec<_>>()
        .join(", ");
    let big: Vec<&SweepRow> = rows.iter().filter(|r| r.n >= 100).collect();
    let kmin = big
        .iter()
        .map(|r| r.k.max_abs.value)
        .fold(f64::INFINITY, f64::min);
    let kmax = big.iter().map(|r| r.k.max_abs.value).fold(0.0, f64::max);
    let _ = writeln!(
        w,
        "As a statement about cost this holds. K_4 is a polynomial of degree 16 in cos γ \
         for every n: one multiplication by the ROM coefficient a(n), two additions, a \
         clamp and {v} squarings — 5 multiplications whatever n is. cos^n γ has degree n \
         (up to 1000 in the paper); even for integer n, binary exponentiation needs \
         floor(log2 n) + popcount(n) − 1 multiplications, which varies with n and reaches \
         {max_pow} for n ≤ {SWEEP_MAX} (n = {arg_max_pow}); non-integer n needs exp/log. \
         What the constant degree costs is accuracy: for n ≥ 100 K_4's max abs error stays \
         between {} and {} (it tends to a constant as n grows, the error of (1 − x/17)^16 \
         against e^(−x)); one 8-bit display step is 1/255 = {}, so K_4 is {} it for every \
         n ≥ 100. The smallest v that brings each fit within 1/255 (\"none ≤ 10\": for \
         small n the fits tend, as v grows, to exp(−a·2^v·(1 − c)), which is not cos^n, so \
         their error stops falling):\n",
        f4(kmin),
        f4(kmax),
        f4(DISPLAY_QUANTUM),
        if kmin > DISPLAY_QUANTUM {
            "above"
        } else if kmax <= DISPLAY_QUANTUM {
            "within"
        } else {
            "sometimes above"
        },
    );
    let _ = writeln!(
        w,
        "| n | K_v: v (squarings), error | G_v: v, error | minimax: v, error |\n|---:|---|---|---|"
    );
    for n in [10.0, 100.0, 350.0, 1000.0] {
        let fits = cheapest_v(n, DISPLAY_QUANTUM)?;
        let cell = |i: usize| match fits[i].v {
            Some((v, e)) => format!("{v} ({:.4})", e),
            None => "none ≤ 10".into(),
        };
        let _ = writeln!(
            w,
            "| {} | {} | {} | {} |",
            fmt_num(n),
            cell(0),
            cell(1),
            cell(2)
        );
    }
    let _ = writeln!(
        w,
        "\n**Verdict:** holds as a cost claim: the degree is fixed at 2^v = 16 and the unit \
         needs v = 4 squarings for every n. It is not free: with v = 4 the max abs error is \
         {}–{} for n ≥ 100, and reaching 1/255 takes the larger v of the table above \
         (one squarer per step of v; map below). `glint analyze --tolerance TOL --n N` prints the cheapest v for any \
         target.\n",
        f4(kmin),
        f4(kmax)
    );

    Ok(())
}

/// The summary table, the figures and the method.
fn summary_and_method(w: &mut String, table: &[LobeMetrics], v: u32) {
    let _ = writeln!(
        w,
        "## Summary for n = 10, 100, 1000 (v = {v})\n\n\
         Same table as `glint analyze --n 10,100,1000 --v {v} --out DIR` writes to \
         summary.md. RMS is over γ uniform in [0°, 90°]; the energy ratio is \
         (n+1)·∫ lobe·sin γ dγ (1 = cos^n's energy; K_v keeps it exactly where n ≥ 2^v).\n"
    );
    let _ = writeln!(w, "{}", summary_markdown(table));
    let _ = writeln!(
        w,
        "## Figures\n\n\
         Fig. 2 of the paper, error of K_4 and G_4 against cos^100 over the highlight:\n\n\
         ![Fig. 2](figures/fig2-error-n100-v4.png)\n\n\
         Fig. 3 of the paper, the same over 0..90° for n = 10, 100, 1000:\n\n\
         ![Fig. 3](figures/fig3-error-whole-range-v4.png)\n\n\
         Every lobe over cos^100 (Schlick's long tail is the \"unnatural blooming\" the \
         paper mentions):\n\n\
         ![Shapes](figures/shapes-n100-v4.png)\n\n\
         Max abs error over n ∈ 1..1000 (log axis) and v ∈ 1..8; the dark stripes are \
         n = 2^v, where the fits are exact:\n\n\
         ![Error map](figures/error-map.png)\n\n\
         SVG versions sit beside the PNGs in `docs/figures/`.\n"
    );
    let _ = writeln!(
        w,
        "## Method and checks\n\n\
         Maxima: a grid in γ (2000 points over 0..90°, 1500 over 30/√(n+1) rad, 2000 over \
         6/√(n+1) rad, plus every kink and region boundary), refined by golden-section \
         search around the four best local maxima. Integrals: double-exponential \
         quadrature (`quadrature` crate) split at the kinks and at multiples of the \
         highlight width. The tests of `glint-analysis` check these against an \
         independent computation (a uniform 2-million-point f64 scan and trapezoid sums) \
         and against closed forms: the energy of K_v is exactly 1 for n ≥ 2^v, of G_v \
         (1 − (1−a)^(m+1))/(a(m+1))·(n+1) or (n+1)/(a(m+1)), of the Gaussian \
         (n+1)(1 − e^(−n))/n and of Schlick (n+1)(n ln n − (n−1))/(n−1)²."
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binary_exponentiation_counts() {
        // c^1000 = c^512·c^256·c^128·c^64·c^32·c^8: 9 squarings, 5 products.
        assert_eq!(pow_multiplies(1000), 14);
        assert_eq!(pow_multiplies(16), 4);
        assert_eq!(pow_multiplies(3), 2);
        assert_eq!(pow_multiplies(1), 0);
    }
}
