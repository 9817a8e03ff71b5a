//! `glint compare`: renders one scene with the exact `cos^n` lobe and with cheaper
//! lobes, and measures the difference in the image as a viewer sees it (8-bit sRGB):
//! PSNR, SSIM, CIEDE2000 ΔE and ꟻLIP, over the whole image and over the highlight
//! (issue 13). `--sweep` repeats it over n and v and plots ΔE against n.

use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::bail;
use glint_analysis::image::{
    compare, comparison_png, delta_e_map, highlight_mask, sweep_plot, ComparisonRow, ImageMetrics,
    Srgb8Image, SweepSeries, DELTA_E_SCALE_MAX, HIGHLIGHT_FRACTION,
};
use glint_analysis::{fmt_num, lobe_label, Staging};
use glint_lobe::LobeKind;
use glint_render::{Depth, Input, Rendered, Renderer, Scene, SceneLobe};
use serde_json::{json, Value};

use super::choice::choice;
use super::render::{check_output_dir, open_renderer as open};
use super::scene_flags::SceneFlags;

/// The n of the sweep (issue 13, item 3).
const SWEEP_N: [f64; 7] = [10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0];
/// The v of the sweep (issue 13, item 3).
const SWEEP_V: [u32; 5] = [2, 3, 4, 5, 6];
/// Lobes swept when no --lobe is given: the paper's K_v and the slope fit G_v.
const SWEEP_LOBES: [LobeKind; 2] = [LobeKind::EnergyFit, LobeKind::SlopeFit];
/// Rec. 709 luminance weights of linear RGB, for the specular term's brightness.
const LUMINANCE: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// Arguments of `glint compare`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    glint compare --lobe k --n 100 --v 4 -o cmp.png\n  \
    glint compare brain.nii.gz --preset mr-t2-brain --view left --lobe k --lobe g --json -o cmp.png\n  \
    glint compare --scene brain.json --lobe schlick -o cmp.png\n  \
    glint compare brain.nii.gz --preset mr-t2-brain --view left --sweep -o sweep/\n\n\
Metrics are taken on the 8-bit sRGB image a PNG holds: PSNR over R, G, B (peak 255); SSIM\n\
on luma (Wang et al. 2004: 11x11 Gaussian, sigma 1.5); CIEDE2000 dE (mean, 99th percentile,\n\
max, share of pixels above 1 and above 2.3, the just-noticeable difference); mean FLIP\n\
(NVIDIA's LDR-FLIP, 67 pixels per degree). 'highlight' rows take only the pixels where the\n\
exact image's specular term exceeds 10% of its maximum.")]
pub struct Args {
    // Boxed: the options are many, and main's subcommand enum should stay small.
    #[command(flatten)]
    opts: Box<Options>,
}

/// The options of `glint compare` (see `glint render` for the scene options).
#[derive(clap::Args)]
struct Options {
    #[command(flatten)]
    scene: SceneFlags,
    /// The comparison picture (PNG) [default: compare.png]; with --sweep, the output
    /// directory [default: compare-sweep].
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Lobe to compare against exact; repeatable; `hw` is the unit of --hw-config
    /// [default: k; with --sweep: k and g; --sweep takes no hw].
    #[arg(long = "lobe", value_parser = choice::<SceneLobe>(SceneLobe::ALL.map(|k| k.name())))]
    lobes: Vec<SceneLobe>,
    /// Print the metrics (and the resolved scene) as JSON instead of a table.
    #[arg(long, conflicts_with = "sweep")]
    json: bool,
    /// Sweep n over 10, 20, 50, 100, 200, 500, 1000 and v over 2..6: a table
    /// (sweep.csv, sweep.md) and plots of mean and p99 dE against n, into -o.
    #[arg(long)]
    sweep: bool,
    /// The n of --sweep, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        requires = "sweep",
        allow_negative_numbers = true
    )]
    sweep_n: Vec<f64>,
    /// The v of --sweep, comma-separated.
    #[arg(long, value_delimiter = ',', requires = "sweep")]
    sweep_v: Vec<u32>,
    /// Top of the heat map's ΔE scale (larger values get the top colour).
    #[arg(long, default_value_t = DELTA_E_SCALE_MAX)]
    scale_max: f64,
    /// No progress messages on stderr.
    #[arg(short, long)]
    quiet: bool,
}

/// The scene of the flags, lobe exact.
fn build_scene(o: &Options) -> anyhow::Result<Scene> {
    if o.sweep && (o.scene.n.is_some() || o.scene.v.is_some()) {
        bail!("--sweep chooses n and v itself: drop --n and --v (or use --sweep-n, --sweep-v)");
    }
    let mut scene = o.scene.scene()?;
    scene.lobe.kind = LobeKind::Exact.into();
    Ok(scene)
}

/// A render and its 8-bit sRGB image (the PNG's samples).
struct Shot {
    rendered: Rendered,
    srgb: Srgb8Image,
}

/// Renders `scene` with the shared renderer (the volume is read and classified once).
fn shoot(renderer: &mut Renderer, scene: &Scene) -> anyhow::Result<Shot> {
    let rendered = renderer.render(scene, &|_| {})?;
    let img = &rendered.image;
    let srgb = Srgb8Image::from_bytes(img.width, img.height, &img.encode_srgb(Depth::Eight))?;
    Ok(Shot { rendered, srgb })
}

/// The exact render of a scene and what the lobes are compared with.
struct Reference {
    shot: Shot,
    /// Pixels where the exact specular term exceeds 10% of its maximum.
    mask: Vec<bool>,
}

/// The specular term's contribution per pixel: the luminance of `full` minus that of
/// the same scene rendered without specular (`dark`), in linear light, at least 0.
fn specular_term(full: &Rendered, dark: &Rendered) -> Vec<f32> {
    let lum = |p: &[f32; 3]| p.iter().zip(LUMINANCE).map(|(c, w)| c * w).sum::<f32>();
    full.image
        .rgb
        .iter()
        .zip(&dark.image.rgb)
        .map(|(a, b)| (lum(a) - lum(b)).max(0.0))
        .collect()
}

/// Renders the scene (already exact) and its highlight mask; `dark` is the same scene
/// without specular, rendered once per run (it does not depend on the lobe or n).
fn reference(renderer: &mut Renderer, scene: &Scene, dark: &Rendered) -> anyhow::Result<Reference> {
    let shot = shoot(renderer, scene)?;
    let mask = highlight_mask(&specular_term(&shot.rendered, dark));
    Ok(Reference { shot, mask })
}

/// The scene without specular light.
fn dark_scene(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    s.material.specular = Some(0.0);
    s
}

/// One lobe compared with exact.
struct Comparison {
    kind: SceneLobe,
    /// The unit of a `hw` row.
    hw: Option<glint_hw::Config>,
    n: f64,
    v: u32,
    frame: Duration,
    shot: Shot,
    delta_e: Vec<f64>,
    whole: ImageMetrics,
    highlight: Option<ImageMetrics>,
}

fn compare_lobe(
    renderer: &mut Renderer,
    reference: &Reference,
    flags: &SceneFlags,
    kind: SceneLobe,
    v: u32,
) -> anyhow::Result<Comparison> {
    let mut scene = reference.shot.rendered.scene.clone();
    scene.derived = None;
    scene.lobe.v = v;
    flags.set_lobe(&mut scene, kind);
    let v = scene.lobe.v;
    let shot = shoot(renderer, &scene)?;
    let exact = &reference.shot.srgb;
    let (whole, highlight) = compare(exact, &shot.srgb, Some(&reference.mask))?;
    Ok(Comparison {
        kind,
        hw: scene.lobe.hw.filter(|_| kind == SceneLobe::Hw),
        n: scene.lobe.n.unwrap_or_default(),
        v,
        frame: shot.rendered.timings.get("frame"),
        delta_e: delta_e_map(exact, &shot.srgb)?,
        shot,
        whole,
        highlight,
    })
}

/// Runs `glint compare`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let o = *args.opts;
    if !(o.scale_max.is_finite() && o.scale_max > 0.0) {
        bail!("--scale-max {}: expected a positive number", o.scale_max);
    }
    let scene = build_scene(&o)?;
    if o.sweep {
        return run_sweep(&o, scene);
    }
    let output = o.output.clone().unwrap_or_else(|| "compare.png".into());
    check_output_dir(&output)?;
    let lobes = if o.lobes.is_empty() {
        vec![LobeKind::EnergyFit.into()]
    } else {
        o.lobes.clone()
    };
    let mut renderer = open(&scene, &o.scene.read_options())?;
    let dark = renderer.render(&dark_scene(&scene), &|_| {})?;
    let reference = reference(&mut renderer, &scene, &dark)?;
    let v = reference.shot.rendered.scene.lobe.v;
    let mut rows = Vec::new();
    for &kind in &lobes {
        rows.push(compare_lobe(&mut renderer, &reference, &o.scene, kind, v)?);
    }
    write_figure(&output, &reference, &rows, o.scale_max)?;
    if o.json {
        let doc = json_report(&reference, &dark, &rows)?;
        println!("{}", serde_json::to_string_pretty(&doc)?);
    } else {
        print!("{}", text_report(&reference, &dark, &rows));
    }
    if !o.quiet {
        eprintln!("glint: wrote {}", output.display());
    }
    Ok(())
}

/// Whether the lobe has a v to show (the power fits and the unit).
fn uses_v(kind: SceneLobe) -> bool {
    kind.float().is_none_or(|k| k.uses_v())
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// A row title: the lobe with its parameters (for the unit: its ROM and output width).
fn lobe_title(c: &Comparison) -> String {
    let (n, v) = (c.n, c.v);
    let kind = match (c.kind, &c.hw) {
        (SceneLobe::Float(kind), _) => kind,
        (SceneLobe::Hw, hw) => {
            let hw = hw.clone().unwrap_or_default();
            return format!(
                "hw unit ({} ROM, {}-bit output, v = {v}), n = {}",
                hw.coefficients,
                hw.out_bits,
                fmt_num(n.round())
            );
        }
    };
    let label = lobe_label(kind, n, v);
    if kind == LobeKind::Exact {
        label
    } else {
        format!("{label}, n = {}", fmt_num(n))
    }
}

fn write_figure(
    path: &Path,
    reference: &Reference,
    rows: &[Comparison],
    scale_max: f64,
) -> anyhow::Result<()> {
    let titles: Vec<String> = rows
        .iter()
        .map(|c| {
            let de = c.whole.delta_e.map(|d| (d.mean, d.p99)).unwrap_or_default();
            format!(
                "{}: mean ΔE {:.3}, p99 {:.3}{}",
                lobe_title(c),
                de.0,
                de.1,
                match c.highlight.and_then(|h| h.delta_e) {
                    Some(h) => format!("; highlight mean {:.3}, p99 {:.3}", h.mean, h.p99),
                    None => String::new(),
                }
            )
        })
        .collect();
    let fig: Vec<ComparisonRow> = rows
        .iter()
        .zip(&titles)
        .map(|(c, t)| ComparisonRow {
            title: t,
            reference: &reference.shot.srgb,
            test: &c.shot.srgb,
            delta_e: &c.delta_e,
        })
        .collect();
    let png = comparison_png(&fig, scale_max)?;
    glint_io::write_atomic(path, |w| w.write_all(&png))?;
    Ok(())
}

/// Formats an optional number, "-" when absent.
fn num(x: Option<f64>, digits: usize) -> String {
    match x {
        Some(v) if v.is_infinite() => "inf".into(),
        Some(v) => format!("{v:.digits$}"),
        None => "-".into(),
    }
}

const TABLE_HEAD: &str =
    "lobe      n     v  render ms  pixels  scope      PSNR dB  SSIM     mean ΔE  p99 ΔE  max ΔE  >1 %    >2.3 %  FLIP\n";

fn table_row(c: &Comparison, scope: &str, m: &ImageMetrics) -> String {
    let de = m.delta_e;
    format!(
        "{:<9} {:<5} {:<2} {:<10.1} {:<7} {:<10} {:<8} {:<8} {:<8} {:<7} {:<7} {:<7} {:<7} {}\n",
        c.kind.name(),
        fmt_num(c.n),
        if uses_v(c.kind) {
            c.v.to_string()
        } else {
            "-".into()
        },
        ms(c.frame),
        m.pixels,
        scope,
        num(m.psnr, 2),
        num(m.ssim, 5),
        num(de.map(|d| d.mean), 4),
        num(de.map(|d| d.p99), 3),
        num(de.map(|d| d.max), 3),
        num(de.map(|d| 100.0 * d.above_1), 3),
        num(de.map(|d| 100.0 * d.above_jnd), 3),
        num(m.flip, 5),
    )
}

/// The table on stdout; the classification time is the first render's (`dark`).
fn text_report(reference: &Reference, dark: &Rendered, rows: &[Comparison]) -> String {
    let r = &reference.shot.rendered;
    let s = &r.scene;
    let hl = reference.mask.iter().filter(|&&m| m).count();
    let mut out = format!(
        "glint compare: {}, preset {}, {} mode, {}x{}, n = {}, {} geometry\n\
         exact: classify {:.1} ms, render {:.1} ms\n\
         highlight: {hl} pixels ({:.2}%) where the exact specular term exceeds {}% of its max\n\n",
        input_name(&s.input),
        s.preset.as_deref().unwrap_or("custom"),
        s.mode.name(),
        s.size[0],
        s.size[1],
        fmt_num(s.lobe.n.unwrap_or_default()),
        s.lobe.geometry,
        ms(dark.timings.get("classify")),
        ms(r.timings.get("frame")),
        100.0 * hl as f64 / reference.mask.len().max(1) as f64,
        fmt_num(100.0 * HIGHLIGHT_FRACTION),
    );
    out.push_str(TABLE_HEAD);
    for c in rows {
        out.push_str(&table_row(c, "image", &c.whole));
        if let Some(h) = &c.highlight {
            out.push_str(&table_row(c, "highlight", h));
        }
    }
    out
}

fn input_name(input: &Input) -> String {
    match input {
        Input::Path(p) => p.display().to_string(),
        Input::Phantom { name, size } => format!("{name} phantom {size}^3"),
        Input::None => "meshes".into(),
    }
}

fn metrics_json(m: &ImageMetrics) -> Value {
    let finite = |x: Option<f64>| x.filter(|v| v.is_finite());
    json!({
        "pixels": m.pixels,
        "psnr_db": finite(m.psnr),
        "ssim": m.ssim,
        "delta_e": m.delta_e.map(|d| json!({
            "mean": d.mean, "p99": d.p99, "max": d.max,
            "share_above_1": d.above_1, "share_above_2_3": d.above_jnd,
        })),
        "flip_mean": m.flip,
    })
}

fn json_report(
    reference: &Reference,
    dark: &Rendered,
    rows: &[Comparison],
) -> anyhow::Result<Value> {
    let r = &reference.shot.rendered;
    let comparisons: Vec<Value> = rows
        .iter()
        .map(|c| {
            json!({
                "lobe": c.kind.name(),
                "n": c.n,
                "v": uses_v(c.kind).then_some(c.v),
                "render_ms": ms(c.frame),
                "image": metrics_json(&c.whole),
                "highlight": c.highlight.as_ref().map(metrics_json),
            })
        })
        .collect();
    Ok(json!({
        "scene": serde_json::to_value(&r.scene)?,
        "exact": { "classify_ms": ms(dark.timings.get("classify")), "render_ms": ms(r.timings.get("frame")) },
        "highlight": {
            "fraction_of_max": HIGHLIGHT_FRACTION,
            "pixels": reference.mask.iter().filter(|&&m| m).count(),
        },
        "metrics_on": "8-bit sRGB; PSNR over RGB; SSIM on Rec. 709 luma; CIEDE2000 (D65); LDR-FLIP at 67 pixels per degree",
        "comparisons": comparisons,
    }))
}

/// One point of the sweep.
struct SweepRow {
    kind: LobeKind,
    n: f64,
    v: Option<u32>,
    frame: Duration,
    whole: ImageMetrics,
    highlight: Option<ImageMetrics>,
}

fn run_sweep(o: &Options, scene: Scene) -> anyhow::Result<()> {
    let ns = if o.sweep_n.is_empty() {
        SWEEP_N.to_vec()
    } else {
        o.sweep_n.clone()
    };
    let vs = if o.sweep_v.is_empty() {
        SWEEP_V.to_vec()
    } else {
        o.sweep_v.clone()
    };
    glint_analysis::check_lists(&ns, &vs)?;
    if let Some(n) = ns.iter().find(|&&n| n <= 0.0) {
        bail!("--sweep-n {n}: the plots put n on a log axis, give n > 0");
    }
    let lobes = if o.lobes.is_empty() {
        SWEEP_LOBES.to_vec()
    } else {
        o.lobes
            .iter()
            .map(|l| match l.float() {
                Some(kind) => Ok(kind),
                None => bail!("--sweep varies v, which a hw unit fixes: compare --lobe hw without --sweep (one unit per run)"),
            })
            .collect::<anyhow::Result<_>>()?
    };
    let out = o.output.clone().unwrap_or_else(|| "compare-sweep".into());
    let staging = Staging::new(&out)?;
    let mut renderer = open(&scene, &o.scene.read_options())?;
    let dark = renderer.render(&dark_scene(&scene), &|_| {})?;
    let mut rows = Vec::new();
    for &n in &ns {
        let mut s = scene.clone();
        s.lobe.n = Some(n);
        let reference = reference(&mut renderer, &s, &dark)?;
        for &kind in &lobes {
            let kind_vs: Vec<Option<u32>> = if kind.uses_v() {
                vs.iter().map(|&v| Some(v)).collect()
            } else {
                vec![None]
            };
            for v in kind_vs {
                let c = compare_lobe(
                    &mut renderer,
                    &reference,
                    &o.scene,
                    kind.into(),
                    v.unwrap_or(s.lobe.v),
                )?;
                if !o.quiet {
                    eprintln!(
                        "glint compare: {} n = {} v = {:?}",
                        kind.name(),
                        fmt_num(n),
                        v
                    );
                }
                rows.push(SweepRow {
                    kind,
                    n,
                    v,
                    frame: c.frame,
                    whole: c.whole,
                    highlight: c.highlight,
                });
            }
        }
    }
    let title = sweep_title(&dark.scene);
    staging.write("sweep.csv", sweep_csv(&rows).as_bytes())?;
    let md = sweep_markdown(&title, &rows);
    staging.write("sweep.md", md.as_bytes())?;
    for (stem, hl) in [("sweep-delta-e", false), ("sweep-delta-e-highlight", true)] {
        let series = sweep_series(&rows, &lobes, hl);
        let t = if hl {
            format!("{title}, highlight pixels")
        } else {
            title.clone()
        };
        sweep_plot(staging.path(), stem, &t, &series)?;
    }
    let files = staging.commit()?;
    print!("{md}");
    if !o.quiet {
        eprintln!("glint: wrote {} files into {}", files.len(), out.display());
    }
    Ok(())
}

fn sweep_title(s: &Scene) -> String {
    let input = match &s.input {
        Input::Path(p) => p.file_name().map_or_else(
            || p.display().to_string(),
            |f| f.to_string_lossy().into_owned(),
        ),
        other => input_name(other),
    };
    format!(
        "CIEDE2000 ΔE against exact cosⁿ: {}, {}",
        input,
        s.preset.as_deref().unwrap_or("custom")
    )
}

fn sweep_series(rows: &[SweepRow], lobes: &[LobeKind], highlight: bool) -> Vec<SweepSeries> {
    let mut out: Vec<SweepSeries> = Vec::new();
    for &kind in lobes {
        let mut vs: Vec<Option<u32>> = rows
            .iter()
            .filter(|r| r.kind == kind)
            .map(|r| r.v)
            .collect();
        vs.dedup();
        vs.sort();
        vs.dedup();
        for v in vs {
            let points = rows
                .iter()
                .filter(|r| r.kind == kind && r.v == v)
                .filter_map(|r| {
                    let m = if highlight {
                        r.highlight.as_ref()?
                    } else {
                        &r.whole
                    };
                    let d = m.delta_e?;
                    Some((r.n, d.mean, d.p99))
                })
                .collect();
            out.push(SweepSeries {
                label: lobe_label(kind, 0.0, v.unwrap_or(0)),
                points,
            });
        }
    }
    out
}

fn sweep_cells(r: &SweepRow, m: Option<&ImageMetrics>) -> Vec<String> {
    let de = m.and_then(|m| m.delta_e);
    vec![
        r.kind.name().to_string(),
        fmt_num(r.n),
        r.v.map_or("-".into(), |v| v.to_string()),
        format!("{:.1}", ms(r.frame)),
        m.map_or("0".into(), |m| m.pixels.to_string()),
        num(m.and_then(|m| m.psnr), 2),
        num(m.and_then(|m| m.ssim), 5),
        num(de.map(|d| d.mean), 4),
        num(de.map(|d| d.p99), 3),
        num(de.map(|d| d.max), 3),
        num(de.map(|d| 100.0 * d.above_1), 3),
        num(de.map(|d| 100.0 * d.above_jnd), 3),
        num(m.and_then(|m| m.flip), 5),
    ]
}

const SWEEP_COLUMNS: [&str; 13] = [
    "lobe",
    "n",
    "v",
    "render_ms",
    "pixels",
    "psnr_db",
    "ssim",
    "de_mean",
    "de_p99",
    "de_max",
    "pct_above_1",
    "pct_above_2_3",
    "flip_mean",
];

fn sweep_csv(rows: &[SweepRow]) -> String {
    let mut out = format!("scope,{}\n", SWEEP_COLUMNS.join(","));
    for r in rows {
        out.push_str(&format!(
            "image,{}\n",
            sweep_cells(r, Some(&r.whole)).join(",")
        ));
        out.push_str(&format!(
            "highlight,{}\n",
            sweep_cells(r, r.highlight.as_ref()).join(",")
        ));
    }
    out
}

fn sweep_markdown(title: &str, rows: &[SweepRow]) -> String {
    let mut out = format!("# {title}\n\n");
    for (scope, hl) in [
        ("Whole image", false),
        ("Highlight pixels (exact specular > 10% of its max)", true),
    ] {
        out.push_str(&format!(
            "## {scope}\n\n| {} |\n|{}\n",
            SWEEP_COLUMNS.join(" | "),
            "---|".repeat(13)
        ));
        for r in rows {
            let m = if hl {
                r.highlight.as_ref()
            } else {
                Some(&r.whole)
            };
            out.push_str(&format!("| {} |\n", sweep_cells(r, m).join(" | ")));
        }
        out.push('\n');
    }
    out
}
