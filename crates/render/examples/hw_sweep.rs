//! Issue 19, item 2: the image-level effect of the unit's widths. For the default
//! phantom scene (`glint render`'s defaults) and the MNI152 template (mr-t2-brain,
//! view left), n from the preset, renders with the `hw` lobe for output widths 8, 10,
//! 12 bits and the energy-fit (`k`) and minimax ROMs (every other width the
//! default's, `glint_hw::Config::default()`), and compares each with the float lobe of
//! the same coefficient and with exact `cos^n`: CIEDE2000 ΔE of the 8-bit sRGB images
//! (`glint_analysis::image`, as `glint compare` measures), mean, 99th percentile and
//! the share of pixels above 1. Prints a markdown table.
//!
//! `cargo run --release -p glint-render --example hw_sweep`
//!
//! `glint compare --lobe hw` measures against exact only; the comparison with the
//! float lobe of the same ROM is why this is an example.

use glint_analysis::image::{DeltaEStats, Srgb8Image};
use glint_hw::{Coefficients, Config};
use glint_lobe::LobeKind;
use glint_render::{CameraSpec, Depth, Image, Input, LobeSpec, ReadOptions, Renderer, Scene, View};

/// Output widths of the sweep (issue 19).
const OUT_BITS: [u32; 3] = [8, 10, 12];

fn scenes() -> Vec<(&'static str, Scene)> {
    let mut out = vec![("phantom (default scene)", Scene::default())];
    let path = glint_testkit::samples_dir().join("mni152_t1_09a.nii.gz");
    if path.is_file() {
        let mni = Scene {
            input: Input::Path(path),
            preset: Some("mr-t2-brain".into()),
            camera: CameraSpec {
                view: View::Left,
                ..Default::default()
            },
            ..Scene::default()
        };
        out.push(("MNI152 T1, left", mni));
    } else {
        eprintln!("hw_sweep: {} missing; phantom only", path.display());
    }
    out
}

fn srgb(image: &Image) -> Result<Srgb8Image, Box<dyn std::error::Error>> {
    let bytes = image.encode_srgb(Depth::Eight);
    Ok(Srgb8Image::from_bytes(image.width, image.height, &bytes)?)
}

/// `mean / p99 / share > 1` of ΔE00 of `test` against `reference`.
fn delta_e(
    reference: &Srgb8Image,
    test: &Srgb8Image,
) -> Result<String, Box<dyn std::error::Error>> {
    let s = DeltaEStats::compare(reference, test, None)?.ok_or("no pixels")?;
    Ok(format!(
        "{:.3} / {:.2} / {:.2}%",
        s.mean,
        s.p99,
        100.0 * s.above_1
    ))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!("| volume | n | ROM | output | vs float lobe (same ROM): mean / p99 / ΔE>1 | vs exact: mean / p99 / ΔE>1 |");
    println!("|---|---|---|---|---|---|");
    for (name, mut scene) in scenes() {
        let mut renderer = Renderer::open(&scene, &ReadOptions::default())?;
        let n = renderer
            .resolve(&scene)?
            .scene
            .lobe
            .n
            .unwrap_or_default()
            .round();
        scene.lobe.n = Some(n);
        let mut render = |lobe: LobeSpec| -> Result<Srgb8Image, Box<dyn std::error::Error>> {
            let s = Scene {
                lobe: LobeSpec { n: Some(n), ..lobe },
                ..scene.clone()
            };
            srgb(&renderer.render(&s, &|_| {})?.image)
        };
        let float = |kind: LobeKind| LobeSpec {
            kind: kind.into(),
            ..LobeSpec::default()
        };
        let exact = render(float(LobeKind::Exact))?;
        for (coefficients, kind) in [
            (Coefficients::EnergyFit, LobeKind::EnergyFit),
            (Coefficients::Minimax, LobeKind::Minimax),
        ] {
            let reference = render(float(kind))?;
            for out_bits in OUT_BITS {
                let hw = render(LobeSpec::hw(Config {
                    out_bits,
                    coefficients,
                    ..Config::default()
                }))?;
                println!(
                    "| {name} | {n} | {coefficients} | {out_bits} bits | {} | {} |",
                    delta_e(&reference, &hw)?,
                    delta_e(&exact, &hw)?
                );
            }
            println!(
                "| {name} | {n} | {coefficients} | float (f32) | - | {} |",
                delta_e(&exact, &reference)?
            );
        }
    }
    Ok(())
}
