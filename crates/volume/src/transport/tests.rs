//! Light transport against closed forms: a slab's transmittance `exp(-τ)`, delta and
//! ratio tracking in agreement on a heterogeneous medium, a white furnace, an opaque
//! sphere's shadow where geometry puts it, determinism per seed on any thread count,
//! the SIMD loop against the scalar one under shadows, an environment map's furnace
//! and its MIS against each strategy alone. Small volumes, few samples.

use std::sync::Arc;

use glint_core::{Light, Material, RenderMode, Shader, Vec3};
use glint_io::{Samples, Volume};
use glint_lobe::{Geometry, LobeKind};

use super::rng::Rng;
use super::tracking::{IndexRay, Tracker};
use super::*;
use crate::classification::{Classification, ClassifySettings, Sampling, TransferFunction};
use crate::field::Field;
use crate::raycast::{FrameSettings, Kernel};
use crate::Transport;

/// The `path` model's frame: samples added to `img` until it holds `spp` (no meshes).
pub(super) fn path_frame(
    class: &Classification,
    shader: &Shader,
    frame: &FrameSettings,
    settings: &PathSettings,
    img: &mut PathImage,
    spp: u32,
) -> Result<glint_core::Image, glint_core::RenderError> {
    let transport = Transport::Path {
        image: img,
        spp,
        settings: *settings,
        occluders: None,
        environment: None,
        cancel: None,
    };
    class.frame(shader, frame, None, transport, &|_| {})
}

/// The `shadows` model's frame lit through `sf`.
pub(super) fn shadows_frame(
    class: &Classification,
    shader: &Shader,
    frame: &FrameSettings,
    sf: &ShadowField,
) -> Result<glint_core::Image, glint_core::RenderError> {
    class.frame(shader, frame, None, Transport::Shadows(sf), &|_| {})
}

/// The `local` model's frame.
fn local_frame(
    class: &Classification,
    shader: &Shader,
    frame: &FrameSettings,
) -> glint_core::Image {
    class
        .frame(shader, frame, None, Transport::Local, &|_| {})
        .unwrap()
}

/// A volume of `dims` and `spacing` whose value at voxel `(i, j, k)` is `f`.
pub(super) fn volume(
    dims: [usize; 3],
    spacing: [f64; 3],
    f: impl Fn(f32, f32, f32) -> f32,
) -> Volume {
    let mut v = Vec::with_capacity(dims.iter().product());
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                v.push(f(i as f32, j as f32, k as f32));
            }
        }
    }
    Volume::new(dims, spacing, Samples::F32(v)).unwrap()
}

pub(super) fn classify(vol: &Volume, tf: &TransferFunction) -> Classification {
    let field = Arc::new(Field::new(vol).unwrap());
    Classification::new(field, tf, &ClassifySettings::default()).unwrap()
}

/// White colour at every value; opacity per unit (one voxel of the smallest spacing)
/// from the `(value, alpha)` points.
pub(super) fn white(opacity: &[(f64, f64)]) -> TransferFunction {
    TransferFunction::new(opacity.to_vec(), vec![(0.0, [1.0; 3])]).unwrap()
}

/// Mean of `n` estimates.
fn mean(n: u64, mut f: impl FnMut(u64) -> f64) -> f64 {
    (0..n).map(&mut f).sum::<f64>() / n as f64
}

#[test]
fn a_slab_transmits_exp_minus_its_optical_depth() {
    // A box of uniform matter, anisotropic voxels: opacity 0.02 per 0.5 mm (the
    // smallest spacing), so σ = -ln(0.98) / 0.5 per mm; an oblique ray across it.
    let spacing = [1.0, 0.5, 2.0];
    let vol = volume([30, 20, 10], spacing, |_, _, _| 1.0);
    let class = classify(&vol, &white(&[(0.0, 0.02)]));
    let sigma = -(0.98f64).ln() / 0.5;
    let field = &**class.field();
    let track = Tracker {
        field,
        medium: class.medium(),
        clip: None,
    };
    // World box: x in [0, 29] mm, y in [0, 9.5], z in [0, 18] (voxel centres).
    let dir = Vec3::new(1.0, 0.2, 0.3).normalize_or_zero();
    let origin = Vec3::new(-5.0, 2.0, 3.0);
    let (dx, dy, dz) = (dir.x as f64, dir.y as f64, dir.z as f64);
    let (ox, oy, oz) = (origin.x as f64, origin.y as f64, origin.z as f64);
    // Entry at x = 0; exit at the nearest of x = 29, y = 9.5, z = 18.
    let t_in = -ox / dx;
    let t_out = ((29.0 - ox) / dx)
        .min((9.5 - oy) / dy)
        .min((18.0 - oz) / dz);
    let tau = sigma * (t_out - t_in);
    assert!((0.8..1.6).contains(&tau), "τ = {tau}");
    let want = (-tau).exp();
    let ray = IndexRay::from_world(field, origin, dir);
    let n = 200_000;
    let delta = mean(n, |s| {
        let mut rng = Rng::new(11, 0, s);
        f64::from(u8::from(
            track
                .free_path(&ray, 0.0, f32::INFINITY, &mut rng)
                .is_none(),
        ))
    });
    let ratio = mean(n, |s| {
        let mut rng = Rng::new(12, 0, s);
        f64::from(track.transmittance(&ray, 0.0, f32::INFINITY, &mut rng))
    });
    eprintln!("slab: exp(-{tau:.4}) = {want:.5}; delta {delta:.5}, ratio {ratio:.5}");
    for (what, got) in [("delta", delta), ("ratio", ratio)] {
        assert!(
            (got - want).abs() < 0.01 * want,
            "{what} tracking: {got} against exp(-{tau}) = {want}"
        );
    }
}

#[test]
fn delta_and_ratio_tracking_agree_on_a_heterogeneous_medium() {
    // A ball whose density falls off with the radius, and a ray through it off
    // centre: many macro cells, majorants above the extinction.
    let vol = volume([32, 32, 32], [1.0; 3], |i, j, k| {
        let r = ((i - 15.5).powi(2) + (j - 15.5).powi(2) + (k - 15.5).powi(2)).sqrt();
        (14.0 - r).max(0.0)
    });
    let class = classify(&vol, &white(&[(0.0, 0.0), (14.0, 0.08)]));
    let field = &**class.field();
    let track = Tracker {
        field,
        medium: class.medium(),
        clip: None,
    };
    let ray = IndexRay::from_world(
        field,
        Vec3::new(-3.0, 12.0, 14.0),
        Vec3::new(1.0, 0.1, 0.05).normalize_or_zero(),
    );
    // A deterministic reference: the optical depth by the midpoint rule, 0.01 mm.
    let (t0, t1) = ray.clip(field.dims(), 0.0, f32::INFINITY).unwrap();
    let steps = ((t1 - t0) / 0.01) as usize;
    let h = (t1 - t0) / steps as f32;
    let tau: f64 = (0..steps)
        .map(|i| {
            f64::from(
                track
                    .medium
                    .sigma_at(field, ray.at(t0 + (i as f32 + 0.5) * h))
                    * h,
            )
        })
        .sum();
    let want = (-tau).exp();
    assert!((0.1..0.7).contains(&want), "T = {want}");
    let n = 200_000;
    let delta = mean(n, |s| {
        let mut rng = Rng::new(21, 0, s);
        f64::from(u8::from(
            track
                .free_path(&ray, 0.0, f32::INFINITY, &mut rng)
                .is_none(),
        ))
    });
    let ratio = mean(n, |s| {
        let mut rng = Rng::new(22, 0, s);
        f64::from(track.transmittance(&ray, 0.0, f32::INFINITY, &mut rng))
    });
    eprintln!("ball: quadrature {want:.5}; delta {delta:.5}, ratio {ratio:.5}");
    assert!(
        (delta - ratio).abs() < 0.015 * want,
        "delta {delta}, ratio {ratio}"
    );
    assert!(
        (ratio - want).abs() < 0.01 * want,
        "ratio {ratio}, quadrature {want}"
    );
}

/// A shader of white diffuse albedo 1 (no ambient, no specular) and the given lights.
pub(super) fn albedo_one(lights: Vec<Light>, gate: f32) -> Shader {
    let m = Material {
        ambient: 0.0,
        diffuse: 1.0,
        specular: 0.0,
        shade: true,
    };
    Shader::new(
        LobeKind::EnergyFit,
        20.0,
        4,
        Geometry::Phong,
        m,
        lights,
        gate,
    )
    .unwrap()
}

#[test]
fn a_white_furnace_shows_the_environment() {
    // Uniform matter of albedo 1 that only scatters, lit by a uniform environment
    // seen also as the background: every pixel's radiance is the environment's.
    let vol = volume([16, 16, 16], [1.0; 3], |_, _, _| 1.0);
    let class = classify(&vol, &white(&[(0.0, 0.15)]));
    let env = 0.7f32;
    let frame = FrameSettings {
        width: 12,
        height: 12,
        background: [env; 3],
        ..Default::default()
    };
    for (g, sampler) in [
        (0.0f32, Sampler::Sobol),
        (0.6, Sampler::Sobol),
        (0.6, Sampler::Independent),
    ] {
        let shader = albedo_one(vec![Light::HEADLIGHT], 0.0)
            .with_anisotropy(g)
            .unwrap();
        // The headlight at intensity 0: environment light alone.
        let shader = Shader::with_specular(
            shader.specular().clone(),
            Geometry::Phong,
            *shader.material(),
            vec![Light {
                intensity: 0.0,
                ..Light::HEADLIGHT
            }],
            0.0,
        )
        .unwrap()
        .with_anisotropy(g)
        .unwrap();
        let settings = PathSettings {
            bounces: MAX_BOUNCES,
            seed: 9,
            environment: env,
            sampler,
            time_budget: None,
            show_environment: false,
        };
        let mut img = PathImage::new(12, 12);
        path_frame(&class, &shader, &frame, &settings, &mut img, 256).unwrap();
        let image = img.image(frame.background);
        // The radiance of the paths that met the matter, the background (the
        // environment, exactly) taken out: Σ(rgb - (1 - α) env) / Σα.
        let e = f64::from(env);
        let (mut scattered, mut covered) = (0.0f64, 0.0f64);
        for (c, &a) in image.rgb.iter().zip(&image.alpha) {
            scattered += f64::from(c[1]) - (1.0 - f64::from(a)) * e;
            covered += f64::from(a);
        }
        assert!(
            covered > 60.0,
            "{covered} pixels' worth of paths met the matter"
        );
        let mean = scattered / covered;
        eprintln!("furnace, g = {g}, {sampler:?}: mean {mean:.5}, environment {env}");
        assert!(
            (mean - f64::from(env)).abs() < 0.01 * f64::from(env),
            "g = {g}: mean radiance {mean}, environment {env}"
        );
        // Paths scatter more than once on average (the furnace tests multiple
        // scattering, not only single).
        assert!(
            image.stats.shaded > image.stats.samples,
            "{:?}",
            image.stats
        );
    }
}

/// A floor slab (value 1, z in 4..=8) under an opaque ball (value 2, radius 6 at
/// (24, 24, 24)), 48^3 voxels of 1 mm; opacity 0.5 per voxel for the floor, full for
/// the ball.
pub(super) fn ball_over_floor() -> Classification {
    let vol = volume([48, 48, 48], [1.0; 3], |i, j, k| {
        let r = ((i - 24.0).powi(2) + (j - 24.0).powi(2) + (k - 24.0).powi(2)).sqrt();
        if r <= 6.0 {
            2.0
        } else if (4.0..=8.0).contains(&k) {
            1.0
        } else {
            0.0
        }
    });
    let tf = white(&[(0.0, 0.0), (0.5, 0.0), (1.0, 0.5), (1.5, 0.5), (2.0, 1.0)]);
    classify(&vol, &tf)
}

#[test]
fn an_opaque_balls_shadow_falls_where_geometry_puts_it() {
    let class = ball_over_floor();
    // A light straight above: the camera looks down (superior) with a headlight.
    let frame = FrameSettings {
        width: 16,
        height: 16,
        camera: glint_core::CameraSpec {
            view: glint_core::View::Superior,
            ..Default::default()
        },
        ..Default::default()
    };
    let shader = albedo_one(vec![Light::HEADLIGHT], 0.0);
    let shadows = class
        .shadow_field(&shader, &frame, &ShadowSettings::default(), None)
        .unwrap();
    let cam = class.camera(&frame).unwrap();
    let placed = shader.placed(&cam);
    let up = placed.world_lights()[0].0;
    assert!(
        up.z > 0.99,
        "the headlight of a superior view shines from +z: {up:?}"
    );
    let field = &**class.field();
    let track = Tracker {
        field,
        medium: class.medium(),
        clip: None,
    };
    let l_index = field.index_direction(up);
    // Points on the floor's top face (z = 8): under the ball (r < 4) dark, clear of
    // its shadow (r > 9) lit, both in the light volume and by ratio tracking.
    let mut checked = 0;
    for (x, y) in [
        (24.0, 24.0),
        (26.0, 22.0),
        (21.0, 25.0),
        (24.0, 36.0),
        (10.0, 10.0),
        (38.0, 20.0),
    ] {
        let r = ((x - 24.0f32).powi(2) + (y - 24.0f32).powi(2)).sqrt();
        let p = [x, y, 8.0];
        let volume_t = shadows.transmittance(0, p).unwrap();
        let ray = IndexRay {
            o: Vec3::new(x, y, 8.0),
            d: l_index,
        };
        let traced = mean(2000, |s| {
            let mut rng = Rng::new(5, 1, s);
            f64::from(track.transmittance(&ray, 0.5, f32::INFINITY, &mut rng))
        });
        if r < 4.0 {
            assert!(
                volume_t < 0.05,
                "({x}, {y}) under the ball: light volume {volume_t}"
            );
            assert!(traced < 0.01, "({x}, {y}) under the ball: traced {traced}");
            checked += 1;
        } else if r > 9.0 {
            assert!(
                volume_t > 0.9,
                "({x}, {y}) in the open: light volume {volume_t}"
            );
            assert!(traced > 0.98, "({x}, {y}) in the open: traced {traced}");
            checked += 1;
        }
    }
    assert_eq!(checked, 6);
    // In the image: a headlight hides the ball's shadow behind the ball, so light it
    // from 40 degrees towards the image's right: the shadow falls on the floor to the
    // left of the ball, where the image under `shadows` is dark and the local one lit.
    let side = albedo_one(
        vec![Light {
            azimuth: 40.0,
            elevation: 0.0,
            intensity: 1.0,
        }],
        0.0,
    );
    let frame = FrameSettings {
        width: 48,
        height: 48,
        ..frame.clone()
    };
    let sf = class
        .shadow_field(&side, &frame, &ShadowSettings::default(), None)
        .unwrap();
    let lit = shadows_frame(&class, &side, &frame, &sf).unwrap();
    let local = local_frame(&class, &side, &frame);
    let lum = |img: &glint_core::Image, x: usize, y: usize| img.rgb[y * 48 + x][1];
    // Where the shadow falls in the image: the floor point under the light's ray
    // through the ball's centre, projected by the camera.
    let cam = class.camera(&frame).unwrap();
    let l = side.placed(&cam).world_lights()[0].0;
    // The ball's centre (world = index here) moved down the light to the floor top.
    let c = Vec3::new(24.0, 24.0, 24.0);
    assert!(l.z > 0.5, "{l:?}");
    let floor = c - l * ((c.z - 8.0) / l.z);
    assert!(
        (floor - Vec3::new(24.0, 24.0, 8.0)).length() > 10.0,
        "{floor:?}"
    );
    let [u0, du, v0, dv] = cam.image_plane(48, 48);
    let rel = floor - cam.eye;
    let (u, v) = match cam.projection {
        glint_core::Projection::Perspective => {
            let f = rel.dot(cam.forward);
            (rel.dot(cam.right) / f, rel.dot(cam.up) / f)
        }
        glint_core::Projection::Orthographic => (rel.dot(cam.right), rel.dot(cam.up)),
    };
    let (px, py) = (
        ((u - u0) / du).round() as usize,
        ((v - v0) / dv).round() as usize,
    );
    assert!(px < 48 && py < 48, "shadow at ({px}, {py})");
    assert!(
        lum(&lit, px, py) < 0.5 * lum(&local, px, py),
        "shadow pixel ({px}, {py}): shadows {} local {}",
        lum(&lit, px, py),
        lum(&local, px, py)
    );
}

pub(super) fn small_scene() -> (Classification, Shader, FrameSettings) {
    let class = ball_over_floor();
    let shader = Shader::new(
        LobeKind::EnergyFit,
        30.0,
        4,
        Geometry::Blinn,
        Material::default(),
        vec![
            Light::HEADLIGHT,
            Light {
                azimuth: 35.0,
                elevation: 20.0,
                intensity: 0.8,
            },
        ],
        0.05,
    )
    .unwrap()
    .with_anisotropy(0.3)
    .unwrap();
    let frame = FrameSettings {
        width: 20,
        height: 16,
        camera: glint_core::CameraSpec {
            azimuth: 20.0,
            elevation: 30.0,
            ..Default::default()
        },
        ..Default::default()
    };
    (class, shader, frame)
}

fn on_threads<T: Send>(n: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
        .install(f)
}

#[test]
fn path_images_depend_on_the_seed_and_sample_count_alone() {
    for sampler in Sampler::ALL {
        path_images_depend_on_the_seed_and_sample_count_alone_with(sampler);
    }
}

fn path_images_depend_on_the_seed_and_sample_count_alone_with(sampler: Sampler) {
    let (class, shader, frame) = small_scene();
    let settings = PathSettings {
        bounces: 4,
        seed: 3,
        environment: 0.5,
        sampler,
        time_budget: None,
        show_environment: false,
    };
    let trace = |threads: usize, batches: &[u32]| {
        on_threads(threads, || {
            let mut img = PathImage::new(20, 16);
            for &spp in batches {
                path_frame(&class, &shader, &frame, &settings, &mut img, spp).unwrap();
            }
            img.image(frame.background)
        })
    };
    let one = trace(1, &[4]);
    let two = trace(2, &[4]);
    let batched = trace(2, &[1, 3, 4]);
    let bits = |img: &glint_core::Image| {
        img.rgb
            .iter()
            .flatten()
            .chain(&img.alpha)
            .map(|x| x.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&one), bits(&two), "1 thread against 2");
    assert_eq!(bits(&one), bits(&batched), "one batch against three");
    assert!(one.alpha.iter().any(|&a| a > 0.0));
    // Another seed gives another image.
    let other = on_threads(2, || {
        let mut img = PathImage::new(20, 16);
        let s = PathSettings {
            seed: 4,
            ..settings
        };
        path_frame(&class, &shader, &frame, &s, &mut img, 4).unwrap();
        img.image(frame.background)
    });
    assert_ne!(bits(&one), bits(&other));
    // Fewer samples than held is refused.
    let mut img = PathImage::new(20, 16);
    path_frame(&class, &shader, &frame, &settings, &mut img, 2).unwrap();
    assert!(path_frame(&class, &shader, &frame, &settings, &mut img, 1).is_err());
}

/// The mean luminance of an image's pixels.
fn mean_luminance(img: &glint_core::Image) -> f64 {
    let sum: f64 = (img.rgb.iter())
        .map(|c| 0.2126 * f64::from(c[0]) + 0.7152 * f64::from(c[1]) + 0.0722 * f64::from(c[2]))
        .sum();
    sum / img.rgb.len() as f64
}

#[test]
fn sobol_and_independent_samplers_agree_and_sobol_is_less_noisy() {
    // Both estimate the same image: the mean over the image at 64 spp agrees with a
    // 512-spp reference for each; Sobol's per-pixel error to the reference is lower.
    let (class, shader, frame) = small_scene();
    let run = |sampler, seed, spp| {
        let settings = PathSettings {
            bounces: 4,
            seed,
            environment: 0.5,
            sampler,
            time_budget: None,
            show_environment: false,
        };
        let mut img = PathImage::new(20, 16);
        path_frame(&class, &shader, &frame, &settings, &mut img, spp).unwrap()
    };
    let reference = run(Sampler::Independent, 100, 512);
    let rms = |img: &glint_core::Image| {
        let sq: f64 = (img.rgb.iter().zip(&reference.rgb))
            .map(|(a, b)| {
                (0..3)
                    .map(|c| (f64::from(a[c]) - f64::from(b[c])).powi(2))
                    .sum::<f64>()
            })
            .sum();
        (sq / (3 * img.rgb.len()) as f64).sqrt()
    };
    let want = mean_luminance(&reference);
    let mut errors = Vec::new();
    for sampler in Sampler::ALL {
        // Over several seeds, so the comparison is not one draw's luck.
        let images: Vec<_> = (1..=4).map(|seed| run(sampler, seed, 16)).collect();
        let error = images.iter().map(rms).sum::<f64>() / 4.0;
        let mean = images.iter().map(mean_luminance).sum::<f64>() / 4.0;
        eprintln!("{sampler:?}: rms {error:.5}, mean {mean:.5} (reference {want:.5})");
        assert!(
            (mean - want).abs() < 0.02 * want,
            "{sampler:?}: {mean} against {want}"
        );
        errors.push(error);
    }
    assert!(
        errors[0] < errors[1],
        "sobol {} against independent {}",
        errors[0],
        errors[1]
    );
}

#[test]
fn adaptive_sampling_converges_to_the_same_mean_and_is_deterministic() {
    let (class, shader, frame) = small_scene();
    let settings = |time_budget| PathSettings {
        bounces: 4,
        seed: 5,
        environment: 0.5,
        sampler: Sampler::Sobol,
        time_budget,
        show_environment: false,
    };
    let uniform = {
        let mut img = PathImage::new(20, 16);
        path_frame(&class, &shader, &frame, &settings(None), &mut img, 256).unwrap()
    };
    // A budget far longer than the passes take: they stop when no pixel below the
    // sample cap is noisy, so the counts, and the image, depend on nothing else.
    let budget = Some(std::time::Duration::from_secs(600));
    let adaptive = |threads| {
        on_threads(threads, || {
            let mut img = PathImage::new(20, 16);
            let image = path_frame(&class, &shader, &frame, &settings(budget), &mut img, 256);
            (image.unwrap(), img.sample_counts().to_vec())
        })
    };
    let (one, counts) = adaptive(1);
    let (two, counts2) = adaptive(2);
    assert_eq!(counts, counts2);
    assert_eq!(one.rgb, two.rgb, "1 thread against 2");
    let (min, max) = (counts.iter().min().unwrap(), counts.iter().max().unwrap());
    let total: u64 = counts.iter().map(|&n| u64::from(n)).sum();
    eprintln!("adaptive: {min}..={max} samples per pixel, {total} in all");
    assert!(*min >= ADAPTIVE_MIN_SAMPLES, "{min}");
    assert!(*max > *min, "every pixel took as many samples: {min}");
    assert!(
        total < 256 * 20 * 16,
        "{total} samples: no fewer than uniform"
    );
    // Pixels still noisy are those at the cap.
    let held = {
        let mut img = PathImage::new(20, 16);
        path_frame(&class, &shader, &frame, &settings(budget), &mut img, 256).unwrap();
        img
    };
    for (i, &n) in counts.iter().enumerate() {
        assert!(n == 256 || held.relative_error(i) <= ADAPTIVE_THRESHOLD);
    }
    let (a, u) = (mean_luminance(&one), mean_luminance(&uniform));
    eprintln!("mean luminance: adaptive {a:.5}, uniform {u:.5}");
    assert!((a - u).abs() < 0.01 * u, "adaptive {a} against uniform {u}");
    // A tiny budget still takes the first pass: one sample per pixel.
    let mut img = PathImage::new(20, 16);
    let tiny = Some(std::time::Duration::from_nanos(1));
    path_frame(&class, &shader, &frame, &settings(tiny), &mut img, 256).unwrap();
    assert_eq!(img.samples(), 1);
    assert_eq!(img.sample_counts().iter().max(), Some(&1));
}

/// The mean radiance (green) of the central 8x8 pixels of a 16x16 `path` frame
/// looking down (superior) at `vol` under a headlight of intensity 1, single
/// scattering, no environment, albedo 1, the surface part under `gate`.
pub(super) fn single_scattering_from_above(vol: &Volume, opacity: f64, gate: f32) -> f64 {
    let class = classify(vol, &white(&[(0.0, 0.0), (1.0, opacity)]));
    let frame = FrameSettings {
        width: 16,
        height: 16,
        camera: glint_core::CameraSpec {
            view: glint_core::View::Superior,
            ..Default::default()
        },
        ..Default::default()
    };
    let shader = albedo_one(vec![Light::HEADLIGHT], gate);
    let settings = PathSettings {
        bounces: 1,
        seed: 2,
        environment: 0.0,
        sampler: Sampler::Sobol,
        time_budget: None,
        show_environment: false,
    };
    let mut img = PathImage::new(16, 16);
    let image = path_frame(&class, &shader, &frame, &settings, &mut img, 256).unwrap();
    let mut sum = 0.0;
    for y in 4..12 {
        for x in 4..12 {
            sum += f64::from(image.rgb[y * 16 + x][1]);
        }
    }
    sum / 64.0
}

#[test]
fn one_light_is_one_irradiance_for_the_medium_and_the_surface() {
    // A light of intensity I is the irradiance E = π·I on both parts.
    // Surface only: a white Lambertian floor facing the light and the camera
    // (gate 0: every sample with a gradient is surface) sends ρ·E·cos/π = I.
    let floor = volume(
        [24, 24, 24],
        [1.0; 3],
        |_, _, k| if k <= 12.0 { 1.0 } else { 0.0 },
    );
    let surface = single_scattering_from_above(&floor, 0.999, 0.0);
    // Medium only: a uniform cube of depth D (gate far above any gradient), seen and
    // lit along its depth, sends by single scattering
    // ∫ σ e^{-σt} · E/(4π) · e^{-σt} dt = I·(1 - e^{-2σD})/8.
    let cube = volume([24, 24, 24], [1.0; 3], |_, _, _| 1.0);
    let medium = single_scattering_from_above(&cube, 0.03, 1e6);
    let tau = -(0.97f64).ln() * 23.0;
    let want = (1.0 - (-2.0 * tau).exp()) / 8.0;
    eprintln!("surface {surface:.4} (want 1); medium {medium:.5} (want {want:.5}, τ {tau:.3})");
    assert!((surface - 1.0).abs() < 0.02, "surface: {surface}");
    assert!(
        (medium - want).abs() < 0.03 * want,
        "medium: {medium} against {want}"
    );
}

#[test]
fn time_budgets_are_checked() {
    for bad in [0.0, -5.0, f64::NAN, f64::INFINITY, MAX_TIME_BUDGET_MS + 1.0] {
        let e = check_time_budget(bad).unwrap_err().to_string();
        assert!(e.contains("time budget") && !e.contains('\n'), "{e}");
    }
    assert_eq!(
        check_time_budget(250.0).unwrap(),
        std::time::Duration::from_millis(250)
    );
}

#[test]
fn shadow_images_are_deterministic_and_the_simd_loop_is_the_scalar_one() {
    // On x86-64 CI and strict runs the AVX2 loop must really run, or this would
    // compare the scalar loop with itself.
    if glint_testkit::strict() && cfg!(target_arch = "x86_64") {
        assert!(
            Kernel::simd_available(),
            "no AVX2+FMA: the SIMD loop is not tested"
        );
    }
    let (class, shader, frame) = small_scene();
    // Several bricks per axis, so a sample's place in the brick pool is not its place
    // in the grid: the AVX2 loop must find its light-volume cell from its brick.
    assert!(class.field().brick_dims.iter().all(|&b| b >= 3));
    for occlusion in [false, true] {
        let sf = class
            .shadow_field(&shader, &frame, &ShadowSettings { occlusion }, None)
            .unwrap();
        assert_eq!(sf.has_occlusion(), occlusion);
        let render = |threads: usize, kernel: Kernel| {
            on_threads(threads, || {
                let f = FrameSettings {
                    kernel,
                    ..frame.clone()
                };
                shadows_frame(&class, &shader, &f, &sf).unwrap()
            })
        };
        let a = render(1, Kernel::Auto);
        let b = render(2, Kernel::Auto);
        let c = render(2, Kernel::Scalar);
        assert_eq!(a.rgb, b.rgb);
        assert_eq!(a.rgb, c.rgb, "SIMD against scalar");
        assert_eq!(a.alpha, c.alpha);
        let local = local_frame(&class, &shader, &frame);
        assert_ne!(a.rgb, local.rgb, "shadows changed nothing");
    }
    // Pre-integrated sampling too.
    let field = class.field().clone();
    let tf = white(&[(0.0, 0.0), (0.5, 0.0), (1.0, 0.5), (1.5, 0.5), (2.0, 1.0)]);
    let pre = Classification::new(
        field,
        &tf,
        &ClassifySettings {
            sampling: Sampling::PreIntegrated,
            ..Default::default()
        },
    )
    .unwrap();
    let sf = pre
        .shadow_field(&shader, &frame, &ShadowSettings::default(), None)
        .unwrap();
    let a = shadows_frame(&pre, &shader, &frame, &sf).unwrap();
    let scalar = FrameSettings {
        kernel: Kernel::Scalar,
        ..frame.clone()
    };
    let b = shadows_frame(&pre, &shader, &scalar, &sf).unwrap();
    assert_eq!(a.rgb, b.rgb, "pre-integrated: SIMD against scalar");
}

#[test]
fn light_volumes_refuse_other_lights_and_mip() {
    let (class, shader, frame) = small_scene();
    let sf = class
        .shadow_field(&shader, &frame, &ShadowSettings::default(), None)
        .unwrap();
    let moved = FrameSettings {
        camera: glint_core::CameraSpec {
            azimuth: 50.0,
            ..frame.camera
        },
        ..frame.clone()
    };
    assert!(shadows_frame(&class, &shader, &moved, &sf).is_err());
    let mip = Classification::new(
        class.field().clone(),
        &white(&[(0.0, 0.0), (2.0, 1.0)]),
        &ClassifySettings {
            mode: RenderMode::Mip,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(shadows_frame(&mip, &shader, &frame, &sf).is_err());
    let mut img = PathImage::new(20, 16);
    let settings = PathSettings {
        bounces: 2,
        seed: 0,
        environment: 1.0,
        sampler: Sampler::default(),
        time_budget: None,
        show_environment: false,
    };
    assert!(path_frame(&mip, &shader, &frame, &settings, &mut img, 1).is_err());
}

/// A uniform slab (32^3 voxels of 1 mm, matter of opacity `alpha` per voxel up to
/// height `top`, none above) and a square mesh (two triangles) at height `z` over
/// `[x0, x1] x [y0, y1]` (world = index here).
fn slab_under_a_square(
    alpha: f64,
    top: f32,
    [x0, x1, y0, y1, z]: [f32; 5],
) -> (Classification, Occluders, [f32; 5]) {
    let vol = volume(
        [32, 32, 32],
        [1.0; 3],
        |_, _, k| if k <= top { 1.0 } else { 0.0 },
    );
    let class = classify(&vol, &white(&[(0.0, 0.0), (0.5, 0.0), (1.0, alpha)]));
    let c = [
        Vec3::new(x0, y0, z),
        Vec3::new(x1, y0, z),
        Vec3::new(x1, y1, z),
        Vec3::new(x0, y1, z),
    ];
    let occ = Occluders::new(class.field(), [[c[0], c[1], c[2]], [c[0], c[2], c[3]]]);
    (class, occ, [x0, x1, y0, y1, z])
}

/// How far `(x, y)` lies inside the square `[x0, x1] x [y0, y1]` (negative: outside).
fn inside_by(q: [f32; 5], x: f32, y: f32) -> f32 {
    let [x0, x1, y0, y1, _] = q;
    (x - x0).min(x1 - x).min(y - y0).min(y1 - y)
}

#[test]
fn a_mesh_casts_its_shadow_into_the_light_volume() {
    let (class, occ, q) = slab_under_a_square(0.05, 31.0, [4.0, 26.0, 6.0, 26.0, 20.3]);
    // The square's cells: grid x 2..=13, y 3..=13 on grid plane z 10 (2-voxel cells,
    // each the box of one grid step around its point).
    assert_eq!(occ.count(), 12 * 11, "occupied grid points");
    assert!(occ.occupied([2, 3, 10]) && occ.occupied([13, 13, 10]));
    assert!(!occ.occupied([1, 3, 10]) && !occ.occupied([2, 3, 11]) && !occ.occupied([2, 3, 9]));
    // Light from straight above (the headlight of a superior view), then from 35
    // degrees aside: the shadow is the square's projection along the light.
    for azimuth in [0.0, 35.0] {
        let frame = FrameSettings {
            width: 8,
            height: 8,
            camera: glint_core::CameraSpec {
                view: glint_core::View::Superior,
                ..Default::default()
            },
            ..Default::default()
        };
        let light = Light {
            azimuth,
            elevation: 0.0,
            intensity: 1.0,
        };
        let shader = albedo_one(vec![light], 0.0);
        let settings = ShadowSettings::default();
        let bare = class
            .shadow_field(&shader, &frame, &settings, None)
            .unwrap();
        let none = class
            .shadow_field(&shader, &frame, &settings, None)
            .unwrap();
        let shaded = class
            .shadow_field(&shader, &frame, &settings, Some(&occ))
            .unwrap();
        let l = shader.placed(&class.camera(&frame).unwrap()).world_lights()[0].0;
        assert!(l.z > 0.8, "{l:?}");
        let (mut dark, mut open) = (0, 0);
        for k in 0..32 {
            for j in 0..32 {
                for i in 0..32 {
                    let p = Vec3::new(i as f32, j as f32, k as f32);
                    let t0 = bare.transmittance(0, p.to_array()).unwrap();
                    let t1 = shaded.transmittance(0, p.to_array()).unwrap();
                    assert_eq!(
                        t0.to_bits(),
                        none.transmittance(0, p.to_array()).unwrap().to_bits()
                    );
                    // Where the ray towards the light crosses the square's plane.
                    let s = (q[4] - p.z) / l.z;
                    let hit = p + l * s;
                    let inside = inside_by(q, hit.x, hit.y);
                    // Margins (mm): a grid cell and the shadow bias for the vertical
                    // light, whose sweep is exact; for the oblique one the sweep's
                    // bilinear blur too (a spread of about 3 mm after 10 planes).
                    let (din, dout) = if azimuth == 0.0 {
                        (1.0, -2.0)
                    } else {
                        (8.0, -10.0)
                    };
                    if s >= 2.3 && inside >= din {
                        assert!(t0 > 0.1, "{p:?}: {t0} without the mesh");
                        assert!(t1 < 0.02, "{p:?} in the shadow: {t1}");
                        dark += 1;
                    } else if s < 0.0 || inside <= dout {
                        let tol = if azimuth == 0.0 { 1e-5 } else { 0.02 };
                        assert!((t1 - t0).abs() <= tol * t0, "{p:?}: {t1} vs {t0}");
                        open += 1;
                    }
                }
            }
        }
        assert!(dark > 200 && open > 10_000, "{dark} dark, {open} open");
    }
}

#[test]
fn a_mesh_shadows_the_path_traced_volume() {
    // The square at z = 30.5 over matter up to z = 26, lit from straight above; the
    // camera looks down through it (camera rays pass: `far` would stop them at a
    // mesh in a scene, here it is not given) onto the slab below. Single scattering:
    // the volume under the square gets no light at all (its collisions' shadow rays
    // all meet the square) and the rest exactly what it had; with 4 bounces, light
    // scattered in from the sides lights the shadow a little and the open part loses
    // what came from under the square.
    let (class, occ, q) = slab_under_a_square(0.1, 26.0, [10.0, 22.0, 10.0, 22.0, 30.5]);
    let frame = FrameSettings {
        width: 24,
        height: 24,
        camera: glint_core::CameraSpec {
            view: glint_core::View::Superior,
            ..Default::default()
        },
        ..Default::default()
    };
    let shader = albedo_one(vec![Light::HEADLIGHT], 0.0);
    let trace = |occluders: Option<&Occluders>, threads: usize, bounces: u32| {
        let settings = PathSettings {
            bounces,
            seed: 21,
            environment: 0.0,
            sampler: Sampler::default(),
            time_budget: None,
            show_environment: false,
        };
        on_threads(threads, || {
            let mut img = PathImage::new(24, 24);
            let target = Transport::Path {
                image: &mut img,
                spp: 24,
                settings,
                occluders,
                environment: None,
                cancel: None,
            };
            class.frame(&shader, &frame, None, target, &|_| {}).unwrap();
            img.image([0.0; 3])
        })
    };
    let cam = class.camera(&frame).unwrap();
    // Sums of the green channel over the pixels whose ray meets the slab's middle
    // (z = 15) 3 mm or more inside the square's shadow, and 6 mm or more outside it.
    let sums = |img: &glint_core::Image| {
        let (mut dark, mut open) = ((0.0f64, 0), (0.0f64, 0));
        for y in 0..24u32 {
            for x in 0..24u32 {
                let (eye, dir) = cam.ray(x as f32, y as f32, 24, 24);
                let at = eye + dir * ((15.0 - eye.z) / dir.z);
                let inside = inside_by(q, at.x, at.y);
                let v = f64::from(img.rgb[(y * 24 + x) as usize][1]);
                let within = |c: f32| (0.0..31.0).contains(&c);
                if inside >= 3.0 {
                    dark = (dark.0 + v, dark.1 + 1);
                } else if inside <= -6.0 && within(at.x) && within(at.y) {
                    open = (open.0 + v, open.1 + 1);
                }
            }
        }
        assert!(dark.1 >= 4 && open.1 >= 20, "{dark:?} dark, {open:?} open");
        (dark.0, open.0)
    };
    for bounces in [1, 4] {
        let bare = trace(None, 2, bounces);
        let shaded = trace(Some(&occ), 2, bounces);
        let again = trace(Some(&occ), 1, bounces);
        let bits =
            |img: &glint_core::Image| img.rgb.iter().map(|c| c[1].to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&shaded), bits(&again), "2 threads against 1");
        let (d0, o0) = sums(&bare);
        let (d1, o1) = sums(&shaded);
        eprintln!("path, {bounces} bounces: shadow {d0} -> {d1}, open {o0} -> {o1}");
        assert!(d0 > 0.0, "the slab is lit without the mesh");
        if bounces == 1 {
            assert!(d1 < 0.02 * d0, "in the shadow: {d1} against {d0}");
            assert!(
                (o1 - o0).abs() <= 1e-9 * o0,
                "in the open: {o1} against {o0}"
            );
        } else {
            assert!(d1 < 0.5 * d0, "in the shadow: {d1} against {d0}");
            assert!(o1 <= o0 && o1 > 0.85 * o0, "in the open: {o1} against {o0}");
        }
    }
}

#[test]
fn ambient_occlusion_treats_clipped_space_as_empty() {
    let (class, shader, frame) = small_scene();
    let field = class.field().clone();
    // A plane through the ball's centre across index axis 0, keeping i >= 24.
    let o = field.index_to_world([24.0, 0.0, 0.0]);
    let e = field.index_to_world([25.0, 0.0, 0.0]);
    let cut = FrameSettings {
        clip: glint_core::Clip {
            planes: vec![glint_core::ClipPlane {
                point: o,
                normal: [0, 1, 2].map(|a| e[a] - o[a]),
            }],
            crop: None,
        },
        ..frame.clone()
    };
    let occlusion = |frame: &FrameSettings| {
        let sf = class
            .shadow_field(&shader, frame, &ShadowSettings { occlusion: true }, None)
            .unwrap();
        move |p: Vec3| sf.at(p, &mut [0.0; glint_core::MAX_LIGHTS])
    };
    let (whole, clipped) = (occlusion(&frame), occlusion(&cut));
    let mut brighter = 0;
    for k in 0..48 {
        for j in 0..48 {
            for i in 24..48 {
                let p = Vec3::new(i as f32, j as f32, k as f32);
                let (a, b) = (whole(p), clipped(p));
                assert!(b >= a - 1e-6, "({i}, {j}, {k}): {b} darker than {a}");
                if i >= 34 {
                    // Beyond the occlusion's reach of the plane: as it was.
                    assert_eq!(a, b, "({i}, {j}, {k})");
                }
                brighter += usize::from(b > a + 0.01);
            }
        }
    }
    // The ball's removed half no longer occludes the kept half and the floor by it.
    assert!(brighter > 100, "{brighter}");
}

/// The `path` model's frame lit by the environment `map` (no meshes).
pub(super) fn path_frame_env(
    class: &Classification,
    shader: &Shader,
    frame: &FrameSettings,
    settings: &PathSettings,
    map: &glint_core::EnvMap,
    spp: u32,
) -> glint_core::Image {
    let mut img = PathImage::new(frame.width, frame.height);
    let transport = Transport::Path {
        image: &mut img,
        spp,
        settings: *settings,
        occluders: None,
        environment: Some(map),
        cancel: None,
    };
    class
        .frame(shader, frame, None, transport, &|_| {})
        .unwrap()
}

#[test]
fn a_constant_environment_map_is_the_uniform_environment() {
    // The white furnace under a constant map: every pixel's radiance is the map's
    // (next-event estimation of the map and the paths that leave, by MIS).
    let vol = volume([16, 16, 16], [1.0; 3], |_, _, _| 1.0);
    let class = classify(&vol, &white(&[(0.0, 0.15)]));
    let env = 0.7f32;
    let map = glint_core::EnvMap::constant([env; 3], 32, 16).unwrap();
    let frame = FrameSettings {
        width: 12,
        height: 12,
        background: [env; 3],
        ..Default::default()
    };
    let shader = Shader::with_specular(
        albedo_one(vec![], 0.0).specular().clone(),
        Geometry::Phong,
        *albedo_one(vec![], 0.0).material(),
        vec![],
        0.0,
    )
    .unwrap()
    .with_anisotropy(0.6)
    .unwrap();
    let settings = PathSettings {
        bounces: MAX_BOUNCES,
        seed: 9,
        environment: 0.0,
        sampler: Sampler::Sobol,
        time_budget: None,
        show_environment: true,
    };
    let image = path_frame_env(&class, &shader, &frame, &settings, &map, 128);
    let mean = image.rgb.iter().map(|c| f64::from(c[1])).sum::<f64>() / 144.0;
    eprintln!("furnace under a constant map: mean {mean:.5}, map {env}");
    assert!(
        (mean - f64::from(env)).abs() < 0.01 * f64::from(env),
        "{mean}"
    );
    // A lit scene of surfaces and medium: the constant map's image has the uniform
    // environment's mean, within the noise.
    let (class, shader, frame) = small_scene();
    let uniform = PathSettings {
        bounces: 4,
        seed: 5,
        environment: 0.5,
        sampler: Sampler::Sobol,
        time_budget: None,
        show_environment: true,
    };
    let mut img = PathImage::new(20, 16);
    let a = path_frame(&class, &shader, &frame, &uniform, &mut img, 64).unwrap();
    let map = glint_core::EnvMap::constant([0.5; 3], 64, 32).unwrap();
    let mapped = PathSettings {
        environment: 0.0,
        ..uniform
    };
    let b = path_frame_env(&class, &shader, &frame, &mapped, &map, 64);
    let (ma, mb) = (mean_luminance(&a), mean_luminance(&b));
    eprintln!("uniform environment {ma:.5}, constant map {mb:.5}");
    assert!((ma - mb).abs() < 0.01 * ma, "{ma} vs {mb}");
}

/// A map of a dim sky and one small bright source (5° in radius, radiance 200) above
/// and to the right.
fn small_source_map() -> glint_core::EnvMap {
    let (w, h) = (128u32, 64u32);
    let c = Vec3::new(0.5, 0.3, 0.81).normalize_or_zero();
    let mut texels = Vec::new();
    for y in 0..h {
        let t = std::f32::consts::PI * (y as f32 + 0.5) / h as f32;
        for x in 0..w {
            let p = std::f32::consts::TAU * (x as f32 + 0.5) / w as f32;
            let d = Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
            let l = if d.dot(c) > 5f32.to_radians().cos() {
                200.0
            } else {
                0.05
            };
            texels.push([l; 3]);
        }
    }
    glint_core::EnvMap::new(w, h, texels).unwrap()
}

#[test]
fn mis_of_the_map_agrees_with_each_strategy_and_is_deterministic() {
    use super::path::EnvStrategy;
    let (class, shader, frame) = small_scene();
    let shader = Shader::with_specular(
        shader.specular().clone(),
        Geometry::Blinn,
        *shader.material(),
        vec![],
        shader.gate(),
    )
    .unwrap()
    .with_anisotropy(0.3)
    .unwrap();
    let map = small_source_map();
    let settings = PathSettings {
        bounces: 3,
        seed: 2,
        environment: 0.0,
        sampler: Sampler::Independent,
        time_budget: None,
        show_environment: false,
    };
    let camera = class.camera(&frame).unwrap();
    let placed = shader.placed(&camera);
    let size = [frame.width, frame.height];
    let spp = 48u32;
    // Per strategy: the mean over the pixels and samples of the radiance's green
    // channel, and the variance of one sample (over samples, within each pixel).
    let run = |strategy: EnvStrategy| {
        let mut tracer = PathTracer::new(
            class.field(),
            class.medium(),
            &placed,
            camera,
            size,
            settings,
        )
        .unwrap()
        .lit_by(Some(&map));
        tracer.env_strategy = strategy;
        green_mean_and_variance(&tracer, size, spp)
    };
    let (mis, var_mis) = run(EnvStrategy::Mis);
    let (light, var_light) = run(EnvStrategy::Light);
    let (scatter, var_scatter) = run(EnvStrategy::Scatter);
    eprintln!(
        "path under a small source: mean MIS {mis:.4}, light {light:.4}, scattering {scatter:.4}; \
         variance per sample MIS {var_mis:.4}, light {var_light:.4}, scattering {var_scatter:.4}"
    );
    // Standard errors of the means over all samples (pixels independent).
    let n = f64::from(size[0] * size[1] * spp);
    let se = |v: f64| (v / n).sqrt();
    assert!(mis > 0.01, "{mis}");
    for (name, m, v) in [
        ("light", light, var_light),
        ("scattering", scatter, var_scatter),
    ] {
        let tol = 4.0 * (se(v) + se(var_mis));
        assert!((m - mis).abs() < tol, "{name}: {m} vs MIS {mis} (±{tol})");
    }
    assert!(var_mis < var_scatter, "{var_mis} vs {var_scatter}");
    // The same image on any thread count, with the map.
    let sobol = PathSettings {
        sampler: Sampler::Sobol,
        ..settings
    };
    let img = |threads| {
        on_threads(threads, || {
            path_frame_env(&class, &shader, &frame, &sobol, &map, 4)
        })
    };
    let (one, two) = (img(1), img(2));
    assert_eq!(one.rgb, two.rgb);
    assert!(mean_luminance(&one) > 0.0);
}

#[test]
fn roulette_on_the_maps_shadow_rays_keeps_the_mean() {
    // Russian roulette on the map's shadow rays (`env_survival`) divides the rays it
    // keeps by their survival probability: the mean is that of tracing every one,
    // within the noise, at the default threshold and at one eight times higher (where
    // most rays are played, so the variance visibly grows: the roulette acts).
    let (class, shader, frame) = small_scene();
    let map = small_source_map();
    let settings = PathSettings {
        bounces: 3,
        seed: 4,
        environment: 0.0,
        sampler: Sampler::Independent,
        time_budget: None,
        show_environment: false,
    };
    let camera = class.camera(&frame).unwrap();
    let placed = shader.placed(&camera);
    let size = [frame.width, frame.height];
    let spp = 48u32;
    let run = |threshold: f32| {
        let mut tracer = PathTracer::new(
            class.field(),
            class.medium(),
            &placed,
            camera,
            size,
            settings,
        )
        .unwrap()
        .lit_by(Some(&map));
        tracer.env_roulette = threshold;
        green_mean_and_variance(&tracer, size, spp)
    };
    let (all, var_all) = run(0.0);
    let (default, var_default) = run(super::path::ENV_ROULETTE);
    let (heavy, var_heavy) = run(8.0 * super::path::ENV_ROULETTE);
    eprintln!(
        "map shadow-ray roulette: mean every ray {all:.4}, default {default:.4}, 8x {heavy:.4}; \
         variance per sample {var_all:.4}, {var_default:.4}, {var_heavy:.4}"
    );
    let n = f64::from(size[0] * size[1] * spp);
    let se = |v: f64| (v / n).sqrt();
    assert!(all > 0.01, "{all}");
    for (name, m, v) in [("default", default, var_default), ("8x", heavy, var_heavy)] {
        let tol = 4.0 * (se(v) + se(var_all));
        assert!((m - all).abs() < tol, "{name}: {m} vs {all} (±{tol})");
    }
    assert!(var_heavy > var_all, "{var_heavy} vs {var_all}");
}

/// The mean over the pixels of `size` of each pixel's mean green radiance over `spp`
/// samples of `tracer`, and the mean of the pixels' sample variances.
pub(super) fn green_mean_and_variance(
    tracer: &PathTracer<'_>,
    size: [u32; 2],
    spp: u32,
) -> (f64, f64) {
    let (mut sum, mut var) = (0.0f64, 0.0f64);
    for y in 0..size[1] {
        for x in 0..size[0] {
            let v: Vec<f64> = (0..spp)
                .map(|s| f64::from(tracer.trace(x, y, s, f32::INFINITY).radiance[1]))
                .collect();
            let m = v.iter().sum::<f64>() / f64::from(spp);
            sum += m;
            var += v.iter().map(|a| (a - m) * (a - m)).sum::<f64>() / f64::from(spp - 1);
        }
    }
    let pixels = f64::from(size[0] * size[1]);
    (sum / pixels, var / pixels)
}
