//! `glint eval`: lobe values at given angles or cosines, as a table or JSON.

use anyhow::{bail, Context};
use glint_lobe::{Lobe, LobeKind};
use serde_json::{json, Map, Value};

/// Arguments of `glint eval`.
#[derive(clap::Args)]
#[command(
    after_help = "Examples:\n  glint eval --lobe k --n 100 --v 4 --angle 0,2.5,5,10\n  \
                        glint eval --lobe exact --lobe k --lobe g --cos 0.99,0.9 --json"
)]
pub struct Args {
    /// Lobes to evaluate, one column each: exact, k, g, schlick, gauss, minimax
    /// (repeat the flag or separate with commas) [default: all]
    #[arg(long, value_delimiter = ',')]
    lobe: Vec<String>,
    /// Shininess exponent n of cos^n (0..=10000).
    #[arg(long, default_value_t = 100.0, allow_negative_numbers = true)]
    n: f64,
    /// The power fits (k, g, minimax) raise their base to 2^v (0..=10).
    #[arg(long, default_value_t = 4)]
    v: u32,
    /// Angles γ in degrees, comma-separated [default: 0,2.5,5,10,15,20,30,45,60,90]
    #[arg(
        long,
        value_delimiter = ',',
        conflicts_with = "cos",
        allow_negative_numbers = true
    )]
    angle: Vec<f64>,
    /// Cosines cos γ in [-1, 1], comma-separated (instead of --angle).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    cos: Vec<f64>,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

const DEFAULT_ANGLES: [f64; 10] = [0.0, 2.5, 5.0, 10.0, 15.0, 20.0, 30.0, 45.0, 60.0, 90.0];

/// Runs `glint eval`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let kinds: Vec<LobeKind> = if args.lobe.is_empty() {
        LobeKind::ALL.to_vec()
    } else {
        args.lobe
            .iter()
            .map(|s| s.parse::<LobeKind>())
            .collect::<Result<_, _>>()?
    };
    let lobes: Vec<Lobe<f64>> = kinds
        .iter()
        .map(|&kind| Lobe::new(kind, args.n, args.v))
        .collect::<Result<_, _>>()?;

    // Points as (angle in degrees, cosine).
    let points: Vec<(f64, f64)> = if !args.cos.is_empty() {
        for &c in &args.cos {
            if !(-1.0..=1.0).contains(&c) {
                bail!("invalid --cos value {c}: a cosine lies in [-1, 1]");
            }
        }
        args.cos
            .iter()
            .map(|&c| (c.acos().to_degrees(), c))
            .collect()
    } else {
        let angles = if args.angle.is_empty() {
            DEFAULT_ANGLES.to_vec()
        } else {
            args.angle.clone()
        };
        for &a in &angles {
            if !a.is_finite() {
                bail!("invalid --angle value {a}: angles are finite numbers of degrees");
            }
        }
        angles.iter().map(|&a| (a, a.to_radians().cos())).collect()
    };

    if args.json {
        print_json(&args, &lobes, &points).context("writing JSON")
    } else {
        print_table(&args, &lobes, &points);
        Ok(())
    }
}

fn print_table(args: &Args, lobes: &[Lobe<f64>], points: &[(f64, f64)]) {
    println!(
        "# n = {}, v = {} (power 2^v = {})",
        args.n,
        args.v,
        1u32 << args.v
    );
    for lobe in lobes {
        if let Some(a) = lobe.coefficient() {
            println!("# {}: a = {a:.10}", lobe.kind());
        }
    }
    let mut header = format!("{:>10} {:>12}", "angle_deg", "cos");
    for lobe in lobes {
        header.push_str(&format!(" {:>14}", lobe.kind().name()));
    }
    println!("{header}");
    for &(angle, c) in points {
        let mut line = format!("{angle:>10.4} {c:>12.9}");
        for lobe in lobes {
            line.push_str(&format!(" {:>14.8e}", lobe.eval(c)));
        }
        println!("{line}");
    }
}

fn print_json(args: &Args, lobes: &[Lobe<f64>], points: &[(f64, f64)]) -> anyhow::Result<()> {
    let mut coefficients = Map::new();
    for lobe in lobes {
        if let Some(a) = lobe.coefficient() {
            coefficients.insert(lobe.kind().name().into(), json!(a));
        }
    }
    let rows: Vec<Value> = points
        .iter()
        .map(|&(angle, c)| {
            let mut row = Map::new();
            row.insert("angle_deg".into(), json!(angle));
            row.insert("cos".into(), json!(c));
            for lobe in lobes {
                row.insert(lobe.kind().name().into(), json!(lobe.eval(c)));
            }
            Value::Object(row)
        })
        .collect();
    let doc = json!({
        "n": args.n,
        "v": args.v,
        "lobes": lobes.iter().map(|l| l.kind().name()).collect::<Vec<_>>(),
        "coefficients": coefficients,
        "rows": rows,
    });
    println!("{}", serde_json::to_string_pretty(&doc)?);
    Ok(())
}
