//! Issue 19, item 2: the image-level effect of the unit's widths. For the phantom and
//! the MNI152 template (the scene of `benches/mni152.rs`, n from the preset), renders
//! with the unit's table for output widths 8, 10, 12 bits and the energy-fit (`k`) and
//! minimax ROMs (every other width the default's), and compares each with the float
//! lobe of the same coefficient and with exact `cos^n`: mean and max absolute
//! difference of the 8-bit sRGB codes (`Image::encode_srgb`) over all pixels and
//! channels, and the share of pixels that differ at all. Prints a markdown table.
//!
//! `cargo run --release -p glint-render --example hw_sweep`

use std::path::PathBuf;

use glint_hw::{Coefficients, Config, Unit};
use glint_lobe::{LobeKind, Specular};
use glint_render::{CameraSpec, Depth, Image, Input, Phantom, Renderer, Scene, View};

/// Output widths of the sweep (issue 19).
const OUT_BITS: [u32; 3] = [8, 10, 12];

fn scenes() -> Vec<(&'static str, Scene)> {
    let base = Scene {
        camera: CameraSpec {
            view: View::Left,
            ..Default::default()
        },
        size: [512, 512],
        step: 0.5,
        ..Scene::default()
    };
    let phantom = Scene {
        input: Input::Phantom {
            name: Phantom::SheppLogan,
            size: 192,
        },
        preset: Some("phantom".into()),
        ..base.clone()
    };
    let home = std::env::var_os("HOME").unwrap_or_default();
    let path = PathBuf::from(home).join(".cache/glint/samples/mni152_t1_09a.nii.gz");
    let mut out = vec![("phantom 192^3", phantom)];
    if path.is_file() {
        let mni = Scene {
            input: Input::Path(path),
            preset: Some("mr-t2-brain".into()),
            ..base
        };
        out.push(("MNI152 T1", mni));
    } else {
        eprintln!("hw_sweep: {} missing; phantom only", path.display());
    }
    out
}

/// Mean and max |a - b| of 8-bit sRGB codes, and the share of pixels that differ.
fn diff(a: &Image, b: &Image) -> (f64, u8, f64) {
    let (a, b) = (a.encode_srgb(Depth::Eight), b.encode_srgb(Depth::Eight));
    let d: Vec<u8> = a.iter().zip(&b).map(|(x, y)| x.abs_diff(*y)).collect();
    let mean = d.iter().map(|&x| f64::from(x)).sum::<f64>() / d.len() as f64;
    let max = d.iter().copied().max().unwrap_or(0);
    let px = d.chunks(3).filter(|p| p.iter().any(|&x| x > 0)).count();
    (mean, max, px as f64 / (d.len() / 3) as f64)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!("| volume | n | ROM | out bits | vs float (same a): mean / max / pixels | vs exact: mean / max / pixels |");
    println!("|---|---|---|---|---|---|");
    for (name, mut scene) in scenes() {
        let mut renderer = Renderer::open(&scene.input)?;
        let n = renderer
            .resolve(&scene)?
            .scene
            .lobe
            .n
            .unwrap_or_default()
            .round();
        scene.lobe.n = Some(n);
        let render = |renderer: &mut Renderer, kind: LobeKind, spec: Option<Specular>| {
            let mut s = scene.clone();
            s.lobe.kind = kind;
            let mut resolved = renderer.resolve(&s)?;
            if let Some(spec) = spec {
                resolved.shader.set_specular(spec);
            }
            renderer.render_resolved(resolved, &|_| {}).map(|r| r.image)
        };
        let exact = render(&mut renderer, LobeKind::Exact, None)?;
        for (coefficients, kind) in [
            (Coefficients::EnergyFit, LobeKind::EnergyFit),
            (Coefficients::Minimax, LobeKind::Minimax),
        ] {
            let float = render(&mut renderer, kind, None)?;
            for out_bits in OUT_BITS {
                let unit = Unit::new(Config {
                    out_bits,
                    coefficients,
                    ..Config::default()
                })?;
                let table = unit.cos_table(unit.n_code(n)?)?;
                let hw = render(&mut renderer, kind, Some(Specular::from(table)))?;
                let (fm, fx, fp) = diff(&hw, &float);
                let (em, ex, ep) = diff(&hw, &exact);
                println!(
                    "| {name} | {n} | {coefficients} | {out_bits} | {fm:.4} / {fx} / {:.2}% | {em:.4} / {ex} / {:.2}% |",
                    100.0 * fp,
                    100.0 * ep
                );
            }
            let (em, ex, ep) = diff(&float, &exact);
            println!(
                "| {name} | {n} | {coefficients} | float f32 | - | {em:.4} / {ex} / {:.2}% |",
                100.0 * ep
            );
        }
    }
    Ok(())
}
