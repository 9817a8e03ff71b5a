//! Frame time of a clip-plane move against a camera move on the MNI152 scene of
//! `benches/mni152.rs` (512x512, step 0.5 voxel, mr-t2-brain, view left), one renderer:
//! a clip change reuses the field and the classification, so it should cost what a
//! camera move costs.
//!
//! `cargo run --release -p glint-render --example clip_speed [frames]`
//!
//! Frames alternate between a camera move (azimuth steps, no clip) and a clip move (the
//! plane steps through the volume, camera fixed), so drift in machine load hits both;
//! the medians and 95th percentiles are printed. Without the template (`GLINT_MNI152`,
//! default `~/.cache/glint/samples/mni152_t1_09a.nii.gz`) it uses the phantom at 192^3.

use std::time::Instant;

use glint_render::{ClipPlane, ReadOptions, Renderer, Scene};

#[path = "../benches/common/mni152_scene.rs"]
mod common;

/// The `p` quantile (0..=1) of `v`.
fn quantile(mut v: Vec<f64>, p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let frames: usize = match std::env::args().nth(1) {
        Some(n) => n.parse()?,
        None => 20,
    };
    let scene = common::mni152_scene("clip_speed");
    let mut renderer = Renderer::open(&scene, &ReadOptions::default())?;
    // Classified once; the clip's plane then moves through the volume's middle.
    let first = renderer.render(&scene, &|_| {})?;
    let centre = first
        .scene
        .derived
        .as_ref()
        .map_or([0.0; 3], |d| d.focal_point.map(f64::from));
    let (mut camera, mut clip) = (Vec::new(), Vec::new());
    for i in 0..frames {
        let moved = Scene {
            camera: glint_render::CameraSpec {
                azimuth: scene.camera.azimuth + 2.0 * (i + 1) as f64,
                ..scene.camera
            },
            ..scene.clone()
        };
        let t = Instant::now();
        renderer.render(&moved, &|_| {})?;
        camera.push(t.elapsed().as_secs_f64() * 1e3);
        let offset = 2.0 * i as f64 - frames as f64;
        let cut = Scene {
            clip: vec![ClipPlane {
                point: [centre[0] + offset, centre[1], centre[2]],
                normal: [1.0, 0.0, 0.2],
            }],
            ..scene.clone()
        };
        let t = Instant::now();
        let r = renderer.render(&cut, &|_| {})?;
        clip.push(t.elapsed().as_secs_f64() * 1e3);
        assert_eq!(r.timings.get("classify"), std::time::Duration::ZERO);
    }
    for (name, v) in [("camera move", camera), ("clip move", clip)] {
        println!(
            "{name}: median {:.1} ms, p95 {:.1} ms over {frames} frames",
            quantile(v.clone(), 0.5),
            quantile(v, 0.95)
        );
    }
    Ok(())
}
