//! `glint pick`: the 3D point a pixel of a scene's image shows, as JSON.

use std::time::Instant;

use glint_render::{Pick, PICK_OPACITY};

use super::render::open_renderer;
use super::scene_flags::SceneFlags;

/// Arguments of `glint pick`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    glint pick --at 256,200                          # the built-in phantom\n  \
    glint pick head.nii.gz --preset ct-bone --at 256,180 --at 300,180\n  \
    glint pick --scene brain.json --at 120.5,88 --opacity 0.9\n  \
    glint pick lh.pial.gii --view left --at 256,256\n\n\
X,Y are pixels of the image `glint render` writes for the same flags, from its\n\
top-left corner (pixel (i, j) covers [i, i+1) x [j, j+1); its centre i+0.5, j+0.5\n\
traces the same ray as the rendered pixel). One ray is traced with the render's\n\
camera, sampling and transfer function: in composite mode to the first point where\n\
the accumulated opacity reaches --opacity, in iso mode to the iso surface, in MIP\n\
to the ray's maximum; a mesh or label surface in front of that point is picked\n\
instead.\n\n\
Output: one JSON object per --at (an array when there are several; null where the\n\
pixel shows nothing): {\"x\", \"y\", \"object\": {\"kind\": \"volume\" | \"mesh\" (\"index\",\n\
\"path\") | \"isosurface\" | \"label_surface\" (\"label\") | \"label_volume\"}, \"world_mm\",\n\
\"depth_mm\", \"voxel\", \"voxel_nearest\", \"value\" (the nearest voxel's stored value in\n\
the volume's units, after the file's rescale: HU for CT), \"interpolated\" (the value\n\
the renderer classified there), \"units\", \"label\" ({\"id\", \"name\"} or null),\n\
\"opacity\"}. A point off the image is an error.")]
pub struct Args {
    // Boxed: the options are many, and main's subcommand enum should stay small.
    #[command(flatten)]
    scene: Box<SceneFlags>,
    /// Image point to pick, X,Y in pixels from the image's top-left corner (repeat
    /// for several).
    #[arg(long, value_name = "X,Y", required = true, allow_hyphen_values = true, value_parser = parse_point)]
    at: Vec<[f64; 2]>,
    /// Composite mode: the accumulated opacity at which the ray's point is taken,
    /// between 0 and 1 (exclusive) [default: 0.5].
    #[arg(long, value_name = "ALPHA")]
    opacity: Option<f32>,
    /// Benchmarking: pick each point this many times and print ms per pick to stderr.
    #[arg(long, default_value_t = 1, hide = true, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    repeat: u32,
}

/// `X,Y` as two finite numbers.
fn parse_point(s: &str) -> Result<[f64; 2], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let numbers: Option<Vec<f64>> = parts
        .iter()
        .map(|p| p.parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect();
    match numbers.as_deref() {
        Some([x, y]) => Ok([*x, *y]),
        _ => Err(format!(
            "'{s}': expected X,Y, two numbers (pixels from the image's top-left corner)"
        )),
    }
}

/// Runs `glint pick`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let scene = args.scene.scene()?;
    let mut renderer = open_renderer(&scene, &args.scene.read_options())?;
    let opacity = args.opacity.unwrap_or(PICK_OPACITY);
    // The first pick resolves and classifies the scene; later ones reuse it.
    let mut picks: Vec<Option<Pick>> = Vec::with_capacity(args.at.len());
    for &[x, y] in &args.at {
        picks.push(renderer.pick_with(&scene, x, y, opacity)?);
    }
    if args.repeat > 1 {
        let start = Instant::now();
        for _ in 0..args.repeat {
            for &[x, y] in &args.at {
                renderer.pick_with(&scene, x, y, opacity)?;
            }
        }
        let n = f64::from(args.repeat) * args.at.len() as f64;
        eprintln!(
            "glint: {:.3} ms per pick ({} picks after the first)",
            start.elapsed().as_secs_f64() * 1e3 / n,
            n
        );
    }
    let json = match picks.as_slice() {
        [one] => serde_json::to_string_pretty(one)?,
        many => serde_json::to_string_pretty(many)?,
    };
    println!("{json}");
    Ok(())
}
