//! `glint render`: a scene (a volume or the built-in phantom, with flags or a scene
//! file) to a shaded PNG, or with `--turntable N` to an animated GIF, an MP4 or PNG
//! frames of N views round it. Parses flags into a [`Scene`], renders it with the
//! library, writes the image.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{bail, Context};
use glint_io::ReadOptions;
use glint_render::{
    Depth, FloatFormat, Input, Kernel, Rendered, Renderer, Scene, SceneLobe, Turntable,
    DEFAULT_TURNTABLE_FPS,
};

use super::choice::choice;
use super::scene_flags::SceneFlags;
use super::spinner::Spinner;

/// Arguments of `glint render`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    glint render -o phantom.png\n  \
    glint render head.nii.gz --preset mr-t2-brain --view left --lobe k -o brain.png\n  \
    glint render ct.nrrd --preset ct-bone --view anterior --azimuth 30 --elevation 15 \
--lobe exact --n 40 --geometry blinn --light 45,30 -o bone.png\n  \
    glint render --mode mip --projection orthographic -o mip.png\n  \
    glint render lh.pial.gii rh.pial.gii --overlay lh.sulc.gii --overlay rh.sulc.gii \
--colormap sulc --view left --ssaa 4 -o brain.png\n  \
    glint render mni152.nii.gz --mode surface --iso 60 --view left -o surface.png\n  \
    glint render brain.nii.gz --dump-scene brain.json -o a.png   # then:\n  \
    glint render --scene brain.json --lobe exact -o b.png        # flags override the file\n  \
    glint render --lighting path --spp 256 -o radiance.exr   # linear float (or .pfm)\n  \
    glint render head.nii.gz --lighting path --aperture 4 --focus auto --tone agx -o dof.png\n  \
    glint render --phantom shepp-logan --size 256x256 --turntable 36 -o spin.gif\n  \
    glint render head.nii.gz --preset ct-bone --turntable 120 --fps 30 -o spin.mp4   # needs ffmpeg\n  \
    glint render head.nii.gz --turntable 8 -o frames/   # frames/frame-0000.png ...\n  \
    glint render head.nii.gz --turntable 72 -o spin.webp   # animated WebP (lossless)\n  \
    glint render head.nii.gz --camera-path keys.json --frames 60 -o fly.gif\n    \
      keys.json: [{\"azimuth\": 0, \"elevation\": 0, \"zoom\": 1}, {\"azimuth\": 90, \"elevation\": 30, \"zoom\": 2}]\n\n\
Presets (3D Slicer's volume rendering presets, MR ones scaled to the volume's maximum):\n  \
    phantom (glint's, the default for the phantom), ct-aaa, ct-aaa2, ct-bone, ct-bones,\n  \
    ct-cardiac, ct-cardiac2, ct-cardiac3, ct-chest-contrast-enhanced, ct-chest-vessels,\n  \
    ct-coronary-arteries, ct-coronary-arteries-2, ct-coronary-arteries-3,\n  \
    ct-cropped-volume-bone, ct-fat, ct-liver-vasculature, ct-lung, ct-mip, ct-muscle,\n  \
    ct-pulmonary-arteries, ct-soft-tissue, mr-angio, mr-default, mr-mip, mr-t2-brain,\n  \
    dti-fa-brain\n\n\
Transfer-function JSON (--tf): {\"opacity\": [[value, alpha], ...], \"color\": [[value, r, g, b], ...],\n  \
    \"ambient\": 0.1, \"diffuse\": 0.9, \"specular\": 0.2, \"power\": 10, \"shade\": true}\n  \
    (alpha per voxel of distance, colours sRGB in 0..1; the material fields are optional)\n  \
    --tf also reads 3D Slicer volume property files (.vp) and ParaView colour maps (.json);\n  \
    `glint tf export --preset ct-bone -o bone.vp|bone.json` writes them\n  \
    --window 400 --window-level 40: the function's opacity ramp stretched to that window\n\n\
Scene JSON (--scene, --dump-scene): every field below as a key, e.g.\n  \
    {\"version\": 1, \"input\": {\"path\": \"brain.nii.gz\"}, \"preset\": \"mr-t2-brain\",\n  \
    \"lobe\": {\"kind\": \"k\", \"n\": 40, \"v\": 4, \"geometry\": \"phong\"},\n  \
    \"camera\": {\"view\": \"left\", \"azimuth\": 0, \"elevation\": 0, \"zoom\": 1, \"projection\": \"perspective\"},\n  \
    \"lights\": [{\"azimuth\": 0, \"elevation\": 0, \"intensity\": 1}], \"size\": [512, 512], \"step\": 0.5}\n  \
    A scene of meshes: {\"input\": \"none\", \"mode\": \"surface\", \"ssaa\": 2, \"meshes\": [{\"path\": \"lh.pial.gii\",\n  \
    \"overlay\": {\"path\": \"lh.sulc.gii\", \"array\": 0, \"colormap\": \"viridis\", \"range\": [-1, 1]},\n  \
    \"color\": [0.85, 0.77, 0.64]}], ...} (colours linear RGB; a volume with meshes renders in surface mode)\n  \
    (relative input, mesh and overlay paths are relative to the scene file)")]
pub struct Args {
    // Boxed: the options are many, and main's subcommand enum should stay small.
    #[command(flatten)]
    opts: Box<Options>,
}

/// The options of `glint render` (boxed inside [`Args`]). Every scene option is
/// optional: unset, it keeps the scene file's value or the scene default.
#[derive(clap::Args)]
struct Options {
    #[command(flatten)]
    scene: SceneFlags,
    /// Output PNG (written atomically), or linear float radiance (before --exposure
    /// and --tone, without colour bar or legend) as OpenEXR (.exr: RGBA f32) or a
    /// Portable Float Map (.pfm: RGB f32); with --turntable or --camera-path, an animated
    /// GIF (.gif), an animated WebP (.webp), an MP4 (.mp4, through ffmpeg) or a
    /// directory of PNG frames (ending in '/', or an existing directory).
    #[arg(short, long, default_value = "render.png")]
    output: PathBuf,
    /// Render N views round the scene, the camera's azimuth stepping 360/N degrees
    /// (about the view's up axis) from the scene's camera; frame 0 is the still
    /// (2..=3600).
    #[arg(long, value_name = "N", conflicts_with = "repeat")]
    turntable: Option<u32>,
    /// Render --frames N views along camera keys read from a JSON file: a list of
    /// cameras as the scene's "camera" writes them (azimuth, elevation and zoom
    /// required; view and projection optional, alike in every key), evenly spaced in
    /// time; azimuth and elevation interpolated linearly in degrees (the eye moves
    /// over the sphere, keeping the keys' winding), zoom geometrically.
    #[arg(long, value_name = "KEYS.json", conflicts_with_all = ["turntable", "repeat"])]
    camera_path: Option<PathBuf>,
    /// The number of frames along --camera-path (2..=3600).
    #[arg(long, value_name = "N")]
    frames: Option<u32>,
    /// Frames per second of a --turntable or --camera-path GIF, WebP or MP4 (1..=120)
    /// [default: 24].
    #[arg(long)]
    fps: Option<u32>,
    /// Write the resolved scene (every default chosen, plus the camera and transfer
    /// function in world units) as JSON; `--scene` renders it again bit for bit.
    #[arg(long, value_name = "FILE")]
    dump_scene: Option<PathBuf>,
    /// Specular lobe: exact (cos^n), k (energy fit K_v), g (slope fit G_v), schlick,
    /// gauss, minimax, or hw (the hardware unit's output, bit for bit; --hw-config)
    /// [default: k].
    #[arg(long, value_parser = choice::<SceneLobe>(SceneLobe::ALL.map(|k| k.name())))]
    lobe: Option<SceneLobe>,
    /// Bits per PNG channel (of the still, or of --turntable's PNG frames; GIF and MP4
    /// are 8-bit).
    #[arg(long, default_value = "8", value_parser = ["8", "16"])]
    depth: String,
    /// No progress bar, and of the reader's notes (what a DICOM directory's read
    /// skipped, where the affine came from) only its warnings.
    #[arg(short, long)]
    quiet: bool,
    /// Print the time of each stage (read, field, classify, frame, encode, write) to
    /// stderr.
    #[arg(long)]
    timings: bool,
    /// Benchmarking: render this many times and print ms per frame to stdout (path
    /// lighting traces every frame's samples anew).
    #[arg(long, default_value_t = 1, hide = true, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    repeat: u32,
    /// Benchmarking: composite with the portable scalar loop instead of the SIMD one.
    #[arg(long, hide = true)]
    scalar: bool,
}

/// Runs `glint render`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let args = *args.opts;
    check_output_dir(&args.output)?;
    if let Some(frames) = args.turntable {
        return run_turntable(&args, Turntable::new(frames));
    }
    match (&args.camera_path, args.frames) {
        (Some(keys), Some(frames)) => {
            let keys = glint_render::CameraPath::load(keys)?;
            return run_turntable(&args, Turntable::along(keys, frames));
        }
        (Some(_), None) => bail!("--camera-path needs --frames N, the number of frames"),
        (None, Some(_)) => {
            bail!(
                "--frames is the frame count of a --camera-path; give --camera-path KEYS.json too"
            )
        }
        (None, None) => {}
    }
    if args.fps.is_some() {
        bail!("--fps is the frame rate of a --turntable or --camera-path; give one of them too");
    }
    let scene = build_scene(&args)?;
    let mut renderer = open_for(&args, &scene)?;
    let building = Spinner::start("classifying the volume".into(), args.quiet);
    let resolved = renderer.resolve(&scene)?;
    drop(building);
    let bar = progress_bar(&args, &resolved.scene, u64::from(args.repeat));
    let progress = |n: u64| {
        if let Some(b) = &bar {
            b.inc(n);
        }
    };
    // Linear float output takes the radiance, before the exposure and tone curve.
    let float = FloatFormat::of_path(&args.output);
    let render = |renderer: &mut Renderer| match float {
        Some(_) => renderer.render_resolved_linear(resolved.clone(), &progress),
        None => renderer.render_resolved(resolved.clone(), &progress),
    };
    let mut rendered = render(&mut renderer)?;
    let mut frames = Vec::with_capacity(args.repeat as usize);
    for _ in 1..args.repeat {
        // A path-traced frame repeated is traced again, not taken from the last one.
        renderer.forget_paths();
        let start = Instant::now();
        rendered = render(&mut renderer)?;
        frames.push(start.elapsed());
    }
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    for note in renderer.device_notes() {
        eprintln!("glint: note: {note}");
    }
    if args.repeat > 1 {
        print_repeat(&rendered, &mut frames);
    }
    let start = Instant::now();
    let bytes = match float {
        // The radiance alone: no colour bar or legend drawn into it.
        Some(format) => rendered.image.encode_float(format)?,
        None => {
            rendered.draw_overlays();
            rendered
                .image
                .encode_png(depth(&args))
                .context("encoding the PNG")?
        }
    };
    let encode = start.elapsed();
    let start = Instant::now();
    glint_io::write_atomic(&args.output, |w| w.write_all(&bytes))?;
    let write = start.elapsed();
    if let Some(path) = &args.dump_scene {
        rendered.scene.save(path)?;
    }
    if args.timings {
        print_timings(&rendered, encode, write);
    }
    if !args.quiet {
        eprintln!("glint: wrote {}", args.output.display());
    }
    Ok(())
}

/// `--turntable N` or `--camera-path KEYS --frames N`: the frames round the scene or
/// along the keys, rendered with one renderer (read and classified once), written as
/// the output's format asks. The format, the frame count and rate and (MP4) ffmpeg are
/// checked before the volume is read.
fn run_turntable(args: &Options, turntable: Turntable) -> anyhow::Result<()> {
    let turntable = Turntable {
        fps: args.fps.unwrap_or(DEFAULT_TURNTABLE_FPS),
        depth: depth(args),
        ..turntable
    };
    let frames = turntable.frames;
    let writer = turntable.writer(&args.output)?;
    let scene = build_scene(args)?;
    let mut renderer = open_for(args, &scene)?;
    let bar = progress_bar(args, &scene, u64::from(frames));
    let progress = |n: u64| {
        if let Some(b) = &bar {
            b.inc(n);
        }
    };
    let written = turntable.render(&mut renderer, &scene, writer, &progress)?;
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    if let Some(path) = &args.dump_scene {
        written.first.save(path)?;
    }
    if args.timings {
        let per_frame = written.render / written.frames;
        eprintln!(
            "glint render: {} frames rendered in {:.2?} ({per_frame:.2?} per frame, the first \
classifying), encoded and written in {:.2?}",
            written.frames, written.render, written.encode
        );
    }
    if !args.quiet {
        eprintln!(
            "glint: wrote {} ({} frames of {}x{})",
            args.output.display(),
            written.frames,
            written.width,
            written.height
        );
    }
    Ok(())
}

/// The renderer of `scene` (the spinner turning while it reads), with the kernel the
/// flags ask for.
fn open_for(args: &Options, scene: &Scene) -> anyhow::Result<Renderer> {
    let reading = Spinner::start(reading_what(scene), args.quiet);
    let mut renderer = open_renderer_noting(scene, &args.scene.read_options(), args.quiet)?;
    drop(reading);
    if args.scalar {
        renderer.kernel = Kernel::Scalar;
    }
    Ok(renderer)
}

/// The PNG depth of `--depth`.
fn depth(args: &Options) -> Depth {
    if args.depth == "16" {
        Depth::Sixteen
    } else {
        Depth::Eight
    }
}

/// A renderer of the scene's input, its field built with the scene's prefilter, with
/// an error that names the input; prints what the reader assumed (e.g. DICOM frames
/// without positions) to stderr. Meshes are read when the scene is resolved (their
/// errors name the file, not the volume).
pub(crate) fn open_renderer(scene: &Scene, options: &ReadOptions) -> anyhow::Result<Renderer> {
    open_renderer_noting(scene, options, true)
}

/// [`open_renderer`] printing every note of the reader ([`print_notes`]), or with
/// `quiet` only its warnings.
pub(crate) fn open_renderer_noting(
    scene: &Scene,
    options: &ReadOptions,
    quiet: bool,
) -> anyhow::Result<Renderer> {
    let volume = Scene {
        input: scene.input.clone(),
        prefilter: scene.prefilter,
        ..Scene::default()
    };
    let renderer = Renderer::open(&volume, options).with_context(|| match &scene.input {
        Input::Path(p) => format!("cannot read volume {}", p.display()),
        Input::Phantom { name, .. } => format!("cannot build the {name} phantom"),
        Input::None => "cannot open the scene".into(),
    })?;
    if let Input::Path(path) = &scene.input {
        print_notes(path, renderer.notes(), quiet);
    }
    Ok(renderer)
}

/// Prints a reader's notes about `path` to stderr, one `glint: PATH: NOTE` line each,
/// as `glint info` lists them (objects of a DICOM directory skipped, slices and files
/// read, where the affine came from, ...). With `quiet` (`-q`), only the warnings:
/// geometry the reader assumed and data missing (chunks of a pyramid), which a script
/// reading the output must still hear about.
pub(crate) fn print_notes(path: &Path, notes: &[String], quiet: bool) {
    let warning = |n: &&String| n.contains("assumed") || n.contains("missing");
    for note in notes.iter().filter(|n| !quiet || warning(n)) {
        eprintln!("glint: {}: {note}", path.display());
    }
}

/// What the spinner says while the scene's input is read.
pub(crate) fn reading_what(scene: &Scene) -> String {
    match &scene.input {
        Input::Path(p) => format!("reading {}", p.display()),
        _ => "building the scene".into(),
    }
}

/// Refuses before any work when the output's directory does not exist.
pub(crate) fn check_output_dir(output: &Path) -> anyhow::Result<()> {
    if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            bail!(
                "cannot write {}: directory {} does not exist",
                output.display(),
                dir.display()
            );
        }
    }
    Ok(())
}

/// The scene of the flags, with the lobe.
fn build_scene(args: &Options) -> anyhow::Result<Scene> {
    let mut scene = args.scene.scene()?;
    if let Some(kind) = args.lobe {
        args.scene.set_lobe(&mut scene, kind);
    }
    Ok(scene)
}

/// The bar of `frames` renders of the scene's size (a spinner for a `path` frame with a
/// time budget); none when quiet or stderr is not a terminal.
fn progress_bar(args: &Options, scene: &Scene, frames: u64) -> Option<indicatif::ProgressBar> {
    if args.quiet || !std::io::stderr().is_terminal() {
        return None;
    }
    if scene.lighting.time_budget.is_some() {
        // An adaptive `path` frame adds passes until its budget is spent, each reporting
        // the rows it went over: no total to fill, so the time spent instead of a percentage.
        let bar = indicatif::ProgressBar::new_spinner();
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} rendering (time budget) {elapsed_precise}",
            )
            .expect("static template"),
        );
        bar.enable_steady_tick(std::time::Duration::from_millis(100));
        return Some(bar);
    }
    let [w, h] = scene.size;
    let bar = indicatif::ProgressBar::new(u64::from(w) * u64::from(h) * frames);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} rendering [{bar:40}] {percent}% {elapsed_precise}",
        )
        .expect("static template")
        .progress_chars("=> "),
    );
    Some(bar)
}

/// `--repeat`: the frames after the first (which classifies), in ms per frame: their
/// mean, and their median (the steady frame, which the first few frames' allocations
/// do not reach).
fn print_repeat(rendered: &Rendered, frames: &mut [Duration]) {
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let mean = frames.iter().map(|&d| ms(d)).sum::<f64>() / frames.len() as f64;
    frames.sort_unstable();
    let n = frames.len();
    let median = (ms(frames[(n - 1) / 2]) + ms(frames[n / 2])) / 2.0;
    eprintln!(
        "glint render: first frame (classified once): {:?}; per frame {:?}",
        rendered.timings.stages(),
        rendered.image.stats
    );
    let s = &rendered.scene;
    let detail = if s.is_surface() {
        format!("ssaa {}", s.ssaa.unwrap_or_default())
    } else {
        format!("step {}", s.step)
    };
    println!(
        "glint render: {mean:.2} ms/frame ({n} frames, {}x{}, lobe {}, {detail}; median {median:.2} ms)",
        s.size[0],
        s.size[1],
        s.lobe.kind.name(),
    );
}

/// `--timings`: every stage of the one-shot render, then the total.
fn print_timings(rendered: &Rendered, encode: Duration, write: Duration) {
    let mut t = rendered.timings.clone();
    t.record("encode", encode);
    t.record("write", write);
    eprintln!("{t}");
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
        // A flag clap refuses counts as the command's error (main prints its first line).
        let result = match Cli::try_parse_from(argv) {
            Ok(cli) => run(cli.args),
            Err(e) => Err(anyhow::anyhow!(e
                .to_string()
                .lines()
                .next()
                .unwrap_or_default()
                .to_string())),
        };
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
            (vec!["--n".into(), "-5".into()], "invalid n = -5"),
            (vec!["--v".into(), "20".into()], "v = 20"),
            (vec!["--geometry".into(), "ward".into()], "geometry"),
            (vec!["--view".into(), "sideways".into()], "view"),
            (vec!["--mode".into(), "xray".into()], "mode"),
            (vec!["--depth".into(), "12".into()], "depth"),
            (vec!["--light".into(), "45".into()], "--light"),
            (vec!["--light".into(), "10,95".into()], "elevation"),
            (vec!["--no-headlight".into()], "no light"),
            (vec!["--specular".into(), "NaN".into()], "specular"),
            (vec!["--sampling".into(), "linear".into()], "--sampling"),
            (vec!["--tone".into(), "filmic".into()], "--tone"),
            (vec!["--exposure".into(), "NaN".into()], "exposure"),
            (vec!["--aperture".into(), "-1".into()], "aperture = -1"),
            (vec!["--focus".into(), "near".into()], "--focus"),
            (
                ["--lighting", "path", "--aperture", "2", "--focus", "0"]
                    .map(String::from)
                    .to_vec(),
                "focus = 0",
            ),
            // Autofocus with nothing under the image centre (a plane cuts it all away).
            (
                [
                    "--lighting",
                    "path",
                    "--aperture",
                    "2",
                    "--clip",
                    "1000,0,0,1,0,0",
                ]
                .map(String::from)
                .to_vec(),
                "autofocus",
            ),
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
    fn float_output_is_the_radiance_before_the_tone_curve() {
        let dir = tempfile::tempdir().unwrap();
        let small = ["--size", "12x10", "--phantom-size", "16"];
        let pfm = |name: &str, extra: &[&str]| {
            let mut argv = small.to_vec();
            argv.extend_from_slice(extra);
            let bytes = render_to(dir.path(), name, &argv);
            let header = b"PF\n12 10\n-1.0\n";
            assert_eq!(&bytes[..header.len()], header);
            bytes[header.len()..].to_vec()
        };
        let plain = pfm("a.pfm", &[]);
        assert_eq!(plain.len(), 12 * 10 * 3 * 4);
        // The exposure and tone curve change the PNG, not the radiance.
        assert_eq!(pfm("b.pfm", &["--exposure", "2", "--tone", "agx"]), plain);
        let png = |name: &str, extra: &[&str]| {
            let mut argv = small.to_vec();
            argv.extend_from_slice(extra);
            render_to(dir.path(), name, &argv)
        };
        assert_ne!(png("a.png", &[]), png("b.png", &["--tone", "aces"]));
        // Exposure 0 and the linear curve given explicitly: today's PNG, bit for bit.
        assert_eq!(
            png("c.png", &[]),
            png("d.png", &["--exposure", "0", "--tone", "linear"])
        );
        // OpenEXR: its magic number, from every lighting model.
        for model in ["local", "shadows", "path"] {
            let mut argv = small.to_vec();
            argv.extend(["--lighting", model]);
            if model == "path" {
                argv.extend(["--spp", "2"]);
            }
            let exr = render_to(dir.path(), "x.exr", &argv);
            assert_eq!(&exr[..4], &[0x76, 0x2f, 0x31, 0x01], "{model}");
        }
    }

    #[test]
    fn denoise_oidn_renders_or_is_one_line_and_no_file_without_its_library() {
        let path = [
            "--size",
            "16x16",
            "--phantom-size",
            "16",
            "--lighting",
            "path",
            "--spp",
            "1",
        ];
        let with = |d: &'static str| {
            let mut a = path.to_vec();
            a.extend(["--denoise", d]);
            run_in_tmp(&a)
        };
        let (result, left, _dir) = with("atrous");
        result.unwrap();
        assert!(left);
        let (result, left, _dir) = with("oidn");
        if glint_render::denoise::has_oidn() {
            result.unwrap();
            assert!(left, "oidn rendered no file");
        } else {
            let err = format!("{:#}", result.expect_err("oidn without its library"));
            for part in [
                "libOpenImageDenoise",
                "scripts/fetch-oidn",
                "--denoise atrous",
            ] {
                assert!(err.contains(part), "'{err}' lacks '{part}'");
            }
            assert!(!err.contains('\n'), "one line expected: {err}");
            assert!(!left, "a file was left");
        }
        let (result, left, _dir) = with("fast");
        assert!(result.is_err() && !left);
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

    /// Runs `glint render ARGS` in `dir`, writing `name`; returns the PNG's bytes.
    fn render_to(dir: &Path, name: &str, extra: &[&str]) -> Vec<u8> {
        let out = dir.join(name);
        let mut argv = vec!["glint", "-q", "-o", out.to_str().unwrap()];
        argv.extend_from_slice(extra);
        run(Cli::try_parse_from(argv).unwrap().args).unwrap();
        std::fs::read(out).unwrap()
    }

    #[test]
    fn a_dumped_scene_renders_the_same_image_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        let json = dir.path().join("scene.json");
        let small = ["--size", "40x32", "--phantom-size", "40"];
        for extra in [
            &[][..],
            &["--mode", "mip", "--projection", "orthographic"][..],
            &[
                "--mode",
                "iso",
                "--view",
                "left",
                "--lobe",
                "schlick",
                "--light",
                "-40,20,0.5",
            ][..],
            &["--sampling", "pre-integrated", "--phantom", "shepp-logan"][..],
        ] {
            let mut argv = small.to_vec();
            argv.extend_from_slice(extra);
            argv.extend(["--dump-scene", json.to_str().unwrap()]);
            let first = render_to(dir.path(), "a.png", &argv);
            let again = render_to(dir.path(), "b.png", &["--scene", json.to_str().unwrap()]);
            assert_eq!(first, again, "{extra:?}");
            // The dump names what was chosen.
            let text = std::fs::read_to_string(&json).unwrap();
            let scene = Scene::from_json(&text).unwrap();
            assert!(
                scene.lobe.n.is_some() && scene.material.specular.is_some(),
                "{text}"
            );
            assert!(scene.derived.is_some(), "{text}");
            let sampling = if extra.contains(&"pre-integrated") {
                glint_render::Sampling::PreIntegrated
            } else {
                glint_render::Sampling::Point
            };
            assert_eq!(scene.sampling, sampling, "{text}");
        }
        // Flags override the file: another lobe changes the image.
        let other = render_to(
            dir.path(),
            "c.png",
            &[
                "--scene",
                json.to_str().unwrap(),
                "--lobe",
                "exact",
                "--n",
                "5",
            ],
        );
        let base = render_to(dir.path(), "d.png", &["--scene", json.to_str().unwrap()]);
        assert_ne!(other, base);
    }

    #[test]
    fn a_hw_lobe_scene_dumps_its_unit_and_renders_again_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        let unit = dir.path().join("unit.json");
        std::fs::write(&unit, r#"{"out_bits": 10}"#).unwrap();
        let json = dir.path().join("scene.json");
        // 16-bit PNGs: the unit's difference from float K_4 is below 8-bit sRGB's step
        // on this small scene.
        let small = [
            "--size",
            "40x32",
            "--phantom-size",
            "40",
            "--n",
            "40",
            "--depth",
            "16",
        ];
        let hw = [
            small.as_slice(),
            &["--lobe", "hw", "--hw-config", unit.to_str().unwrap()],
        ]
        .concat();
        let dump = [hw.as_slice(), &["--dump-scene", json.to_str().unwrap()]].concat();
        let first = render_to(dir.path(), "a.png", &dump);
        let again = render_to(
            dir.path(),
            "b.png",
            &["--scene", json.to_str().unwrap(), "--depth", "16"],
        );
        assert_eq!(first, again);
        // The dump holds the whole unit: the file's width, the default's other fields.
        let scene = Scene::from_json(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert_eq!(scene.lobe.kind, SceneLobe::Hw);
        let want = glint_hw::Config {
            out_bits: 10,
            ..glint_hw::Config::default()
        };
        assert_eq!((scene.lobe.hw, scene.lobe.v), (Some(want), 4));
        // Float K_4 of the same n is another image.
        let k = render_to(
            dir.path(),
            "c.png",
            &[small.as_slice(), &["--lobe", "k"]].concat(),
        );
        assert!(first != k, "the unit's image equals float K_4's");
        // A v = 3 unit gives the lobe v = 3; --v 4 with it is a contradiction.
        std::fs::write(&unit, r#"{"v": 3, "square_frac": [14, 14, 12]}"#).unwrap();
        render_to(dir.path(), "d.png", &hw);
        let (result, left, _out) = run_in_tmp(&[hw.as_slice(), &["--v", "4"]].concat());
        let err = format!("{:#}", result.unwrap_err());
        assert!(err.contains("contradicts") && !err.contains('\n'), "{err}");
        assert!(!left);
        // A bad unit: one line naming the file and the field, no output.
        std::fs::write(&unit, r#"{"out_bits": 0}"#).unwrap();
        let (result, left, _out) = run_in_tmp(&hw);
        let err = format!("{:#}", result.unwrap_err());
        assert!(err.contains("out_bits") && !err.contains('\n'), "{err}");
        assert!(!left);
    }

    #[test]
    fn bad_scene_files_fail_without_output() {
        let dir = tempfile::tempdir().unwrap();
        let cases = [
            (
                "unknown.json",
                r#"{"version": 1, "colour": [1, 0, 0]}"#,
                "colour",
            ),
            ("future.json", r#"{"version": 99}"#, "version 99"),
            ("lobe.json", r#"{"lobe": {"kind": "cosine"}}"#, "cosine"),
            (
                "tf.json",
                r#"{"transfer_function": {"opacity": [[1, 0], [0, 1]], "color": [[0, 1, 1, 1]]}}"#,
                "increasing",
            ),
            (
                "truncated.json",
                r#"{"version": 1, "size": [64"#,
                "scene JSON",
            ),
        ];
        for (name, text, needle) in cases {
            let path = dir.path().join(name);
            std::fs::write(&path, text).unwrap();
            let (result, left, _out) = run_in_tmp(&["--scene", path.to_str().unwrap()]);
            let err = format!("{:#}", result.expect_err(name));
            assert!(
                err.contains(needle) && err.contains(name),
                "{name}: '{err}'"
            );
            assert!(!err.contains('\n'), "{name}: one line expected: {err}");
            // Said once: not "FILE: X: X".
            let rest = err
                .strip_prefix(&format!("{}: ", path.display()))
                .unwrap_or_else(|| panic!("{name}: the file first: {err}"));
            let half = rest.len().saturating_sub(2) / 2;
            assert!(
                !(rest.len() > 2
                    && rest.is_char_boundary(half)
                    && rest[half..].starts_with(": ")
                    && rest[..half] == rest[half + 2..]),
                "{name}: said twice: {err}"
            );
            assert!(!left, "{name} left a file");
        }
        let (result, left, _out) = run_in_tmp(&["--scene", "/nonexistent/scene.json"]);
        let err = format!("{:#}", result.unwrap_err());
        assert!(err.contains("/nonexistent/scene.json"), "{err}");
        assert_eq!(err.matches("os error").count(), 1, "said once: {err}");
        assert!(!left);
    }
}
