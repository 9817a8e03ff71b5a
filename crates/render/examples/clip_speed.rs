//! Frame time of a clip-plane move against a camera move on the MNI152 scene of
//! `benches/mni152.rs` (512x512, step 0.5 voxel, mr-t2-brain, view left), one renderer:
//! a clip change reuses the field and the classification, so it should cost what a
//! camera move costs.
//!
//! `cargo run --release -p glint-render --example clip_speed [frames]`
//!
//! Frames alternate between a camera move (azimuth steps, no clip), the same camera
//! move under a plane that keeps everything (the clip's own cost: the same samples) and
//! a clip move (the plane steps through the volume, camera fixed: other samples, the
//! cut opens the inside), so drift in machine load hits all three; the medians, 95th
//! percentiles and samples per frame are printed. Without the template (`GLINT_MNI152`,
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
    let mut times = [Vec::new(), Vec::new(), Vec::new()];
    let mut samples = [0u64; 3];
    let mut timed = |k: usize, s: &Scene| -> Result<(), Box<dyn std::error::Error>> {
        let t = Instant::now();
        let r = renderer.render(s, &|_| {})?;
        times[k].push(t.elapsed().as_secs_f64() * 1e3);
        samples[k] += r.image.stats.samples;
        assert_eq!(r.timings.get("classify"), std::time::Duration::ZERO);
        Ok(())
    };
    for i in 0..frames {
        let moved = Scene {
            camera: glint_render::CameraSpec {
                azimuth: scene.camera.azimuth + 2.0 * (i + 1) as f64,
                ..scene.camera
            },
            ..scene.clone()
        };
        timed(0, &moved)?;
        let everything = Scene {
            clip: vec![ClipPlane {
                point: [centre[0] - 1e4, centre[1], centre[2]],
                normal: [1.0, 0.0, 0.0],
            }],
            ..moved
        };
        timed(1, &everything)?;
        let offset = 2.0 * i as f64 - frames as f64;
        let cut = Scene {
            clip: vec![ClipPlane {
                point: [centre[0] + offset, centre[1], centre[2]],
                normal: [1.0, 0.0, 0.2],
            }],
            ..scene.clone()
        };
        timed(2, &cut)?;
    }
    let names = [
        "camera move",
        "camera move, plane keeping everything",
        "clip move",
    ];
    for ((name, v), n) in names.iter().zip(times).zip(samples) {
        println!(
            "{name}: median {:.1} ms, p95 {:.1} ms, {} samples per frame over {frames} frames",
            quantile(v.clone(), 0.5),
            quantile(v, 0.95),
            n / frames as u64
        );
    }
    Ok(())
}
