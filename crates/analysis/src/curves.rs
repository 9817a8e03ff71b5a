//! Sampled curves: `cos^n`, every lobe and its error against `cos^n`, over γ ∈ [0°, 90°].

use std::f64::consts::FRAC_PI_2;

use glint_lobe::{Lobe, LobeKind};

use crate::error::AnalysisError;
use crate::metrics::{check_n, check_v, exact, level_angle, zero_angle};

/// The lobes compared with `cos^n`, in the order of the tables and CSV columns.
pub const COMPARED: [LobeKind; 5] = [
    LobeKind::EnergyFit,
    LobeKind::SlopeFit,
    LobeKind::Minimax,
    LobeKind::Schlick,
    LobeKind::Gauss,
];

/// Points over the whole range in a curve (uniform in γ).
const WHOLE_RANGE_POINTS: usize = 1201;
/// Points over the highlight (γ where `cos^n >= 1e-4`) in a curve.
const HIGHLIGHT_POINTS: usize = 3001;

/// The angles (radians) of a curve for `cos^n`: uniform over [0, π/2], three times
/// denser over the highlight (where `cos^n >= 1e-4`, where every lobe changes fastest),
/// plus the points where a lobe reaches 0 so the kinks are drawn exactly. At least
/// 4000 distinct points.
pub fn curve_angles(n: f64, kinks: &[f64]) -> Vec<f64> {
    let highlight = level_angle(n, 1e-4).unwrap_or(FRAC_PI_2).min(FRAC_PI_2);
    let mut g: Vec<f64> = (0..WHOLE_RANGE_POINTS)
        .map(|i| FRAC_PI_2 * i as f64 / (WHOLE_RANGE_POINTS - 1) as f64)
        .collect();
    // Offset by half a step (3001 is prime) so the two grids never coincide, even when the highlight
    // covers the whole range (small n).
    g.extend((0..HIGHLIGHT_POINTS).map(|i| highlight * (i as f64 + 0.5) / HIGHLIGHT_POINTS as f64));
    g.extend(
        kinks
            .iter()
            .copied()
            .filter(|k| (0.0..=FRAC_PI_2).contains(k)),
    );
    g.sort_by(f64::total_cmp);
    g.dedup();
    g
}

/// The curves for one `(n, v)`: a column per lobe, sampled at [`curve_angles`].
#[derive(Clone, Debug)]
pub struct Curves {
    /// Shininess exponent.
    pub n: f64,
    /// `v` of the power fits.
    pub v: u32,
    /// Angles γ in degrees.
    pub angle_deg: Vec<f64>,
    /// `cos^n γ`.
    pub exact: Vec<f64>,
    /// One column per lobe of [`COMPARED`], in that order: `(kind, values)`.
    pub lobes: Vec<(LobeKind, Vec<f64>)>,
}

impl Curves {
    /// Samples `cos^n` and every compared lobe.
    pub fn sample(n: f64, v: u32) -> Result<Self, AnalysisError> {
        let (n, v) = (check_n(n)?, check_v(v)?);
        let lobes: Vec<Lobe<f64>> = COMPARED
            .iter()
            .map(|&k| Lobe::new(k, n, v))
            .collect::<Result<_, _>>()?;
        let kinks: Vec<f64> = lobes.iter().filter_map(zero_angle).collect();
        let angles = curve_angles(n, &kinks);
        let exact_col = angles.iter().map(|&g| exact(n, g)).collect();
        let cols = lobes
            .iter()
            .map(|l| (l.kind(), angles.iter().map(|&g| l.eval(g.cos())).collect()))
            .collect();
        Ok(Curves {
            n,
            v,
            angle_deg: angles.iter().map(|g| g.to_degrees()).collect(),
            exact: exact_col,
            lobes: cols,
        })
    }

    /// The values of one lobe, if sampled.
    pub fn lobe(&self, kind: LobeKind) -> Option<&[f64]> {
        self.lobes
            .iter()
            .find(|(k, _)| *k == kind)
            .map(|(_, v)| v.as_slice())
    }

    /// The signed error `lobe - cos^n` of one lobe.
    pub fn error(&self, kind: LobeKind) -> Option<Vec<f64>> {
        self.lobe(kind)
            .map(|l| l.iter().zip(&self.exact).map(|(a, b)| a - b).collect())
    }
}

/// The header of curves.csv.
pub fn curves_header() -> Vec<String> {
    let mut h: Vec<String> = ["n", "v", "gamma_deg", "cos", "exact"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    h.extend(COMPARED.iter().map(|k| k.name().to_string()));
    h.extend(COMPARED.iter().map(|k| format!("err_{}", k.name())));
    h.extend(COMPARED.iter().map(|k| format!("abs_err_{}", k.name())));
    h
}

/// Writes curves.csv: one row per (n, v, γ); `err_X = X - cos^n`, `abs_err_X = |err_X|`.
pub fn write_curves_csv<W: std::io::Write>(out: W, all: &[Curves]) -> csv::Result<()> {
    let mut w = csv::Writer::from_writer(out);
    w.write_record(curves_header())?;
    for c in all {
        for i in 0..c.angle_deg.len() {
            let mut rec: Vec<String> = vec![
                fmt_num(c.n),
                c.v.to_string(),
                format!("{:.10}", c.angle_deg[i]),
                format!("{:.17e}", c.angle_deg[i].to_radians().cos()),
                format!("{:.17e}", c.exact[i]),
            ];
            rec.extend(c.lobes.iter().map(|(_, l)| format!("{:.17e}", l[i])));
            rec.extend(
                c.lobes
                    .iter()
                    .map(|(_, l)| format!("{:.17e}", l[i] - c.exact[i])),
            );
            rec.extend(
                c.lobes
                    .iter()
                    .map(|(_, l)| format!("{:.17e}", (l[i] - c.exact[i]).abs())),
            );
            w.write_record(&rec)?;
        }
    }
    w.flush()?;
    Ok(())
}

/// Formats `n` without a trailing `.0` when it is an integer.
pub fn fmt_num(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else {
        format!("{x}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_least_4000_points_denser_in_the_highlight() {
        for n in [0.0, 1.0, 10.0, 100.0, 1000.0, 10000.0] {
            let g = curve_angles(n, &[]);
            assert!(g.len() >= 4000, "n = {n}: {}", g.len());
            assert_eq!(g[0], 0.0);
            assert_eq!(*g.last().unwrap(), FRAC_PI_2);
            if n >= 10.0 {
                // More than half the points lie where cos^n >= 1e-4.
                let hl = level_angle(n, 1e-4).unwrap();
                let inside = g.iter().filter(|&&x| x <= hl).count();
                assert!(inside > g.len() / 2, "n = {n}");
            }
        }
    }
}
