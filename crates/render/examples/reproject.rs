//! Issue 41, item 2: what carrying the accumulated `path` image across a camera turn
//! would give, measured before building it into the viewer.
//!
//! The history: the scene at azimuth 0 accumulated to `HISTORY` samples per pixel.
//! For each turn of `STEP` degrees, every pixel of the new view with a first hit (the
//! deterministic one the denoisers' features use: where accumulated opacity crosses
//! [`glint_render::FEATURE_OPACITY`]) is moved into the old view by its depth, and its
//! history is accepted where the old view's first hit lies within 1 % of the same
//! depth with a normal within 25° (the usual test of temporal reprojection: Nehab et
//! al., "Accelerating real-time shading with reverse reprojection caching", GH 2007;
//! Schied et al., SVGF, HPG 2017). An accepted pixel's estimate is the history's mean
//! blended with one new sample, weighted by their sample counts (`HISTORY` to 1); the
//! others have the new sample alone. Printed per turn: the share of covered pixels
//! accepted, and the mean ꟻLIP to a `REF`-sample image of the new view of (a) one
//! new sample alone, (b) the reprojected blend, (c) 2, 4, 8 and `HISTORY` + 1 fresh
//! samples (the last: what the blend would be if the history were unbiased there),
//! so the blend's error can be read as the samples a fresh start needs to reach it.
//!
//! `cargo run --release -p glint-render --example reproject [FILE] [PRESET] [SIZE]
//! [HISTORY] [REF] [STEPS]` (defaults: the head phantom, its preset, 192, 32, 512,
//! "0.5,2,8,30")

use glint_analysis::image::{flip, Srgb8Image};
use glint_render::math::Vec3;
use glint_render::{
    Camera, Image, Input, LightingModel, PathFeatures, Plan, Projection, ReadOptions, Renderer,
    Scene,
};

/// The scene turned to `azimuth`, traced to `spp` samples (seed 1: the views' noise
/// streams are independent of the history's, seed 0).
fn at(base: &Scene, azimuth: f64, spp: u32, seed: u64) -> Scene {
    let mut s = base.clone();
    s.camera.azimuth = azimuth;
    s.lighting.spp = Some(spp);
    s.lighting.seed = Some(seed);
    s
}

/// The first-hit features and the camera of `scene`.
fn features(
    r: &mut Renderer,
    scene: &Scene,
) -> Result<(PathFeatures, Camera), Box<dyn std::error::Error>> {
    let resolved = r.resolve(scene)?;
    let Plan::Volume {
        tf,
        classify,
        frame,
        ..
    } = resolved.plan
    else {
        return Err("not a volume scene".into());
    };
    let (class, _) = r.classification(&tf, &classify)?;
    let f = class.path_features(&resolved.shader, &frame, None)?;
    Ok((f, class.camera(&frame)?))
}

/// Pixel coordinates (centre at integer + 0) of world point `p` in `cam`'s image.
fn project(cam: &Camera, p: Vec3, w: u32, h: u32) -> Option<(f32, f32)> {
    let [u0, du, v0, dv] = cam.image_plane(w, h);
    let d = p - cam.eye;
    let z = d.dot(cam.forward);
    let (u, v) = match cam.projection {
        Projection::Perspective => {
            if z <= 1e-3 {
                return None;
            }
            (d.dot(cam.right) / z, d.dot(cam.up) / z)
        }
        Projection::Orthographic => (d.dot(cam.right), d.dot(cam.up)),
    };
    Some(((u - u0) / du, (v - v0) / dv))
}

fn srgb(i: &Image) -> Srgb8Image {
    Srgb8Image::from_linear(i.width, i.height, &i.rgb).expect("image size")
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize| args.get(i).filter(|a| !a.is_empty()).cloned();
    let size: u32 = arg(2).map_or(Ok(192), |s| s.parse())?;
    let history: u32 = arg(3).map_or(Ok(32), |s| s.parse())?;
    let reference: u32 = arg(4).map_or(Ok(512), |s| s.parse())?;
    let steps: Vec<f64> = arg(5)
        .unwrap_or_else(|| "0.5,2,8,30".into())
        .split(',')
        .map(|s| s.parse())
        .collect::<Result<_, _>>()?;
    let mut base = Scene::default();
    if let Some(file) = arg(0) {
        base.input = Input::Path(file.into());
    }
    base.preset = arg(1);
    base.size = [size, size];
    base.lighting.model = LightingModel::Path;
    let mut r = Renderer::open(&base, &ReadOptions::default())?;
    let old = r.render(&at(&base, 0.0, history, 0), &|_| {})?.image;
    let (fa, cam_a) = features(&mut r, &at(&base, 0.0, 1, 0))?;
    println!(
        "reproject: {} at {size}x{size}, history {history} spp, reference {reference} spp",
        arg(0).unwrap_or_else(|| "the head phantom".into())
    );
    println!(
        "| turn | accepted | ꟻLIP 1 new sample | ꟻLIP reprojected + 1 | ꟻLIP {} fresh |",
        history + 1
    );
    println!("|---|---|---|---|---|");
    for step in steps {
        let one = r.render(&at(&base, step, 1, 1), &|_| {})?.image;
        // Fresh samples accumulated in one image: 2, 4, 8, then history + 1.
        let mut fresh = Vec::new();
        for spp in [2, 4, 8, history + 1] {
            fresh.push(r.render(&at(&base, step, spp, 1), &|_| {})?.image);
        }
        let truth = r.render(&at(&base, step, reference, 2), &|_| {})?.image;
        let (fb, cam_b) = features(&mut r, &at(&base, step, 1, 1))?;
        let (w, h) = (size, size);
        let mut blend = one.clone();
        let (mut covered, mut accepted) = (0usize, 0usize);
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                if !fb.hit(i) {
                    continue;
                }
                covered += 1;
                let (o, d) = cam_b.ray(x as f32, y as f32, w, h);
                let p = o + d * fb.depth[i];
                let Some((xa, ya)) = project(&cam_a, p, w, h) else {
                    continue;
                };
                let (xa, ya) = (xa.round(), ya.round());
                if xa < 0.0 || ya < 0.0 || xa >= w as f32 || ya >= h as f32 {
                    continue;
                }
                let j = (ya as u32 * w + xa as u32) as usize;
                if !fa.hit(j) {
                    continue;
                }
                let (oa, da) = cam_a.ray(xa, ya, w, h);
                let expect = (p - oa).dot(da);
                let near = (fa.depth[j] - expect).abs() <= 0.01 * expect.abs().max(1.0);
                let [n1, n2] = [fa.normal[j], fb.normal[i]];
                let facing =
                    n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2] >= 25f32.to_radians().cos();
                if !(near && facing) {
                    continue;
                }
                accepted += 1;
                let k = history as f32;
                for c in 0..3 {
                    blend.rgb[i][c] = (k * old.rgb[j][c] + one.rgb[i][c]) / (k + 1.0);
                }
            }
        }
        let t = srgb(&truth);
        let e = |img: &Image| flip(&t, &srgb(img), None).map(|m| m.unwrap_or(f64::NAN));
        let fresh: Vec<String> = fresh
            .iter()
            .map(|f| e(f).map(|v| format!("{v:.4}")))
            .collect::<Result<_, _>>()?;
        println!(
            "| {step}° | {:.1} % of {covered} | {:.4} | {:.4} | {} |",
            100.0 * accepted as f64 / covered.max(1) as f64,
            e(&one)?,
            e(&blend)?,
            fresh.join(" / ")
        );
    }
    Ok(())
}
