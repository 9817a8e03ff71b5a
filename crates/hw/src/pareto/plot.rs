//! The Pareto plots: error against `cos^n` (n 16-1023) vs cost, one per target and
//! output width, every design a point coloured by family, each family's front a line,
//! the paper's Fig. 4 unit ringed. PNG and SVG, text from an embedded font.

use std::error::Error;
use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{ParetoError, Row};
use crate::hdl::Costs;

/// A cost axis.
#[derive(Clone, Copy, Debug)]
pub struct Axis {
    /// Short name (file names, CSV columns).
    pub key: &'static str,
    /// Axis label.
    pub label: &'static str,
    cost: fn(&Costs) -> f64,
}

impl Axis {
    /// The design's cost on this axis.
    pub fn cost(&self, c: &Costs) -> f64 {
        (self.cost)(c)
    }
}

/// The three targets: gate-level NAND2 equivalents (ROMs as logic), iCE40 LUTs, ECP5
/// LUT equivalents (hard multipliers and block RAMs not counted: nearly free there).
pub const TARGETS: [Axis; 3] = [
    Axis {
        key: "gates",
        label: "NAND2 equivalents (yosys abc -g, stat -tech cmos / 4, ROM bit = 1 transistor)",
        cost: |c| c.nand2(),
    },
    Axis {
        key: "ice40",
        label: "iCE40 HX8K LUT4s (synth_ice40; BRAMs not counted)",
        cost: |c| c.ice40_luts as f64,
    },
    Axis {
        key: "ecp5",
        label: "ECP5 LUT4 equivalents (synth_ecp5; MULT18X18D and BRAMs not counted)",
        cost: |c| c.ecp5_lut_equiv() as f64,
    },
];

const FONT: &str = "sans-serif";

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // DejaVu Sans is a valid font: registering it cannot fail.
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
    });
}

fn family_style(family: &str) -> (RGBColor, &'static str) {
    match family {
        "kv" => (
            RGBColor(214, 39, 40),
            "K_v (v = 3, 4, 5; ROM, constant, table; squarers)",
        ),
        "pow" => (RGBColor(31, 119, 180), "exact cosⁿ (log/exp tables)"),
        _ => (RGBColor(255, 127, 14), "Schlick (divider)"),
    }
}

type DrawResult = Result<(), Box<dyn Error>>;

fn draw<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    rows: &[&Row],
    t: usize,
    out_bits: u32,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let axis = TARGETS[t];
    let pts: Vec<(f64, f64, &Row)> = rows
        .iter()
        .filter_map(|r| {
            // Designs whose costs are not measured have no point.
            let c = r.measured.costs.as_ref()?;
            Some((
                axis.cost(c).max(1.0),
                r.measured.errors.power_16_up().max(0.1),
                *r,
            ))
        })
        .collect();
    let (x0, x1) = pts
        .iter()
        .fold((f64::MAX, 0.0f64), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (y0, y1) = pts
        .iter()
        .fold((f64::MAX, 0.0f64), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!(
                "{out_bits}-bit output: error against cosⁿ (n 16-1023) vs cost, {}",
                axis.key
            ),
            (FONT, 20),
        )
        .margin(14)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(
            ((x0 * 0.8)..(x1 * 1.25)).log_scale(),
            ((y0 * 0.8)..(y1 * 1.3)).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc(axis.label)
        .y_desc("max error vs cosⁿ, n 16-1023 (output LSB)")
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 15))
        .draw()?;
    for fam in ["kv", "pow", "schlick"] {
        let (color, label) = family_style(fam);
        let mine: Vec<&(f64, f64, &Row)> = pts
            .iter()
            .filter(|p| p.2.candidate.design.family() == fam)
            .collect();
        if mine.is_empty() {
            continue;
        }
        chart
            .draw_series(
                mine.iter()
                    .map(|p| Circle::new((p.0, p.1), 4, color.filled())),
            )?
            .label(label)
            .legend(move |(x, y)| Circle::new((x + 8, y), 4, color.filled()));
        let mut front: Vec<(f64, f64)> = mine
            .iter()
            .filter(|p| p.2.fronts.power[t])
            .map(|p| (p.0, p.1))
            .collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        // The front as a staircase: each design holds its error until the next is
        // cheaper-to-better.
        let mut stairs = Vec::new();
        for (i, &(x, y)) in front.iter().enumerate() {
            if i > 0 {
                stairs.push((x, front[i - 1].1));
            }
            stairs.push((x, y));
        }
        chart.draw_series(LineSeries::new(stairs, color.stroke_width(2)))?;
    }
    let refs: Vec<(f64, f64)> = pts
        .iter()
        .filter(|p| p.2.candidate.id.contains("fig4-ref"))
        .map(|p| (p.0, p.1))
        .collect();
    chart
        .draw_series(
            refs.iter()
                .map(|&p| Circle::new(p, 9, BLACK.stroke_width(2))),
        )?
        .label("the paper's Fig. 4 unit (ROM1, generic multipliers)")
        .legend(|(x, y)| Circle::new((x + 8, y), 6, BLACK.stroke_width(2)));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(150, 150, 150))
        .label_font((FONT, 14))
        .draw()?;
    Ok(())
}

/// Writes `pareto-<target>-o<out>.png` and `.svg` into `dir` for every target and
/// output width present; returns the file names.
pub fn plot(dir: &Path, rows: &[Row]) -> Result<Vec<String>, ParetoError> {
    register_font();
    let mut outs: Vec<u32> = rows.iter().map(|r| r.candidate.design.out_bits()).collect();
    outs.sort_unstable();
    outs.dedup();
    let mut files = Vec::new();
    for &o in &outs {
        let mine: Vec<&Row> = rows
            .iter()
            .filter(|r| r.candidate.design.out_bits() == o)
            .collect();
        for (t, axis) in TARGETS.iter().enumerate() {
            let stem = format!("pareto-{}-o{o}", axis.key);
            let err = |file: &str, e: Box<dyn Error>| ParetoError::Plot {
                file: file.to_string(),
                message: e.to_string(),
            };
            let png = format!("{stem}.png");
            let path = dir.join(&png);
            let r: DrawResult = (|| {
                let area = BitMapBackend::new(&path, (1000, 640)).into_drawing_area();
                area.fill(&WHITE)?;
                draw(&area, &mine, t, o)?;
                area.present()?;
                Ok(())
            })();
            r.map_err(|e| err(&png, e))?;
            let svg = format!("{stem}.svg");
            let path = dir.join(&svg);
            let r: DrawResult = (|| {
                let area = SVGBackend::new(&path, (1000, 640)).into_drawing_area();
                area.fill(&WHITE)?;
                draw(&area, &mine, t, o)?;
                area.present()?;
                Ok(())
            })();
            r.map_err(|e| err(&svg, e))?;
            files.push(png);
            files.push(svg);
        }
    }
    Ok(files)
}
