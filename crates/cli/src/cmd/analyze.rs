//! `glint analyze`: accuracy of the lobes against cos^n (tables, CSVs, plots, report).

use std::path::PathBuf;

use anyhow::{bail, Context};
use glint_analysis::{
    cheapest_v, check_lists, fmt_num, summary_document, summary_rows, write_analysis, write_report,
};

/// Arguments of `glint analyze`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    glint analyze --n 100 --v 4 --out analysis/\n  \
    glint analyze --n 10,100,1000 --v 1..8 --out analysis/\n  \
    glint analyze --tolerance 0.004 --n 350\n  \
    glint analyze --report docs/      (regenerates docs/accuracy.md and docs/figures/)\n\n\
    Without --out, --tolerance or --report the summary table is printed.")]
pub struct Args {
    /// Shininess exponents n of cos^n, comma-separated (0..=10000).
    #[arg(long, default_value = "10,100,1000", allow_hyphen_values = true)]
    n: String,
    /// Values of v (the fits raise their base to 2^v), comma-separated; ranges like
    /// 1..8 (inclusive) are accepted (0..=10).
    #[arg(long, default_value = "4", allow_hyphen_values = true)]
    v: String,
    /// Write curves.csv, summary.csv, summary.md and the figures (PNG, SVG) into DIR,
    /// all or nothing.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Print, for each fit (k, g, minimax) and each n, the smallest v whose maximum
    /// absolute error against cos^n is within this tolerance, and its cost.
    #[arg(long, value_name = "TOL", allow_hyphen_values = true)]
    tolerance: Option<f64>,
    /// Regenerate the accuracy report: DIR/accuracy.md and DIR/figures/ (ignores the
    /// other options).
    #[arg(long, value_name = "DIR", conflicts_with_all = ["out", "tolerance"])]
    report: Option<PathBuf>,
}

/// Parses a comma-separated list of n.
fn parse_ns(s: &str) -> anyhow::Result<Vec<f64>> {
    let items: Vec<&str> = s
        .split(',')
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .collect();
    items
        .iter()
        .map(|t| {
            t.parse::<f64>()
                .with_context(|| format!("invalid --n value '{t}': expected a number"))
        })
        .collect()
}

/// Parses a comma-separated list of v, with inclusive ranges `a..b` or `a..=b`.
fn parse_vs(s: &str) -> anyhow::Result<Vec<u32>> {
    let mut out = Vec::new();
    for t in s.split(',').map(str::trim).filter(|t| !t.is_empty()) {
        let int = |x: &str| {
            x.trim().parse::<u32>().with_context(|| {
                format!("invalid --v value '{t}': expected an integer 0..=10 or a range like 1..8")
            })
        };
        if let Some((a, b)) = t.split_once("..") {
            let (a, b) = (int(a)?, int(b.trim_start_matches('='))?);
            if a > b {
                bail!("invalid --v range '{t}': the start is above the end");
            }
            if b > glint_lobe::MAX_V {
                bail!("invalid v = {b}: expected 0..={}", glint_lobe::MAX_V);
            }
            out.extend(a..=b);
        } else {
            out.push(int(t)?);
        }
    }
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

/// Runs `glint analyze`.
pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(dir) = &args.report {
        let files = write_report(dir, "scripts/accuracy-report")?;
        println!("wrote {} files under {}", files.len(), dir.display());
        return Ok(());
    }
    let ns = parse_ns(&args.n)?;
    let vs = parse_vs(&args.v)?;
    check_lists(&ns, &vs)?;

    if let Some(tol) = args.tolerance {
        print_tolerance(&ns, tol)?;
    }
    if let Some(dir) = &args.out {
        let files = write_analysis(&ns, &vs, dir)?;
        println!("wrote {} files into {}", files.len(), dir.display());
    } else if args.tolerance.is_none() {
        print!("{}", summary_document(&ns, &vs, &summary_rows(&ns, &vs)?));
    }
    Ok(())
}

fn print_tolerance(ns: &[f64], tol: f64) -> anyhow::Result<()> {
    println!("# smallest v with max |lobe - cos^n| <= {tol} over 0..90 degrees");
    println!(
        "{:>8} {:>8} {:>3} {:>6} {:>10} {:>14}",
        "n", "fit", "v", "power", "squarings", "max_abs_err"
    );
    for &n in ns {
        for c in cheapest_v(n, tol)? {
            match c.v {
                Some((v, err)) => println!(
                    "{:>8} {:>8} {:>3} {:>6} {:>10} {:>14.6e}",
                    fmt_num(n),
                    c.kind.name(),
                    v,
                    1u32 << v,
                    v,
                    err
                ),
                None => println!(
                    "{:>8} {:>8} {:>3} {:>6} {:>10} {:>14.6e}  (no v <= {} reaches the tolerance; error at v = {} shown)",
                    fmt_num(n),
                    c.kind.name(),
                    "-",
                    "-",
                    "-",
                    c.best_error,
                    glint_lobe::MAX_V,
                    glint_lobe::MAX_V
                ),
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn v_lists_and_ranges() {
        assert_eq!(parse_vs("1..8").unwrap(), (1..=8).collect::<Vec<_>>());
        assert_eq!(parse_vs("4, 2,2..=3").unwrap(), vec![2, 3, 4]);
        assert!(parse_vs("8..1").is_err());
        assert!(parse_vs("x").is_err());
        assert!(parse_vs("1..11").is_err());
        assert!(parse_vs("").unwrap().is_empty());
        assert_eq!(parse_ns("10,100, 1000").unwrap(), vec![10.0, 100.0, 1000.0]);
        assert!(parse_ns("ten").is_err());
    }

    fn args(n: &str, v: &str, out: Option<PathBuf>) -> Args {
        Args {
            n: n.into(),
            v: v.into(),
            out,
            tolerance: None,
            report: None,
        }
    }

    #[test]
    fn bad_arguments_give_one_error_and_no_output() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("out");
        for (n, v, msg) in [
            ("-1", "4", "invalid n = -1"),
            ("100", "11", "invalid v = 11"),
            ("100", "4..11", "invalid v = 11"),
            ("", "4", "list of n values is empty"),
            ("100", ",", "list of v values is empty"),
        ] {
            let err = run(args(n, v, Some(out.clone()))).unwrap_err();
            let line = format!("{err:#}");
            assert!(line.contains(msg) && !line.contains('\n'), "{line}");
            assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
        }
        let mut a = args("100", "4", None);
        a.tolerance = Some(-1.0);
        assert!(format!("{:#}", run(a).unwrap_err()).contains("invalid tolerance"));
    }
}
