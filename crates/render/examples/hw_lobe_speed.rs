//! Frame time of the `hw` lobe (the hardware unit's table over its cosine codes,
//! `glint_hw::Unit::cos_table`) against float K_4 (`--lobe k`) on the MNI152 scene of
//! `benches/mni152.rs` (512x512, step 0.5 voxel, mr-t2-brain, view left), in one run.
//!
//! `cargo run --release -p glint-render --example hw_lobe_speed [frames] [unit.json]`
//!
//! Frames alternate between the two shaders (so drift in machine load hits both), and
//! the medians are compared. Without the template (`GLINT_MNI152`, default
//! `~/.cache/glint/samples/mni152_t1_09a.nii.gz`) it uses the phantom at 192^3.

use std::time::Instant;

use glint_hw::{Config, Unit};
use glint_render::{LobeSpec, ReadOptions, Renderer, Scene};

#[path = "../benches/common/mni152_scene.rs"]
mod common;

/// The benchmark scene (`common::mni152_scene`).
fn scene() -> Scene {
    common::mni152_scene("hw_lobe_speed")
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let frames: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(15);
    let config = match args.next() {
        Some(path) => Config::from_json(&std::fs::read_to_string(path)?)?,
        None => Config::default(),
    };
    let mut scene = scene();
    let unit = Unit::new(config.clone())?;
    scene.lobe.v = unit.config().v;
    let mut renderer = Renderer::open(&scene, &ReadOptions::default())?;
    let k = renderer.resolve(&scene)?;
    let n = unit.n_code(k.scene.lobe.n.unwrap_or_default())?;
    // K_v at the unit's integer n, so both lobes have the same shininess.
    scene.lobe.n = Some(f64::from(n));
    let k = renderer.resolve(&scene)?;
    // The scene's `hw` lobe, as `glint render --lobe hw` resolves it.
    let hw_scene = Scene {
        lobe: LobeSpec {
            n: scene.lobe.n,
            geometry: scene.lobe.geometry,
            ..LobeSpec::hw(config)
        },
        ..scene.clone()
    };
    let t0 = Instant::now();
    let hw = renderer.resolve(&hw_scene)?;
    let build = t0.elapsed().as_secs_f64();
    // One warm-up frame each (the first also classifies).
    renderer.render_resolved(k.clone(), &|_| {})?;
    renderer.render_resolved(hw.clone(), &|_| {})?;
    let (mut tk, mut th) = (Vec::new(), Vec::new());
    for _ in 0..frames {
        for (resolved, times) in [(&k, &mut tk), (&hw, &mut th)] {
            let r = renderer.render_resolved(resolved.clone(), &|_| {})?;
            times.push(r.timings.get("frame").as_secs_f64() * 1e3);
        }
    }
    let (mk, mh) = (median(tk), median(th));
    println!(
        "n = {n}, {frames} frames each, alternating: k {mk:.1} ms, hw table {mh:.1} ms \
         (median frame), hw/k = {:.3}; hw scene resolved (unit and table built) in {:.2} ms",
        mh / mk,
        build * 1e3
    );
    Ok(())
}
