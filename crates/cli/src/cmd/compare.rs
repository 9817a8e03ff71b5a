//! `glint compare`: renders one scene with the exact `cos^n` lobe and with cheaper
//! lobes, and measures the difference in the image as a viewer sees it (8-bit sRGB):
//! PSNR, SSIM, CIEDE2000 ΔE and ꟻLIP, over the whole image and over the highlight
//! (issue 13). `--sweep` repeats it over n and v and plots ΔE against n. The
//! experiment is glint-compare's; this parses the flags and writes the outputs.

use std::path::PathBuf;

use anyhow::bail;
use glint_analysis::{fmt_num, Staging};
use glint_compare::{SweepSpec, DELTA_E_SCALE_MAX};
use glint_lobe::LobeKind;
use glint_render::{Denoise, LightingModel, Scene, SceneLobe};

use super::choice::choice;
use super::render::{check_output_dir, open_renderer as open};
use super::scene_flags::SceneFlags;

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
    /// With --lighting path: also measure each image against the exact lobe traced
    /// with this many samples per pixel and another seed [default: 16 x --spp; 0: no
    /// reference].
    #[arg(long, conflicts_with = "sweep")]
    reference_spp: Option<u32>,
    /// With --lighting path: instead of comparing lobes, trace the scene progressively
    /// (1, 2, 3, 4, 6, 8, 11, ... samples per pixel, up to --spp) and print each step's
    /// cumulative render time and its distance to the --reference-spp render.
    #[arg(long, conflicts_with_all = ["sweep", "json"])]
    convergence: bool,
    /// With --convergence: stop at the first step whose mean FLIP is below this.
    #[arg(long, requires = "convergence")]
    flip_below: Option<f64>,
    /// With --convergence: trace each step from no samples (a cold start of the
    /// frame, denoising included with --denoise) and print its own time, not the
    /// cumulative one.
    #[arg(long, requires = "convergence")]
    cold: bool,
    /// With --convergence: run the steps once per denoiser (comma-separated: none,
    /// atrous, oidn, auto) against the one reference [default: --denoise's, or none].
    #[arg(long, value_delimiter = ',', requires = "convergence",
          value_parser = choice::<Denoise>(Denoise::ALL.map(|d| d.name())))]
    denoisers: Vec<Denoise>,
    /// No progress messages on stderr.
    #[arg(short, long)]
    quiet: bool,
}

/// The scene of the flags (its own lobe); under `path` lighting with the comparison's
/// defaults ([`glint_compare::path_defaults`]: its size unless --size or --scene gives
/// one, its samples per pixel unless --spp does).
fn flag_scene(o: &Options) -> anyhow::Result<Scene> {
    if o.sweep && (o.scene.n.is_some() || o.scene.v.is_some()) {
        bail!("--sweep chooses n and v itself: drop --n and --v (or use --sweep-n, --sweep-v)");
    }
    let mut scene = o.scene.scene()?;
    glint_compare::path_defaults(
        &mut scene,
        o.scene.size.is_some() || o.scene.scene.is_some(),
    );
    if scene.lighting.model == LightingModel::Path {
        let spp = scene.lighting.spp.unwrap_or(glint_compare::PATH_SPP);
        if let Some(r) = o.reference_spp.filter(|&r| r > 0 && r <= spp) {
            bail!("--reference-spp {r}: the reference's samples per pixel must exceed --spp {spp}");
        }
    } else if o.reference_spp.is_some_and(|s| s > 0) || o.convergence {
        bail!("--reference-spp and --convergence need --lighting path");
    }
    Ok(scene)
}

/// Runs `glint compare`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let o = *args.opts;
    if !(o.scale_max.is_finite() && o.scale_max > 0.0) {
        bail!("--scale-max {}: expected a positive number", o.scale_max);
    }
    let own = flag_scene(&o)?;
    if o.convergence {
        return run_convergence(&o, own);
    }
    let scene = own.with_exact_lobe();
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
    let renderer = open(&scene, &o.scene.read_options())?;
    let report = glint_compare::run_against(
        renderer,
        &scene,
        &lobes,
        o.scene.v,
        glint_compare::reference_spp(&scene, o.reference_spp)?,
    )?;
    let png = report.figure_png(o.scale_max)?;
    glint_io::write_atomic(&output, |w| w.write_all(&png))?;
    if o.json {
        println!("{}", serde_json::to_string_pretty(&report.to_json()?)?);
    } else {
        print!("{}", report.text());
    }
    if !o.quiet {
        eprintln!("glint: wrote {}", output.display());
    }
    Ok(())
}

fn run_sweep(o: &Options, scene: Scene) -> anyhow::Result<()> {
    let defaults = SweepSpec::default();
    let lobes = if o.lobes.is_empty() {
        defaults.lobes
    } else {
        o.lobes
            .iter()
            .map(|l| match l.float() {
                Some(kind) => Ok(kind),
                None => bail!("--sweep varies v, which a hw unit fixes: compare --lobe hw without --sweep (one unit per run)"),
            })
            .collect::<anyhow::Result<_>>()?
    };
    let spec = SweepSpec {
        ns: if o.sweep_n.is_empty() {
            defaults.ns
        } else {
            o.sweep_n.clone()
        },
        vs: if o.sweep_v.is_empty() {
            defaults.vs
        } else {
            o.sweep_v.clone()
        },
        lobes,
    };
    glint_analysis::check_lists(&spec.ns, &spec.vs)?;
    let out = o.output.clone().unwrap_or_else(|| "compare-sweep".into());
    let staging = Staging::new(&out)?;
    let renderer = open(&scene, &o.scene.read_options())?;
    let quiet = o.quiet;
    let sweep = glint_compare::sweep(renderer, &scene, &spec, &|r| {
        if !quiet {
            eprintln!(
                "glint compare: {} n = {} v = {:?}",
                r.kind.name(),
                fmt_num(r.n),
                r.v
            );
        }
    })?;
    staging.write("sweep.csv", sweep.csv().as_bytes())?;
    let md = sweep.markdown();
    staging.write("sweep.md", md.as_bytes())?;
    sweep.write_plots(staging.path())?;
    let files = staging.commit()?;
    print!("{md}");
    if !o.quiet {
        eprintln!("glint: wrote {} files into {}", files.len(), out.display());
    }
    Ok(())
}

/// `--convergence`: the scene traced progressively up to its --spp, each step's time
/// and distance to the converged reference.
fn run_convergence(o: &Options, scene: Scene) -> anyhow::Result<()> {
    let max = scene.lighting.spp.unwrap_or(glint_compare::PATH_SPP);
    let Some(reference) = glint_compare::reference_spp(&scene, o.reference_spp)? else {
        bail!("--convergence needs a reference: --reference-spp above 0");
    };
    if let Some(t) = o.flip_below {
        if !(t.is_finite() && t > 0.0) {
            bail!("--flip-below {t}: expected a positive number");
        }
    }
    let renderer = open(&scene, &o.scene.read_options())?;
    if !o.quiet {
        eprintln!("glint compare: tracing the reference, {reference} spp");
    }
    let denoisers: Vec<_> = o.denoisers.iter().map(|&d| Some(d)).collect();
    let steps = glint_compare::Steps {
        schedule: &glint_compare::convergence_schedule(max),
        stop_below: o.flip_below,
        cold: o.cold,
        denoisers: &denoisers,
    };
    println!("denoise spp  seconds  mean dE  FLIP     SSIM");
    let conv = glint_compare::convergence_with(renderer, &scene, reference, &steps, &|s| {
        println!(
            "{:<7} {:<4} {:<8.3} {:<8.4} {:.5}  {:.5}",
            s.denoise.unwrap_or_default().name(),
            s.spp,
            s.elapsed.as_secs_f64(),
            s.image.delta_e.map_or(f64::NAN, |d| d.mean),
            s.image.flip.unwrap_or(f64::NAN),
            s.image.ssim.unwrap_or(f64::NAN)
        );
    })?;
    println!(
        "reference: {} spp, seed {}, {:.1} s, {}x{}",
        conv.reference_spp,
        conv.reference_seed,
        conv.reference_time.as_secs_f64(),
        scene.size[0],
        scene.size[1]
    );
    if let Some(t) = o.flip_below {
        let mut names: Vec<Option<Denoise>> = Vec::new();
        for s in &conv.steps {
            if !names.contains(&s.denoise) {
                names.push(s.denoise);
            }
        }
        for d in names {
            let name = d.unwrap_or_default().name();
            let first = conv
                .steps
                .iter()
                .find(|s| s.denoise == d && s.image.flip.is_some_and(|f| f < t));
            match first {
                Some(s) => println!(
                    "{name}: mean FLIP below {t} at {} spp after {:.3} s",
                    s.spp,
                    s.elapsed.as_secs_f64()
                ),
                None => println!("{name}: mean FLIP not below {t} by {max} spp"),
            }
        }
    }
    Ok(())
}
