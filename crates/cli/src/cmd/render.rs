//! `glint render`: a volume (or the built-in Shepp-Logan phantom) to a shaded PNG.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context};
use glint_io::{read_volume, ReadOptions};
use glint_lobe::{Geometry, LobeKind};
use glint_render::{
    phantom, preset, CameraSpec, Classification, Depth, Field, Kernel, Light, Mode, Projection,
    RenderSettings, Shader, TransferFunction, View,
};

/// Arguments of `glint render`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    glint render -o phantom.png\n  \
    glint render head.nii.gz --preset mr-t2-brain --view left --lobe k -o brain.png\n  \
    glint render ct.nrrd --preset ct-bone --view anterior --azimuth 30 --elevation 15 \
--lobe exact --n 40 --geometry blinn --light 45,30 -o bone.png\n  \
    glint render --mode mip --projection orthographic -o mip.png\n\n\
Presets (3D Slicer's volume rendering presets, MR ones scaled to the volume's maximum):\n  \
    phantom (glint's, the default for the phantom), ct-aaa, ct-aaa2, ct-bone, ct-bones,\n  \
    ct-cardiac, ct-cardiac2, ct-cardiac3, ct-chest-contrast-enhanced, ct-chest-vessels,\n  \
    ct-coronary-arteries, ct-coronary-arteries-2, ct-coronary-arteries-3,\n  \
    ct-cropped-volume-bone, ct-fat, ct-liver-vasculature, ct-lung, ct-mip, ct-muscle,\n  \
    ct-pulmonary-arteries, ct-soft-tissue, mr-angio, mr-default, mr-mip, mr-t2-brain,\n  \
    dti-fa-brain\n\n\
Transfer-function JSON (--tf): {\"opacity\": [[value, alpha], ...], \"color\": [[value, r, g, b], ...],\n  \
    \"ambient\": 0.1, \"diffuse\": 0.9, \"specular\": 0.2, \"power\": 10, \"shade\": true}\n  \
    (alpha per voxel of distance, colours sRGB in 0..1; the material fields are optional)")]
pub struct Args {
    // Boxed: the options are many, and main's subcommand enum should stay small.
    #[command(flatten)]
    opts: Box<Options>,
}

/// The options of `glint render` (boxed inside [`Args`]).
#[derive(clap::Args)]
struct Options {
    /// Volume to render (any format glint's io reads); without it, the built-in 3D
    /// Shepp-Logan head phantom.
    input: Option<PathBuf>,
    /// Output PNG (written atomically).
    #[arg(short, long, default_value = "render.png")]
    output: PathBuf,
    /// Transfer-function and material preset [default: phantom for the phantom, ct-bone
    /// for CT-like volumes (minimum below -500), mr-t2-brain otherwise].
    #[arg(long, conflicts_with = "tf")]
    preset: Option<String>,
    /// Custom transfer function from a JSON file (see below).
    #[arg(long)]
    tf: Option<PathBuf>,
    /// composite (direct volume rendering), iso (first hit at --iso) or mip.
    #[arg(long, default_value = "composite")]
    mode: String,
    /// Iso value for --mode iso [default: the middle of the volume's range].
    #[arg(long, allow_negative_numbers = true)]
    iso: Option<f32>,
    /// Named view in the volume's world frame (RAS+): anterior, posterior, left, right,
    /// superior, inferior.
    #[arg(long, default_value = "anterior")]
    view: String,
    /// Orbit the camera this many degrees about the view's up axis (towards the image's
    /// right).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    azimuth: f64,
    /// Orbit the camera this many degrees upwards.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    elevation: f64,
    /// Magnification (1 frames what the transfer function makes visible).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    zoom: f64,
    /// perspective (30° field of view) or orthographic.
    #[arg(long, default_value = "perspective")]
    projection: String,
    /// Sample distance along rays, in voxels of the smallest spacing.
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    step: f64,
    /// Specular lobe: exact (cos^n), k (energy fit K_v), g (slope fit G_v), schlick,
    /// gauss, minimax.
    #[arg(long, default_value = "k")]
    lobe: String,
    /// Shininess n [default: the preset's specular power].
    #[arg(long, allow_negative_numbers = true)]
    n: Option<f64>,
    /// The power fits raise their base to 2^v.
    #[arg(long, default_value_t = 4)]
    v: u32,
    /// Highlight geometry: phong (R·V) or blinn (N·H).
    #[arg(long, default_value = "phong")]
    geometry: String,
    /// Override the preset's ambient coefficient.
    #[arg(long, allow_negative_numbers = true)]
    ambient: Option<f32>,
    /// Override the preset's diffuse coefficient.
    #[arg(long, allow_negative_numbers = true)]
    diffuse: Option<f32>,
    /// Override the preset's specular coefficient.
    #[arg(long, allow_negative_numbers = true)]
    specular: Option<f32>,
    /// Extra directional light at AZ,EL degrees from the view direction (towards the
    /// image's right and top); repeatable. The headlight stays on.
    #[arg(long = "light", value_name = "AZ,EL", allow_hyphen_values = true)]
    lights: Vec<String>,
    /// Turn the headlight off (then give at least one --light).
    #[arg(long)]
    no_headlight: bool,
    /// Gradient-magnitude gate: samples whose gradient is below this fraction of the
    /// value range per voxel get no directional shading (no random highlights in flat
    /// regions).
    #[arg(long, default_value_t = 0.01, allow_negative_numbers = true)]
    gate: f64,
    /// Image size WxH.
    #[arg(long, default_value = "512x512")]
    size: String,
    /// Bits per PNG channel: 8 or 16.
    #[arg(long, default_value_t = 8)]
    depth: u8,
    /// Grid edge of the built-in phantom.
    #[arg(long, default_value_t = 128)]
    phantom_size: usize,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
    /// Benchmarking: render this many times and print ms per frame to stdout.
    #[arg(long, default_value_t = 1, hide = true)]
    repeat: u32,
    /// Testing: turn empty-space skipping off.
    #[arg(long, hide = true)]
    no_skip: bool,
    /// Benchmarking: composite with the portable scalar loop instead of the SIMD one.
    #[arg(long, hide = true)]
    scalar: bool,
    /// Benchmarking: write the resolved scene (camera, transfer function, material,
    /// step, volume) as JSON, so scripts/bench-vtk can set VTK up identically.
    #[arg(long, hide = true, value_name = "FILE")]
    dump_scene: Option<PathBuf>,
}

fn parse_size(s: &str) -> anyhow::Result<(u32, u32)> {
    let bad = || format!("invalid --size '{s}': expected WxH, e.g. 512x512");
    let (w, h) = s.split_once(['x', 'X']).with_context(bad)?;
    Ok((
        w.trim().parse().with_context(bad)?,
        h.trim().parse().with_context(bad)?,
    ))
}

fn parse_light(s: &str) -> anyhow::Result<Light> {
    let bad = || format!("invalid --light '{s}': expected AZ,EL in degrees, e.g. 45,30");
    let (a, e) = s.split_once(',').with_context(bad)?;
    let light = Light {
        azimuth: a.trim().parse().with_context(bad)?,
        elevation: e.trim().parse().with_context(bad)?,
        intensity: 1.0,
    };
    light.validate()?;
    Ok(light)
}

/// Runs `glint render`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let args = *args.opts;
    // Parse and check every flag before any work.
    let (width, height) = parse_size(&args.size)?;
    let depth = match args.depth {
        8 => Depth::Eight,
        16 => Depth::Sixteen,
        d => bail!("invalid --depth {d}: expected 8 or 16"),
    };
    let view: View = args.view.parse()?;
    let projection: Projection = args.projection.parse()?;
    let kind: LobeKind = args.lobe.parse()?;
    let geometry: Geometry = args.geometry.parse().map_err(anyhow::Error::msg)?;
    let mut mode: Mode = args.mode.parse()?;
    let extra_lights: Vec<Light> = args
        .lights
        .iter()
        .map(|s| parse_light(s))
        .collect::<anyhow::Result<_>>()?;
    if args.no_headlight && extra_lights.is_empty() {
        bail!("--no-headlight leaves no light: add at least one --light AZ,EL");
    }
    if !args.gate.is_finite() || !(0.0..=1.0).contains(&args.gate) {
        bail!("invalid --gate {}: expected a fraction in 0..=1", args.gate);
    }
    if args.repeat == 0 || args.repeat > 10_000 {
        bail!("invalid --repeat {}: expected 1..=10000", args.repeat);
    }
    if let Some(p) = &args.preset {
        preset(p)?; // fail early on an unknown name
    }
    if let Some(dir) = args.output.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            bail!(
                "cannot write {}: directory {} does not exist",
                args.output.display(),
                dir.display()
            );
        }
    }

    let volume = match &args.input {
        Some(path) => read_volume(path, &ReadOptions::default())
            .with_context(|| format!("cannot read volume {}", path.display()))?,
        None => phantom::shepp_logan(args.phantom_size)?,
    };
    let field = Field::new(&volume)?;
    let (lo, hi) = field.range();

    let (tf, material) = if let Some(path) = &args.tf {
        let (tf, overrides) = TransferFunction::from_json_file(path)?;
        (tf, overrides.apply(Default::default()))
    } else {
        let name = match (&args.preset, &args.input) {
            (Some(p), _) => p.as_str(),
            (None, None) => "phantom",
            (None, Some(_)) if lo < -500.0 => "ct-bone",
            (None, Some(_)) => "mr-t2-brain",
        };
        let p = preset(name)?;
        if matches!(mode, Mode::Mip) && args.preset.is_none() {
            // MIP without a preset: a grey ramp over the volume's range.
            let ramp = TransferFunction::from_flat(
                &[lo as f64, 0.0, (hi as f64).max(lo as f64 + 1e-6), 1.0],
                &[lo as f64, 1.0, 1.0, 1.0],
            )?;
            (ramp, p.material())
        } else {
            (p.transfer_function(hi as f64)?, p.material())
        }
    };
    let mut material = material;
    if let Some(a) = args.ambient {
        material.ambient = a;
    }
    if let Some(d) = args.diffuse {
        material.diffuse = d;
    }
    if let Some(s) = args.specular {
        material.specular = s;
    }
    if let Mode::Iso { threshold } = &mut mode {
        *threshold = args.iso.unwrap_or((lo + hi) / 2.0);
    } else if args.iso.is_some() {
        bail!("--iso is only used with --mode iso");
    }

    let settings = RenderSettings {
        width,
        height,
        step: args.step,
        mode,
        camera: CameraSpec {
            view,
            azimuth: args.azimuth,
            elevation: args.elevation,
            zoom: args.zoom,
            projection,
        },
        background: [0.0; 3],
        skip_empty: !args.no_skip,
        kernel: if args.scalar {
            Kernel::Scalar
        } else {
            Kernel::Auto
        },
    };
    settings.validate()?;
    let classify_start = Instant::now();
    let classification = Classification::new(&field, &tf, &settings)?;
    let classify_time = classify_start.elapsed();
    let camera = classification.camera(&settings)?;
    let mut lights = Vec::new();
    if !args.no_headlight {
        lights.push(Light::HEADLIGHT);
    }
    lights.extend(extra_lights);
    let lights = lights
        .iter()
        .map(|l| (l.direction(&camera), l.intensity))
        .collect();
    let n = args.n.unwrap_or(material.power as f64);
    if let Some(path) = &args.dump_scene {
        let eye = camera.eye;
        let focal = camera.eye + camera.forward * 100.0;
        let scene = serde_json::json!({
            "input": args.input,
            "size": [width, height],
            "projection": match projection { Projection::Perspective => "perspective", Projection::Orthographic => "orthographic" },
            "eye": [eye.x, eye.y, eye.z],
            "focal_point": [focal.x, focal.y, focal.z],
            "view_up": [camera.up.x, camera.up.y, camera.up.z],
            // Perspective: full vertical view angle in degrees; orthographic: half height in mm.
            "view_angle_deg": 2.0 * (camera.half_height as f64).atan().to_degrees(),
            "parallel_scale": camera.half_height,
            "step_mm": args.step * field.min_spacing(),
            "min_spacing_mm": field.min_spacing(),
            "opacity": tf.opacity.iter().map(|&(x, a)| [x, a]).collect::<Vec<_>>(),
            "color": tf.color.iter().map(|&(x, c)| [x, c[0], c[1], c[2]]).collect::<Vec<_>>(),
            "ambient": material.ambient,
            "diffuse": material.diffuse,
            "specular": material.specular,
            "power": n,
            "shade": material.shade,
        });
        std::fs::write(path, serde_json::to_string_pretty(&scene)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    let gate = (args.gate * (hi - lo) as f64 / field.min_spacing()) as f32;
    let shader = Shader::new(kind, n, args.v, geometry, material, lights, gate)?;

    let total = u64::from(width) * u64::from(height) * u64::from(args.repeat);
    let bar = if !args.quiet && std::io::stderr().is_terminal() {
        let bar = indicatif::ProgressBar::new(total);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} rendering [{bar:40}] {percent}% {elapsed_precise}",
            )
            .expect("static template")
            .progress_chars("=> "),
        );
        Some(bar)
    } else {
        None
    };
    let progress = |n: u64| {
        if let Some(b) = &bar {
            b.inc(n);
        }
    };
    let mut image = None;
    let start = Instant::now();
    for _ in 0..args.repeat {
        image = Some(classification.render(&shader, &settings, &progress)?);
    }
    let elapsed = start.elapsed();
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    if args.repeat > 1 {
        if let Some(img) = &image {
            eprintln!(
                "glint render: classified once in {:.2} ms; per frame {:?}",
                classify_time.as_secs_f64() * 1e3,
                img.stats
            );
        }
        println!(
            "glint render: {:.2} ms/frame ({} frames, {}x{}, lobe {}, step {})",
            elapsed.as_secs_f64() * 1e3 / args.repeat as f64,
            args.repeat,
            width,
            height,
            kind.name(),
            args.step
        );
    }
    let image = image.expect("repeat >= 1");
    image.write_png(&args.output, depth)?;
    if !args.quiet {
        eprintln!("glint: wrote {}", args.output.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    /// Runs `glint render ARGS -o DIR/out.png` in a fresh directory; returns the
    /// result and whether any file was left in the directory.
    fn run_in_tmp(extra: &[&str]) -> (anyhow::Result<()>, bool, tempfile::TempDir) {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.png");
        let mut argv = vec!["glint", "-q", "-o", out.to_str().unwrap()];
        argv.extend_from_slice(extra);
        let cli = Cli::try_parse_from(argv).unwrap();
        let result = run(cli.args);
        let left = std::fs::read_dir(dir.path()).unwrap().count() > 0;
        (result, left, dir)
    }

    #[test]
    fn phantom_render_writes_a_png() {
        let (result, left, dir) =
            run_in_tmp(&["--size", "24x16", "--phantom-size", "24", "--depth", "16"]);
        result.unwrap();
        assert!(left);
        let bytes = std::fs::read(dir.path().join("out.png")).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        // IHDR: width 24, height 16, bit depth 16.
        assert_eq!(u32::from_be_bytes(bytes[16..20].try_into().unwrap()), 24);
        assert_eq!(u32::from_be_bytes(bytes[20..24].try_into().unwrap()), 16);
        assert_eq!(bytes[24], 16);
        // Only the output: the temporary file was renamed.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn bad_input_fails_without_output() {
        let dir = tempfile::tempdir().unwrap();
        let garbage = dir.path().join("garbage.nii");
        std::fs::write(&garbage, b"not a volume").unwrap();
        let bad_json = dir.path().join("tf.json");
        std::fs::write(&bad_json, b"{\"opacity\": [[0, 0], [1, 2]], \"color\": []}").unwrap();
        let not_json = dir.path().join("not.json");
        std::fs::write(&not_json, b"opacity: 1").unwrap();
        let cases: Vec<(Vec<String>, &str)> = vec![
            (vec!["/nonexistent/volume.nii.gz".into()], "volume"),
            (vec![garbage.to_str().unwrap().into()], "garbage.nii"),
            (
                vec!["--preset".into(), "ct-nonsense".into()],
                "unknown preset",
            ),
            (
                vec!["--tf".into(), bad_json.to_str().unwrap().into()],
                "tf.json",
            ),
            (
                vec!["--tf".into(), not_json.to_str().unwrap().into()],
                "not.json",
            ),
            (
                vec!["--tf".into(), "/nonexistent/tf.json".into()],
                "tf.json",
            ),
            (vec!["--size".into(), "0x10".into()], "image size"),
            (vec!["--size".into(), "100000x100000".into()], "image size"),
            (vec!["--size".into(), "big".into()], "--size"),
            (vec!["--phantom-size".into(), "1".into()], "phantom size"),
            (
                vec!["--phantom-size".into(), "100000".into()],
                "phantom size",
            ),
            (vec!["--step".into(), "0".into()], "step"),
            (vec!["--zoom".into(), "-1".into()], "zoom"),
            (vec!["--lobe".into(), "cosine".into()], "lobe"),
            (vec!["--n".into(), "-5".into()], "shininess"),
            (vec!["--v".into(), "20".into()], "v = 20"),
            (vec!["--geometry".into(), "ward".into()], "geometry"),
            (vec!["--view".into(), "sideways".into()], "view"),
            (vec!["--mode".into(), "xray".into()], "mode"),
            (vec!["--depth".into(), "12".into()], "depth"),
            (vec!["--light".into(), "45".into()], "--light"),
            (vec!["--light".into(), "10,95".into()], "elevation"),
            (vec!["--no-headlight".into()], "no light"),
            (vec!["--specular".into(), "NaN".into()], "specular"),
        ];
        for (extra, needle) in cases {
            let extra: Vec<&str> = extra.iter().map(|s| s.as_str()).collect();
            let (result, left, _dir) = run_in_tmp(&extra);
            let err = format!("{:#}", result.expect_err(&format!("{extra:?} should fail")));
            assert!(err.contains(needle), "{extra:?}: '{err}' lacks '{needle}'");
            assert!(!err.contains('\n'), "{extra:?}: one line expected: {err}");
            assert!(!left, "{extra:?} left a file");
        }
    }

    #[test]
    fn negative_light_angles_are_values_not_flags() {
        let (result, left, _dir) = run_in_tmp(&[
            "--size",
            "16x16",
            "--phantom-size",
            "16",
            "--light",
            "-60,-10",
        ]);
        result.unwrap();
        assert!(left);
    }

    #[test]
    fn size_and_light_parsing() {
        assert_eq!(parse_size("640x480").unwrap(), (640, 480));
        assert_eq!(parse_size("64X48").unwrap(), (64, 48));
        assert!(parse_size("64").is_err());
        let l = parse_light("-30,15").unwrap();
        assert_eq!((l.azimuth, l.elevation), (-30.0, 15.0));
    }
}
