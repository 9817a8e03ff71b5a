//! Figures drawn with plotters, each as PNG and SVG.
//!
//! Text is drawn with plotters' `ab_glyph` backend and DejaVu Sans embedded from the
//! `dejavu` crate, so rendering needs no system fonts.

use std::error::Error;
use std::f64::consts::FRAC_PI_2;
use std::path::Path;
use std::sync::Once;

use glint_lobe::LobeKind;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;

use crate::curves::{fmt_num, Curves};
use crate::error::AnalysisError;
use crate::map::{ErrorMap, MAP_FITS};
use crate::metrics::{level_angle, CUTOFF_LEVEL};

/// A line: legend label, colour, points.
type Series = (String, RGBColor, Vec<(f64, f64)>);

pub(crate) type DrawResult = Result<(), Box<dyn Error>>;

pub(crate) const FONT: &str = "sans-serif";

/// Registers the embedded font once per process.
pub(crate) fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // DejaVu Sans is a valid font: registering it cannot fail.
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
        let _ = plotters::style::register_font(FONT, FontStyle::Bold, dejavu::sans::bold());
    });
}

/// The colour of each lobe in every figure.
fn lobe_color(kind: LobeKind) -> RGBColor {
    match kind {
        LobeKind::Exact => RGBColor(0, 0, 0),
        LobeKind::EnergyFit => RGBColor(214, 39, 40),
        LobeKind::SlopeFit => RGBColor(31, 119, 180),
        LobeKind::Minimax => RGBColor(44, 160, 44),
        LobeKind::Schlick => RGBColor(255, 127, 14),
        LobeKind::Gauss => RGBColor(148, 103, 189),
    }
}

/// The legend name of a lobe, with its parameters.
pub fn lobe_label(kind: LobeKind, n: f64, v: u32) -> String {
    let n = fmt_num(n);
    match kind {
        LobeKind::Exact => format!("cosⁿγ, n = {n}"),
        LobeKind::EnergyFit => format!("K_{v} (energy fit, paper)"),
        LobeKind::SlopeFit => format!("G_{v} (slope fit)"),
        LobeKind::Minimax => format!("minimax, 2^{v}"),
        LobeKind::Schlick => "Schlick".into(),
        LobeKind::Gauss => "Gaussian exp(n(c−1))".into(),
    }
}

/// A line plot panel: `series` are `(label, colour, points)`.
struct LinePanel<'a> {
    title: String,
    x_range: (f64, f64),
    x_desc: &'a str,
    y_desc: &'a str,
    series: Vec<Series>,
    zero_line: bool,
    legend_pos: SeriesLabelPosition,
}

fn y_range(series: &[Series], x: (f64, f64)) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (_, _, pts) in series {
        for &(px, py) in pts {
            if px >= x.0 && px <= x.1 {
                lo = lo.min(py);
                hi = hi.max(py);
            }
        }
    }
    if !(lo.is_finite() && hi.is_finite()) || hi - lo < 1e-12 {
        return (lo.min(0.0) - 0.01, hi.max(0.0) + 0.01);
    }
    let pad = 0.08 * (hi - lo);
    (lo - pad, hi + pad)
}

fn draw_line_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &LinePanel) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (y0, y1) = y_range(&p.series, p.x_range);
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, (FONT, 20))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(78)
        .build_cartesian_2d(p.x_range.0..p.x_range.1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(p.x_desc)
        .y_desc(p.y_desc)
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .light_line_style(WHITE)
        .draw()?;
    if p.zero_line {
        chart.draw_series(LineSeries::new(
            [(p.x_range.0, 0.0), (p.x_range.1, 0.0)],
            RGBColor(120, 120, 120).stroke_width(1),
        ))?;
    }
    for (label, color, pts) in &p.series {
        let color = *color;
        let visible = thin(pts, p.x_range);
        chart
            .draw_series(LineSeries::new(visible, color.stroke_width(2)))?
            .label(label.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(3))
            });
    }
    chart
        .configure_series_labels()
        .position(p.legend_pos.clone())
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(150, 150, 150))
        .label_font((FONT, 15))
        .draw()?;
    Ok(())
}

/// The points of a series inside `x`, thinned to at most ~2 per pixel column of a
/// 900-pixel-wide plot (keeping each column's lowest and highest point, so peaks
/// survive), to keep the SVG files small.
fn thin(pts: &[(f64, f64)], x: (f64, f64)) -> Vec<(f64, f64)> {
    const COLUMNS: f64 = 900.0;
    let width = (x.1 - x.0) / COLUMNS;
    let mut out: Vec<(f64, f64)> = Vec::new();
    let mut column: Option<i64> = None;
    let mut lo = (0.0, f64::INFINITY);
    let mut hi = (0.0, f64::NEG_INFINITY);
    let flush = |out: &mut Vec<(f64, f64)>, lo: (f64, f64), hi: (f64, f64)| {
        let (a, b) = if lo.0 <= hi.0 { (lo, hi) } else { (hi, lo) };
        out.push(a);
        if b != a {
            out.push(b);
        }
    };
    for &(px, py) in pts.iter().filter(|&&(px, _)| px >= x.0 && px <= x.1) {
        let col = ((px - x.0) / width).floor() as i64;
        if column != Some(col) {
            if column.is_some() {
                flush(&mut out, lo, hi);
            }
            column = Some(col);
            lo = (px, py);
            hi = (px, py);
        }
        if py < lo.1 {
            lo = (px, py);
        }
        if py > hi.1 {
            hi = (px, py);
        }
    }
    if column.is_some() {
        flush(&mut out, lo, hi);
    }
    out
}

/// Draws a figure into `dir/stem.png` and `dir/stem.svg`; evaluates to the file names.
macro_rules! render_both {
    ($dir:expr, $stem:expr, $size:expr, |$area:ident| $body:expr) => {{
        register_font();
        let stem: &str = $stem;
        let mut files = Vec::new();
        {
            let file = format!("{stem}.png");
            let path = $dir.join(&file);
            let result: DrawResult = (|| {
                let $area = BitMapBackend::new(&path, $size).into_drawing_area();
                $area.fill(&WHITE)?;
                $body?;
                $area.present()?;
                Ok(())
            })();
            result.map_err(|e| AnalysisError::Plot {
                file: file.clone(),
                message: e.to_string(),
            })?;
            files.push(file);
        }
        {
            let file = format!("{stem}.svg");
            let path = $dir.join(&file);
            let result: DrawResult = (|| {
                let $area = SVGBackend::new(&path, $size).into_drawing_area();
                $area.fill(&WHITE)?;
                $body?;
                $area.present()?;
                Ok(())
            })();
            result.map_err(|e| AnalysisError::Plot {
                file: file.clone(),
                message: e.to_string(),
            })?;
            files.push(file);
        }
        Ok::<Vec<String>, AnalysisError>(files)
    }};
}

pub(crate) use render_both;

fn error_series(c: &Curves, kinds: &[LobeKind]) -> Vec<Series> {
    kinds
        .iter()
        .filter_map(|&k| {
            let err = c.error(k)?;
            let pts = c.angle_deg.iter().copied().zip(err).collect();
            Some((lobe_label(k, c.n, c.v), lobe_color(k), pts))
        })
        .collect()
}

/// The end of the highlight in degrees: where `cos^n` falls to 1e-3 (90° for n = 0).
fn highlight_end_deg(n: f64) -> f64 {
    let g = level_angle(n, CUTOFF_LEVEL)
        .unwrap_or(FRAC_PI_2)
        .to_degrees();
    // Round up to a whole degree for tidy ticks.
    g.ceil().min(90.0)
}

/// The paper's Fig. 2: the error of K_v and G_v against `cos^n` over the highlight.
pub fn fig2(dir: &Path, c: &Curves) -> Result<Vec<String>, AnalysisError> {
    let stem = format!("fig2-error-n{}-v{}", fmt_num(c.n), c.v);
    let panel = LinePanel {
        title: format!(
            "Error of K_{v} and G_{v} against cosⁿγ, n = {}, over the highlight",
            fmt_num(c.n),
            v = c.v
        ),
        x_range: (0.0, highlight_end_deg(c.n)),
        x_desc: "γ (degrees)",
        y_desc: "error  lobe − cosⁿγ",
        series: error_series(c, &[LobeKind::EnergyFit, LobeKind::SlopeFit]),
        zero_line: true,
        legend_pos: SeriesLabelPosition::UpperRight,
    };
    render_both!(dir, &stem, (900, 520), |area| draw_line_panel(
        &area, &panel
    ))
}

/// The paper's Fig. 3: the same error over 0..90° for several n, one panel each.
pub fn fig3(dir: &Path, curves: &[Curves]) -> Result<Vec<String>, AnalysisError> {
    let v = curves.first().map(|c| c.v).unwrap_or(4);
    let stem = format!("fig3-error-whole-range-v{v}");
    let panels: Vec<LinePanel> = curves
        .iter()
        .map(|c| LinePanel {
            title: format!("n = {}: error of K_{v} and G_{v} over 0..90°", fmt_num(c.n)),
            x_range: (0.0, 90.0),
            x_desc: "γ (degrees)",
            y_desc: "lobe − cosⁿγ",
            series: error_series(c, &[LobeKind::EnergyFit, LobeKind::SlopeFit]),
            zero_line: true,
            legend_pos: SeriesLabelPosition::UpperRight,
        })
        .collect();
    let rows = panels.len().max(1);
    let height = 330 * rows as u32;
    render_both!(dir, &stem, (900, height), |area| {
        let parts = area.split_evenly((rows, 1));
        let mut r: DrawResult = Ok(());
        for (part, panel) in parts.iter().zip(&panels) {
            r = r.and(draw_line_panel(part, panel));
        }
        r
    })
}

/// Every lobe overlaid on `cos^n` over the highlight.
pub fn shapes(dir: &Path, c: &Curves) -> Result<Vec<String>, AnalysisError> {
    let stem = format!("shapes-n{}-v{}", fmt_num(c.n), c.v);
    let end = level_angle(c.n, 1e-4)
        .unwrap_or(FRAC_PI_2)
        .to_degrees()
        .ceil()
        .min(90.0);
    let mut series = vec![(
        lobe_label(LobeKind::Exact, c.n, c.v),
        lobe_color(LobeKind::Exact),
        c.angle_deg
            .iter()
            .copied()
            .zip(c.exact.iter().copied())
            .collect(),
    )];
    for (k, vals) in &c.lobes {
        series.push((
            lobe_label(*k, c.n, c.v),
            lobe_color(*k),
            c.angle_deg
                .iter()
                .copied()
                .zip(vals.iter().copied())
                .collect(),
        ));
    }
    let panel = LinePanel {
        title: format!(
            "Lobe shapes against cosⁿγ, n = {}, v = {}",
            fmt_num(c.n),
            c.v
        ),
        x_range: (0.0, end),
        x_desc: "γ (degrees)",
        y_desc: "lobe value",
        series,
        zero_line: false,
        legend_pos: SeriesLabelPosition::UpperRight,
    };
    render_both!(dir, &stem, (900, 560), |area| draw_line_panel(
        &area, &panel
    ))
}

fn fit_title(kind: LobeKind) -> &'static str {
    match kind {
        LobeKind::EnergyFit => "K_v (energy fit)",
        LobeKind::SlopeFit => "G_v (slope fit)",
        _ => "minimax fit",
    }
}

fn draw_map<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, map: &ErrorMap) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (lo, hi) = log_bounds(map);
    let color = |e: f64| {
        let x = e.max(1e-300).log10().clamp(lo, hi);
        ViridisRGB::get_color_normalized(x, lo, hi)
    };
    let (main, bar) = area.split_horizontally(area.dim_in_pixel().0 - 130);
    let title_h = 40;
    let (title, panels) = main.split_vertically(title_h);
    title.titled(
        "Max abs error against cosⁿγ over 0..90°, by n and v = log₂(power)",
        (FONT, 20),
    )?;
    let parts = panels.split_evenly((1, MAP_FITS.len()));
    let n_lo = map.ns.first().copied().unwrap_or(1.0);
    let n_hi = map.ns.last().copied().unwrap_or(1000.0);
    let v_lo = *map.vs.first().unwrap_or(&1) as f64 - 0.5;
    let v_hi = *map.vs.last().unwrap_or(&8) as f64 + 0.5;
    for (f, part) in parts.iter().enumerate() {
        let mut chart = ChartBuilder::on(part)
            .caption(fit_title(MAP_FITS[f]), (FONT, 18))
            .margin(8)
            .x_label_area_size(45)
            .y_label_area_size(if f == 0 { 50 } else { 30 })
            .build_cartesian_2d((n_lo..n_hi).log_scale(), v_lo..v_hi)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("n (log scale)")
            .y_desc(if f == 0 { "v" } else { "" })
            .y_labels(map.vs.len())
            .y_label_formatter(&|y| format!("{y:.0}"))
            .x_label_formatter(&|x| fmt_num(x.round()))
            .label_style((FONT, 14))
            .axis_desc_style((FONT, 16))
            .draw()?;
        // Cell i spans the geometric midpoints to its neighbours.
        let edges: Vec<f64> = (0..=map.ns.len())
            .map(|i| {
                if i == 0 {
                    n_lo
                } else if i == map.ns.len() {
                    n_hi
                } else {
                    (map.ns[i - 1] * map.ns[i]).sqrt()
                }
            })
            .collect();
        for (iv, &v) in map.vs.iter().enumerate() {
            let v = v as f64;
            chart.draw_series((0..map.ns.len()).map(|i| {
                Rectangle::new(
                    [(edges[i], v - 0.5), (edges[i + 1], v + 0.5)],
                    color(map.errors[f][iv][i]).filled(),
                )
            }))?;
        }
    }
    // Colour bar.
    let mut cb = ChartBuilder::on(&bar)
        .margin_top(title_h + 40)
        .margin_bottom(55)
        .margin_right(10)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..1.0, lo..hi)?;
    cb.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc("max abs error")
        .y_label_formatter(&|y| format!("1e{:.0}", y))
        .y_labels(((hi - lo) as usize + 1).min(12))
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .draw()?;
    let steps = 200;
    cb.draw_series((0..steps).map(|i| {
        let y0 = lo + (hi - lo) * i as f64 / steps as f64;
        let y1 = lo + (hi - lo) * (i + 1) as f64 / steps as f64;
        Rectangle::new(
            [(0.0, y0), (1.0, y1)],
            color(10f64.powf(0.5 * (y0 + y1))).filled(),
        )
    }))?;
    Ok(())
}

/// The colour range: whole decades around the map's errors, at least 1e-4 (the dips
/// to ~0 where n = 2^v would otherwise squeeze every other colour together).
fn log_bounds(map: &ErrorMap) -> (f64, f64) {
    let all = map.errors.iter().flatten().flatten().copied();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for e in all {
        let l = e.max(1e-4).log10();
        lo = lo.min(l);
        hi = hi.max(l);
    }
    if !lo.is_finite() {
        return (-4.0, 0.0);
    }
    (lo.floor(), hi.ceil().max(lo.floor() + 1.0))
}

/// The map of max abs error over n (log axis) and v, for k, g and minimax.
pub fn error_map(dir: &Path, map: &ErrorMap) -> Result<Vec<String>, AnalysisError> {
    render_both!(dir, "error-map", (1300, 480), |area| draw_map(&area, map))
}
