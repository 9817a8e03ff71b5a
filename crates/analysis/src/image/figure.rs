//! The comparison picture (reference | test | ΔE heat map with a colour bar, one row
//! per compared image) and the sweep plot (mean and p99 ΔE against n).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;

use super::delta_e::JND_DELTA_E;
use super::Srgb8Image;
use crate::curves::fmt_num;
use crate::error::AnalysisError;
use crate::plot::{register_font, render_both, DrawResult, FONT};

/// The top of the heat map's ΔE scale: larger values are drawn in the top colour. Fixed
/// (not the image's max) so that figures of different lobes can be compared; 5 puts
/// the just-noticeable difference 2.3 near the middle.
pub const DELTA_E_SCALE_MAX: f64 = 5.0;

/// Pixels between panels and around the figure.
const GAP: u32 = 12;
/// Height of a row's title line and of the column headings.
const TEXT_H: u32 = 26;
/// Width of the colour bar column (bar, ticks and labels).
const BAR_W: u32 = 110;
/// The largest figure side accepted (a sanity bound on the buffer).
const MAX_FIGURE_SIDE: u32 = 30000;

/// One row of the comparison picture.
#[derive(Clone, Copy, Debug)]
pub struct ComparisonRow<'a> {
    /// Title of the row (lobe and parameters, maybe the headline metrics).
    pub title: &'a str,
    /// The reference image (left).
    pub reference: &'a Srgb8Image,
    /// The compared image (middle).
    pub test: &'a Srgb8Image,
    /// Its ΔE map against the reference (right), one value per pixel.
    pub delta_e: &'a [f64],
}

/// The heat-map colour of a ΔE value (viridis over `0..=scale_max`).
fn heat(e: f64, scale_max: f64) -> [u8; 3] {
    let e = if e.is_nan() {
        scale_max
    } else {
        e.clamp(0.0, scale_max)
    };
    let c = ViridisRGB::get_color_normalized(e, 0.0, scale_max);
    [c.0, c.1, c.2]
}

/// The colour bar is as tall as an image, at least 100 pixels.
fn bar_height(img_h: u32) -> u32 {
    img_h.max(100)
}

struct Layout {
    w: u32,
    h: u32,
    img_w: u32,
    img_h: u32,
}

impl Layout {
    fn of(rows: &[ComparisonRow]) -> Result<Layout, AnalysisError> {
        let first = rows
            .first()
            .ok_or(AnalysisError::EmptyList("comparison rows"))?;
        let (img_w, img_h) = (first.reference.width(), first.reference.height());
        for r in rows {
            r.reference
                .check_same_size(r.test.width(), r.test.height())?;
            r.reference.check_same_size(img_w, img_h)?;
            if r.delta_e.len() != r.reference.pixels().len() {
                return Err(AnalysisError::ImageSize {
                    width: img_w,
                    height: img_h,
                    pixels: r.delta_e.len(),
                });
            }
        }
        let n = rows.len() as u64;
        let w = 3 * img_w as u64 + 4 * GAP as u64 + BAR_W as u64;
        let rows_h = TEXT_H as u64 + n * (TEXT_H as u64 + img_h as u64 + GAP as u64) + GAP as u64;
        // The colour bar and its caption must fit too.
        let h = rows_h.max(2 * TEXT_H as u64 + bar_height(img_h) as u64 + 2 * TEXT_H as u64);
        if w > MAX_FIGURE_SIDE as u64 || h > MAX_FIGURE_SIDE as u64 {
            return Err(AnalysisError::TooMany {
                what: "figure pixels per side",
                count: w.max(h) as usize,
                max: MAX_FIGURE_SIDE as usize,
            });
        }
        Ok(Layout {
            w: w as u32,
            h: h as u32,
            img_w,
            img_h,
        })
    }

    /// Top-left corner of panel `col` of row `row`.
    fn panel(&self, row: usize, col: u32) -> (u32, u32) {
        let y = TEXT_H + row as u32 * (TEXT_H + self.img_h + GAP) + TEXT_H;
        (GAP + col * (self.img_w + GAP), y)
    }
}

fn blit(buf: &mut [u8], stride: u32, at: (u32, u32), w: u32, px: impl Iterator<Item = [u8; 3]>) {
    for (i, p) in px.enumerate() {
        let (x, y) = (at.0 + i as u32 % w, at.1 + i as u32 / w);
        let o = 3 * (y as usize * stride as usize + x as usize);
        buf[o..o + 3].copy_from_slice(&p);
    }
}

fn draw_labels<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    lay: &Layout,
    rows: &[ComparisonRow],
    scale_max: f64,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let text = |size| TextStyle::from((FONT, size).into_font()).color(&BLACK);
    let heads = ["reference (exact)", "compared", "CIEDE2000 ΔE"];
    for (c, head) in heads.iter().enumerate() {
        let (x, _) = lay.panel(0, c as u32);
        area.draw_text(head, &text(17), (x as i32, 4))?;
    }
    for (r, row) in rows.iter().enumerate() {
        let (x, y) = lay.panel(r, 0);
        area.draw_text(row.title, &text(16), (x as i32, (y - TEXT_H + 4) as i32))?;
    }
    // The colour bar: spans the first row's image height, top = scale_max.
    let (bx, by) = (lay.panel(0, 3).0 as i32, lay.panel(0, 0).1 as i32);
    let bh = bar_height(lay.img_h) as i32;
    let bw = 18;
    for i in 0..bh {
        let e = scale_max * (1.0 - i as f64 / (bh - 1).max(1) as f64);
        let c = heat(e, scale_max);
        area.draw(&Rectangle::new(
            [(bx, by + i), (bx + bw, by + i + 1)],
            RGBColor(c[0], c[1], c[2]).filled(),
        ))?;
    }
    area.draw(&Rectangle::new(
        [(bx, by), (bx + bw, by + bh)],
        BLACK.stroke_width(1),
    ))?;
    let y_of = |e: f64| by + ((1.0 - e / scale_max) * (bh - 1) as f64).round() as i32;
    let mut ticks: Vec<f64> = (0..=scale_max.floor() as i32).map(f64::from).collect();
    if JND_DELTA_E < scale_max {
        ticks.push(JND_DELTA_E);
    }
    for t in ticks {
        let y = y_of(t);
        area.draw(&PathElement::new(
            vec![(bx + bw, y), (bx + bw + 5, y)],
            BLACK,
        ))?;
        let label = if t == JND_DELTA_E {
            format!("{} JND", fmt_num(t))
        } else if t == scale_max.floor() {
            format!("≥{}", fmt_num(t))
        } else {
            fmt_num(t)
        };
        area.draw_text(&label, &text(13), (bx + bw + 8, y - 7))?;
    }
    area.draw_text("ΔE00", &text(14), (bx, by + bh + 6))?;
    Ok(())
}

/// The comparison picture as an 8-bit RGB PNG (write it with `glint_io::write_atomic`).
/// Each row shows reference | compared | ΔE heat map (viridis, 0 to `scale_max`,
/// values above drawn as `scale_max`), with a labelled colour bar on the right; all
/// rows must have images of one size.
pub fn comparison_png(rows: &[ComparisonRow], scale_max: f64) -> Result<Vec<u8>, AnalysisError> {
    if !(scale_max.is_finite() && scale_max > 0.0) {
        return Err(AnalysisError::InvalidScale(scale_max));
    }
    let lay = Layout::of(rows)?;
    let mut buf = vec![255u8; lay.w as usize * lay.h as usize * 3];
    for (r, row) in rows.iter().enumerate() {
        let px = |img: &Srgb8Image| img.pixels().to_vec().into_iter();
        blit(
            &mut buf,
            lay.w,
            lay.panel(r, 0),
            lay.img_w,
            px(row.reference),
        );
        blit(&mut buf, lay.w, lay.panel(r, 1), lay.img_w, px(row.test));
        let heat_px = row.delta_e.iter().map(|&e| heat(e, scale_max));
        blit(&mut buf, lay.w, lay.panel(r, 2), lay.img_w, heat_px);
    }
    register_font();
    let file = "comparison picture".to_string();
    let plot_err = |e: Box<dyn std::error::Error>| AnalysisError::Plot {
        file: file.clone(),
        message: e.to_string(),
    };
    {
        let area = BitMapBackend::with_buffer(&mut buf, (lay.w, lay.h)).into_drawing_area();
        draw_labels(&area, &lay, rows, scale_max).map_err(plot_err)?;
        area.present().map_err(|e| plot_err(Box::new(e)))?;
    }
    encode_png(lay.w, lay.h, &buf)
}

/// An 8-bit RGB PNG of `rgb`, tagged sRGB.
fn encode_png(w: u32, h: u32, rgb: &[u8]) -> Result<Vec<u8>, AnalysisError> {
    let mut out = Vec::new();
    let err = |e: png::EncodingError| AnalysisError::Plot {
        file: "comparison picture".into(),
        message: e.to_string(),
    };
    let mut enc = png::Encoder::new(&mut out, w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    let mut writer = enc.write_header().map_err(err)?;
    writer.write_image_data(rgb).map_err(err)?;
    writer.finish().map_err(err)?;
    Ok(out)
}

/// One line of the sweep plot: a lobe at one v, its ΔE summary at each n.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepSeries {
    /// Legend label (lobe and v).
    pub label: String,
    /// `(n, mean ΔE, p99 ΔE)`, n ascending.
    pub points: Vec<(f64, f64, f64)>,
}

fn series_color(i: usize) -> RGBColor {
    let c = Palette99::pick(i).to_rgba();
    RGBColor(c.0, c.1, c.2)
}

fn draw_sweep<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    series: &[SweepSeries],
    title: &str,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let ns = series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
    let (n_lo, n_hi) = ns.fold((f64::INFINITY, 0.0f64), |(lo, hi), n| {
        (lo.min(n), hi.max(n))
    });
    let (n_lo, n_hi) = (n_lo.max(1e-3), n_hi.max(n_lo * 10.0).max(1e-2));
    let (title_area, panels) = area.split_vertically(36);
    title_area.titled(title, (FONT, 20))?;
    let parts = panels.split_evenly((1, 2));
    for (k, part) in parts.iter().enumerate() {
        let pick = |p: &(f64, f64, f64)| if k == 0 { p.1 } else { p.2 };
        let y_hi = series
            .iter()
            .flat_map(|s| s.points.iter().map(pick))
            .filter(|y| y.is_finite())
            .fold(JND_DELTA_E, f64::max)
            * 1.08;
        let mut chart = ChartBuilder::on(part)
            .caption(
                if k == 0 {
                    "mean ΔE00"
                } else {
                    "99th percentile ΔE00"
                },
                (FONT, 18),
            )
            .margin(10)
            .x_label_area_size(45)
            .y_label_area_size(55)
            .build_cartesian_2d((n_lo..n_hi).log_scale(), 0.0..y_hi)?;
        chart
            .configure_mesh()
            .x_desc("n (log scale)")
            .y_desc("ΔE00")
            .x_label_formatter(&|x| fmt_num(x.round()))
            .label_style((FONT, 14))
            .axis_desc_style((FONT, 16))
            .light_line_style(WHITE)
            .draw()?;
        let jnd = RGBColor(120, 120, 120);
        chart
            .draw_series(LineSeries::new(
                [(n_lo, JND_DELTA_E), (n_hi, JND_DELTA_E)],
                jnd,
            ))?
            .label("ΔE 2.3 (JND)")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], jnd));
        for (i, s) in series.iter().enumerate() {
            let c = series_color(i);
            let pts: Vec<(f64, f64)> = s.points.iter().map(|p| (p.0, pick(p))).collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))?
                .label(s.label.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 24, y)], c.stroke_width(3))
                });
            chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, c.filled())))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(150, 150, 150))
            .label_font((FONT, 13))
            .draw()?;
    }
    Ok(())
}

/// Draws the sweep plot into `dir/stem.png` and `dir/stem.svg`: mean (left) and 99th
/// percentile (right) CIEDE2000 ΔE against n on a log axis, one line per series, with
/// the JND 2.3 marked. Returns the file names.
pub fn sweep_plot(
    dir: &Path,
    stem: &str,
    title: &str,
    series: &[SweepSeries],
) -> Result<Vec<String>, AnalysisError> {
    if series.iter().all(|s| s.points.is_empty()) {
        return Err(AnalysisError::EmptyList("sweep points"));
    }
    let bad = series
        .iter()
        .flat_map(|s| &s.points)
        .find(|p| !(p.0 > 0.0 && p.0.is_finite()));
    if let Some(p) = bad {
        return Err(AnalysisError::InvalidN(p.0));
    }
    render_both!(dir, stem, (1300, 560), |area| draw_sweep(
        &area, series, title
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_png(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
        let dec = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut r = dec.read_info().unwrap();
        let mut buf = vec![0; r.output_buffer_size().unwrap()];
        let info = r.next_frame(&mut buf).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgb);
        buf.truncate(info.buffer_size());
        (info.width, info.height, buf)
    }

    #[test]
    fn comparison_figure_holds_both_images_and_the_heat_map() {
        let (w, h) = (30u32, 20u32);
        let a = Srgb8Image::new(w, h, vec![[200, 30, 40]; 600]).unwrap();
        let b = Srgb8Image::new(w, h, vec![[20, 30, 240]; 600]).unwrap();
        let de: Vec<f64> = (0..600).map(|i| if i < 300 { 0.0 } else { 9.0 }).collect();
        let rows = [
            ComparisonRow {
                title: "first",
                reference: &a,
                test: &b,
                delta_e: &de,
            },
            ComparisonRow {
                title: "second",
                reference: &a,
                test: &a,
                delta_e: &[0.0; 600],
            },
        ];
        let (fw, fh, px) = read_png(&comparison_png(&rows, DELTA_E_SCALE_MAX).unwrap());
        let lay = Layout::of(&rows).unwrap();
        assert_eq!((fw, fh), (lay.w, lay.h));
        let at = |(x, y): (u32, u32), dx: u32, dy: u32| {
            let o = 3 * ((y + dy) as usize * fw as usize + (x + dx) as usize);
            [px[o], px[o + 1], px[o + 2]]
        };
        // Pixel (29, 19) of each panel: bottom right, clear of any label.
        assert_eq!(at(lay.panel(0, 0), 29, 19), [200, 30, 40]);
        assert_eq!(at(lay.panel(0, 1), 29, 19), [20, 30, 240]);
        // Viridis: 0 is dark purple (68, 1, 84), the top is yellow (253, 231, 37).
        assert_eq!(at(lay.panel(0, 2), 0, 0), [68, 1, 84]);
        let top = at(lay.panel(0, 2), 29, 19);
        assert!(top[0] > 240 && top[1] > 220 && top[2] < 60, "{top:?}");
        assert_eq!(at(lay.panel(1, 1), 29, 19), [200, 30, 40]);
    }

    #[test]
    fn bad_figure_input_is_an_error() {
        let a = Srgb8Image::new(4, 4, vec![[0; 3]; 16]).unwrap();
        let b = Srgb8Image::new(4, 2, vec![[0; 3]; 8]).unwrap();
        let row = |t| ComparisonRow {
            title: "x",
            reference: &a,
            test: t,
            delta_e: &[0.0; 16],
        };
        assert!(comparison_png(&[], 5.0).is_err());
        assert!(comparison_png(&[row(&b)], 5.0).is_err());
        assert!(comparison_png(&[row(&a)], f64::NAN).is_err());
        let short = ComparisonRow {
            delta_e: &[0.0; 3],
            ..row(&a)
        };
        assert!(comparison_png(&[short], 5.0).is_err());
    }

    #[test]
    fn sweep_plot_writes_png_and_svg() {
        let dir = tempfile::tempdir().unwrap();
        let s = vec![
            SweepSeries {
                label: "K_4".into(),
                points: vec![(10.0, 0.5, 2.0), (1000.0, 0.1, 0.9)],
            },
            SweepSeries {
                label: "G_4".into(),
                points: vec![(10.0, 0.7, 3.0), (1000.0, 0.2, 1.1)],
            },
        ];
        let files = sweep_plot(dir.path(), "sweep", "t", &s).unwrap();
        assert_eq!(files, ["sweep.png", "sweep.svg"]);
        let svg = std::fs::read_to_string(dir.path().join("sweep.svg")).unwrap();
        assert!(svg.contains("K_4") && svg.contains("G_4") && svg.contains("JND"));
        let (w, h, _) = read_png(&std::fs::read(dir.path().join("sweep.png")).unwrap());
        assert_eq!((w, h), (1300, 560));
        let bad = [SweepSeries {
            label: "x".into(),
            points: vec![(0.0, 1.0, 1.0)],
        }];
        assert!(sweep_plot(dir.path(), "bad", "t", &bad).is_err());
        assert!(sweep_plot(dir.path(), "bad", "t", &[]).is_err());
    }
}
