//! Rendered images against answers derived independently of the renderer: Beer-Lambert
//! absorption through a uniform slab, the analytic position and shape of a sphere's
//! highlight for each geometry, the projected area of the phantom's skull in a MIP.

use glint_io::{Samples, Volume};
use glint_lobe::{Geometry, Lobe, LobeKind};
use glint_render::{
    phantom, Camera, CameraSpec, Depth, Input, Kernel, Light, LobeSpec, MaterialOverrides,
    Projection, ReadOptions, RenderMode, Rendered, Renderer, Sampling, Scene, TransferFunction,
    View,
};

fn ortho(view: View) -> CameraSpec {
    CameraSpec {
        view,
        projection: Projection::Orthographic,
        ..Default::default()
    }
}

/// Unshaded, the transfer function's colour as it is.
fn flat_material() -> MaterialOverrides {
    MaterialOverrides {
        ambient: Some(1.0),
        diffuse: Some(0.0),
        specular: Some(0.0),
        shade: Some(false),
    }
}

/// A scene of `size` pixels with the defaults otherwise.
fn scene(width: u32, height: u32) -> Scene {
    Scene {
        size: [width, height],
        ..Scene::default()
    }
}

/// The lobe `kind` with shininess `n`, v = 4.
fn lobe(kind: LobeKind, n: f64, geometry: Geometry) -> LobeSpec {
    LobeSpec {
        kind: kind.into(),
        n: Some(n),
        v: 4,
        geometry,
        hw: None,
    }
}

/// Renders `scene` of `volume` with a fresh renderer.
fn render(volume: &Volume, scene: &Scene) -> Rendered {
    Renderer::from_source(volume.clone(), None)
        .unwrap()
        .render(scene, &|_| {})
        .unwrap()
}

/// The camera a render of `scene` of `volume` uses.
fn camera(volume: &Volume, scene: &Scene) -> Camera {
    Renderer::from_source(volume.clone(), None)
        .unwrap()
        .camera(scene)
        .unwrap()
}

/// The Shepp-Logan phantom at `n`^3.
fn shepp_logan(n: usize) -> Volume {
    phantom::shepp_logan(n).unwrap()
}

/// A `n`^3 volume of 1 mm voxels, value 1 everywhere.
fn uniform(n: usize) -> Volume {
    Volume::new([n; 3], [1.0; 3], Samples::F32(vec![1.0; n * n * n])).unwrap()
}

#[test]
fn composite_follows_beer_lambert_for_any_step() {
    // Opacity a per voxel of distance through L voxels gives 1 - (1 - a)^L whatever
    // the step (Max 1995, "Optical models for direct volume rendering"). The central
    // ray of an orthographic view crosses the whole 33-voxel cube: L = 32.
    let volume = uniform(33);
    let a = 0.05;
    let tf = TransferFunction::from_flat(&[0.0, a, 2.0, a], &[0.0, 1.0, 1.0, 1.0]).unwrap();
    let expect = 1.0 - (1.0f64 - a).powf(32.0);
    for step in [1.0, 0.5, 0.25, 0.1] {
        let scene = Scene {
            step,
            camera: ortho(View::Anterior),
            transfer_function: Some(tf.clone()),
            material: flat_material(),
            ..scene(33, 33)
        };
        let img = render(&volume, &scene).image;
        let got = img.alpha[16 * 33 + 16] as f64;
        // The samples cover L to within one step.
        let slack = (1.0 - a).powf(32.0) * (1.0 - (1.0 - a).powf(step)) + 1e-4;
        assert!(
            (got - expect).abs() <= slack,
            "step {step}: {got} vs {expect}"
        );
        // White colour on black: linear value equals the opacity.
        assert!((img.pixel(16, 16)[0] as f64 - got).abs() < 1e-5);
    }
}

#[test]
fn the_opacity_unit_sets_the_length_the_opacity_is_for() {
    // 2 mm voxels: 32 voxels are 64 mm of matter. By default the opacity a is per
    // voxel (1 - (1 - a)^32 across); for a unit of 1 mm it is per mm (1 - (1 - a)^64);
    // a unit of one voxel's 2 mm is the default, to the byte.
    let n = 33;
    let volume = Volume::new([n; 3], [2.0; 3], Samples::F32(vec![1.0; n * n * n])).unwrap();
    let a = 0.03;
    let tf = TransferFunction::from_flat(&[0.0, a, 2.0, a], &[0.0, 1.0, 1.0, 1.0]).unwrap();
    let base = Scene {
        camera: ortho(View::Anterior),
        transfer_function: Some(tf),
        material: flat_material(),
        ..scene(33, 33)
    };
    let alpha = |unit: Option<f64>| {
        let img = render(
            &volume,
            &Scene {
                opacity_unit: unit,
                ..base.clone()
            },
        )
        .image;
        (
            img.alpha[16 * 33 + 16] as f64,
            img.encode_png(Depth::Eight).unwrap(),
        )
    };
    let (by_voxel, png) = alpha(None);
    let (per_mm, _) = alpha(Some(1.0));
    let (per_two_mm, png2) = alpha(Some(2.0));
    assert!(
        (by_voxel - (1.0 - (1.0f64 - a).powf(32.0))).abs() < 5e-3,
        "{by_voxel}"
    );
    assert!(
        (per_mm - (1.0 - (1.0f64 - a).powf(64.0))).abs() < 5e-3,
        "{per_mm}"
    );
    assert_eq!(png, png2);
    assert_eq!(by_voxel, per_two_mm);
    // Nonsense units are refused.
    let mut renderer = Renderer::from_source(volume.clone(), None).unwrap();
    for bad in [0.0, -1.0, f64::NAN, 1e9] {
        let scene = Scene {
            opacity_unit: Some(bad),
            ..base.clone()
        };
        assert!(renderer.render(&scene, &|_| {}).is_err(), "{bad}");
    }
}

#[test]
fn a_shell_thinner_than_a_step_is_integrated_not_sampled() {
    // The value rises 0.1 per voxel towards the viewer and the transfer function is
    // opaque only on [2.0, 2.02]: a shell a fifth of a voxel thick, thinner than the
    // half-voxel step, crossed by every ray at a different phase (jitter). Point
    // sampling gives a ray 0 or a whole step's opacity depending on whether a sample
    // lands in the shell; pre-integration gives every ray the shell's optical depth
    // (Engel et al. 2001), here computed from the transfer function alone.
    let n = 64;
    let mut v = Vec::with_capacity(n * n * n);
    for _k in 0..n {
        for j in 0..n {
            v.extend(std::iter::repeat_n(0.1 * j as f32, n));
        }
    }
    let volume = Volume::new([n; 3], [1.0; 3], Samples::F32(v)).unwrap();
    let opacity = [
        0.0, 0.0, 1.999, 0.0, 2.0, 0.99, 2.02, 0.99, 2.021, 0.0, 10.0, 0.0,
    ];
    let tf = TransferFunction::from_flat(&opacity, &[0.0, 1.0, 1.0, 1.0]).unwrap();
    // Optical depth through the shell: the integral of -ln(1 - alpha) over the value,
    // divided by the value's rise per voxel.
    let dv = 1e-5;
    let depth: f64 = (0..(0.1 / dv) as usize)
        .map(|i| -(1.0 - tf.opacity_at(1.95 + (i as f64 + 0.5) * dv)).ln() * dv)
        .sum::<f64>()
        / 0.1;
    let expect = 1.0 - (-depth).exp();
    let mut scene = Scene {
        camera: ortho(View::Anterior),
        transfer_function: Some(tf),
        material: flat_material(),
        prefilter: glint_render::Prefilter::None,
        sampling: Sampling::PreIntegrated,
        ..scene(48, 48)
    };
    let mut renderer = Renderer::from_source(volume.clone(), None).unwrap();
    let mut centre_alpha = |scene: &Scene| {
        let img = renderer.render(scene, &|_| {}).unwrap().image;
        (12..36)
            .flat_map(|y| (12..36).map(move |x| (x, y)))
            .map(|(x, y)| img.alpha[y * 48 + x] as f64)
            .fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)))
    };
    let (lo, hi) = centre_alpha(&scene);
    assert!(
        hi - lo < 1e-3,
        "alpha from {lo} to {hi}: depends on the phase"
    );
    // Point sampling hits or misses the shell.
    scene.sampling = Sampling::Point;
    let (plo, phi) = centre_alpha(&scene);
    assert!(
        plo < 0.01 && phi > 0.8,
        "point-sampled alpha from {plo} to {phi}"
    );
    // The table holds 4096 bins over the value range, each taking its nearest entry's
    // opacity: the shell's two edges may move by half a bin each, at most one bin of
    // full extinction (-ln 0.01 per voxel) in all.
    let bin = 6.3 / 4095.0;
    let slack = bin * -(0.01f64.ln()) / 0.1;
    let (min, max) = (1.0 - (slack - depth).exp(), 1.0 - (-slack - depth).exp());
    assert!(
        (min..=max).contains(&lo),
        "alpha {lo}, shell's {expect} (depth {depth} +- {slack})"
    );
}

/// A sphere of radius `r` voxels as a signed distance (positive inside) on `n`^3.
fn sphere(n: usize, r: f32) -> Volume {
    let c = (n - 1) as f32 / 2.0;
    let mut v = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let d = ((i as f32 - c).powi(2) + (j as f32 - c).powi(2) + (k as f32 - c).powi(2))
                    .sqrt();
                v.push(r - d);
            }
        }
    }
    Volume::new([n; 3], [1.0; 3], Samples::F32(v)).unwrap()
}

#[test]
fn sphere_highlight_matches_the_analytic_answer_for_each_geometry() {
    let (n, r, size) = (72usize, 30.0f32, 160u32);
    let volume = sphere(n, r);
    let tf =
        TransferFunction::from_flat(&[-100.0, 1.0, 100.0, 1.0], &[0.0, 1.0, 1.0, 1.0]).unwrap();
    let side = Light {
        azimuth: 35.0,
        elevation: 20.0,
        intensity: 1.0,
    };
    let base = Scene {
        mode: RenderMode::Iso,
        iso: Some(0.0),
        camera: ortho(View::Anterior),
        transfer_function: Some(tf),
        lights: vec![side],
        material: MaterialOverrides {
            ambient: Some(0.0),
            diffuse: Some(0.0),
            specular: Some(1.0),
            shade: Some(true),
        },
        gate: 0.0,
        ..scene(size, size)
    };
    let cam = camera(&volume, &base);
    let light = side.direction(&cam);
    let view = -cam.forward;
    let center = (n - 1) as f32 / 2.0; // world = index for 1 mm voxels at the origin
    for geometry in [Geometry::Phong, Geometry::Blinn] {
        let scene = Scene {
            lobe: lobe(LobeKind::Exact, 60.0, geometry),
            ..base.clone()
        };
        let img = render(&volume, &scene).image;
        // Pixel of a world point in this orthographic camera.
        let to_pixel = |p: [f32; 3]| {
            let d = [p[0] - cam.eye.x, p[1] - cam.eye.y, p[2] - cam.eye.z];
            let u = d[0] * cam.right.x + d[1] * cam.right.y + d[2] * cam.right.z;
            let v = d[0] * cam.up.x + d[1] * cam.up.y + d[2] * cam.up.z;
            (
                (u / cam.half_height + 1.0) * size as f32 / 2.0 - 0.5,
                (1.0 - v / cam.half_height) * size as f32 / 2.0 - 0.5,
            )
        };
        // Both geometries peak where the normal is the half vector H = (L+V)/|L+V|.
        let h = (light + view).normalize_or_zero();
        let (px, py) = to_pixel([center + r * h.x, center + r * h.y, center + r * h.z]);
        let (mut best, mut bx, mut by) = (0.0f32, 0, 0);
        for y in 0..size {
            for x in 0..size {
                let v = img.pixel(x, y)[0];
                if v > best {
                    (best, bx, by) = (v, x, y);
                }
            }
        }
        let dist = ((bx as f32 - px).powi(2) + (by as f32 - py).powi(2)).sqrt();
        assert!(
            dist <= 2.0,
            "{geometry}: peak at ({bx},{by}), analytic ({px:.1},{py:.1})"
        );
        assert!(best > 0.95 && best <= 1.0, "{geometry}: peak {best}");

        // On the lobe's shoulder (analytic value 0.25 .. 0.75), each pixel shows
        // lobe(cos γ) for the sphere's analytic normal there (the view vector per sample
        // is exact for orthographic rays), within a bound derived from the lobe: an
        // error δ in the normal moves γ by at most δ (Blinn: the angle to H) or 2δ
        // (Phong: the reflected light turns twice as far), and cos^n changes by
        // |d f/dγ| = f n tan γ per radian. δ = NORMAL_ERROR is what the volume's
        // gradient normals (central differences of a 72^3 sampled sphere) may be off.
        // A renderer returning 0, or another exponent, off the peak fails: the bound is
        // under half the value everywhere it is checked.
        const NORMAL_ERROR: f64 = 0.1_f64.to_radians();
        let n_exp = 60.0;
        let turns = if geometry == Geometry::Phong {
            2.0
        } else {
            1.0
        };
        let lobe = Lobe::<f64>::new(LobeKind::Exact, n_exp, 4).unwrap();
        let (mut checked, mut worst) = (0, 0.0f64);
        for dy in -30i32..=30 {
            for dx in -30i32..=30 {
                let (x, y) = (px.round() as i32 + dx, py.round() as i32 + dy);
                if x < 0 || y < 0 || x >= size as i32 || y >= size as i32 {
                    continue;
                }
                let (x, y) = (x as u32, y as u32);
                // Back-project the pixel centre onto the sphere.
                let scale = cam.half_height * 2.0 / size as f32;
                let u = (x as f32 + 0.5 - size as f32 / 2.0) * scale;
                let v = (size as f32 / 2.0 - y as f32 - 0.5) * scale;
                let c = cam.eye + cam.right * u + cam.up * v;
                let oc = [c.x - center, c.y - center, c.z - center];
                let f = cam.forward;
                let b = oc[0] * f.x + oc[1] * f.y + oc[2] * f.z;
                let cc = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - r * r;
                let disc = b * b - cc;
                if disc <= 0.0 {
                    continue;
                }
                let t = -b - disc.sqrt();
                let normal = [
                    (oc[0] + t * f.x) as f64,
                    (oc[1] + t * f.y) as f64,
                    (oc[2] + t * f.z) as f64,
                ];
                let l = [light.x as f64, light.y as f64, light.z as f64];
                let vv = [view.x as f64, view.y as f64, view.z as f64];
                let cos = geometry.cos(normal, l, vv);
                let expect = lobe.eval(cos);
                if !(0.25..=0.75).contains(&expect) {
                    continue;
                }
                let slope = expect * n_exp * (1.0 - cos * cos).sqrt() / cos * turns;
                let bound = slope * NORMAL_ERROR;
                assert!(
                    bound < 0.5 * expect,
                    "the bound would not bite: {bound} at {expect}"
                );
                let got = img.pixel(x, y)[0] as f64;
                assert!(
                    (got - expect).abs() <= bound,
                    "{geometry} at ({x},{y}): {got} vs analytic {expect}, bound {bound}"
                );
                worst = worst.max((got - expect).abs() / slope);
                checked += 1;
            }
        }
        // The shoulder is a ring several pixels wide around the peak.
        assert!(checked >= 40, "{geometry}: only {checked} shoulder pixels");
        eprintln!(
            "{geometry}: {checked} shoulder pixels, worst error as a normal error {:.3} degrees",
            worst.to_degrees()
        );
    }
}

#[test]
fn no_lobe_gives_nan_pixels() {
    let mut renderer = Renderer::from_source(shepp_logan(40), None).unwrap();
    for (mode, iso) in [(RenderMode::Composite, None), (RenderMode::Iso, Some(0.5))] {
        let lights = vec![
            Light::HEADLIGHT,
            Light {
                azimuth: 80.0,
                elevation: -60.0,
                intensity: 1.0,
            },
        ];
        for &kind in LobeKind::ALL {
            for n in [0.0, 1.0, 100.0, 10_000.0] {
                for geometry in [Geometry::Phong, Geometry::Blinn] {
                    let scene = Scene {
                        mode,
                        iso,
                        lights: lights.clone(),
                        lobe: lobe(kind, n, geometry),
                        gate: 0.0,
                        ..scene(40, 40)
                    };
                    let img = renderer.render(&scene, &|_| {}).unwrap().image;
                    assert!(
                        img.rgb.iter().flatten().all(|c| c.is_finite() && *c >= 0.0),
                        "{kind} n={n} {geometry} {mode:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn phantom_mip_silhouette_has_the_skulls_projected_area() {
    // Anterior orthographic MIP: every ray through the outer ellipsoid meets the skull
    // (value 1), so the pixels above 0.5 cover the ellipse of semi-axes 0.69 (x) and
    // 0.81 (z) phantom units: area π·0.69·0.81.
    let volume = shepp_logan(96);
    let tf = TransferFunction::from_flat(&[0.0, 0.0, 1.0, 1.0], &[0.0, 1.0, 1.0, 1.0]).unwrap();
    let size = 200u32;
    let scene = Scene {
        mode: RenderMode::Mip,
        camera: ortho(View::Anterior),
        transfer_function: Some(tf),
        material: flat_material(),
        ..scene(size, size)
    };
    let cam = camera(&volume, &scene);
    let img = render(&volume, &scene).image;
    let bright = img.rgb.iter().filter(|p| p[0] > 0.5).count() as f64;
    let pixel_mm = 2.0 * cam.half_height as f64 / size as f64;
    let area_mm2 = std::f64::consts::PI * 69.0 * 81.0;
    let expect = area_mm2 / (pixel_mm * pixel_mm);
    assert!(
        (bright - expect).abs() / expect < 0.03,
        "{bright} bright pixels, analytic {expect:.0}"
    );
}

#[test]
fn empty_space_skipping_never_changes_the_image() {
    // Skipping covers the leaps over empty macro cells and the rays' start bounds from
    // the projected non-empty blocks; with it off, every sample inside the volume is
    // taken. Off-centre, zoomed views put block footprints across tile borders and
    // partly off the image.
    let mut renderer = Renderer::from_source(shepp_logan(48), None).unwrap();
    for (projection, sampling) in [
        (Projection::Perspective, Sampling::Point),
        (Projection::Orthographic, Sampling::Point),
        (Projection::Perspective, Sampling::PreIntegrated),
        (Projection::Orthographic, Sampling::PreIntegrated),
    ] {
        for zoom in [1.0, 2.5] {
            for (mode, iso) in [
                (RenderMode::Composite, None),
                (RenderMode::Iso, Some(0.5)),
                (RenderMode::Mip, None),
            ] {
                let mut scene = Scene {
                    mode,
                    iso,
                    preset: Some("phantom".into()),
                    camera: CameraSpec {
                        azimuth: 33.0,
                        elevation: -21.0,
                        zoom,
                        projection,
                        ..Default::default()
                    },
                    lobe: lobe(LobeKind::EnergyFit, 40.0, Geometry::Blinn),
                    gate: 0.0,
                    sampling,
                    ..scene(48, 40)
                };
                let fast = renderer.render(&scene, &|_| {}).unwrap().image;
                scene.skip_empty = false;
                let slow = renderer.render(&scene, &|_| {}).unwrap().image;
                let what = format!("{mode:?} {projection:?} {sampling:?} zoom {zoom}");
                assert_eq!(fast.rgb, slow.rgb, "{what}");
                assert_eq!(fast.alpha, slow.alpha, "{what}");
                let covered = fast.alpha.iter().filter(|&&a| a > 0.0).count();
                assert!(covered > 20, "{what}: {covered} pixels");
                if mode == RenderMode::Composite {
                    assert!(fast.stats.samples < slow.stats.samples, "{what}");
                }
            }
        }
    }
}

#[test]
fn progress_reports_every_pixel() {
    use std::sync::atomic::{AtomicU64, Ordering};
    let scene = scene(37, 23);
    let done = AtomicU64::new(0);
    Renderer::from_source(shepp_logan(16), None)
        .unwrap()
        .render(&scene, &|n| {
            done.fetch_add(n, Ordering::Relaxed);
        })
        .unwrap();
    assert_eq!(done.load(Ordering::Relaxed), 37 * 23);
}

#[test]
fn simd_loop_gives_the_scalar_loops_image() {
    // CI runs on x86-64 machines with AVX2 and FMA: there the SIMD loop must really run,
    // or this test would compare the scalar loop with itself.
    if glint_testkit::strict() && cfg!(target_arch = "x86_64") {
        assert!(
            Kernel::simd_available(),
            "no AVX2+FMA: the SIMD loop is not tested"
        );
    }
    let mut renderer = Renderer::from_source(shepp_logan(48), None).unwrap();
    for projection in [Projection::Perspective, Projection::Orthographic] {
        let lights = vec![
            Light::HEADLIGHT,
            Light {
                azimuth: 50.0,
                elevation: 30.0,
                intensity: 0.7,
            },
        ];
        for &kind in LobeKind::ALL {
            for geometry in [Geometry::Phong, Geometry::Blinn] {
                // A gate of 0.5 value/mm (the phantom's range is 1) blends
                // weak-gradient samples towards flat.
                for (gate, sampling) in [
                    (0.0, Sampling::Point),
                    (0.5, Sampling::Point),
                    (0.0, Sampling::PreIntegrated),
                    (0.5, Sampling::PreIntegrated),
                ] {
                    let scene = Scene {
                        sampling,
                        camera: CameraSpec {
                            azimuth: 33.0,
                            elevation: -21.0,
                            projection,
                            ..Default::default()
                        },
                        lights: lights.clone(),
                        lobe: lobe(kind, 60.0, geometry),
                        gate,
                        ..scene(48, 40)
                    };
                    renderer.kernel = Kernel::Auto;
                    let fast = renderer.render(&scene, &|_| {}).unwrap().image;
                    renderer.kernel = Kernel::Scalar;
                    let slow = renderer.render(&scene, &|_| {}).unwrap().image;
                    let what = format!("{kind} {geometry} gate {gate} {sampling:?} {projection:?}");
                    assert_eq!(fast.alpha, slow.alpha, "{what}");
                    assert_eq!(fast.stats.shaded, slow.stats.shaded, "{what}");
                    if matches!(kind, LobeKind::Exact | LobeKind::Gauss) {
                        // Vectorised pow/exp: within 2 ulp of libm per lobe value.
                        let worst = fast
                            .rgb
                            .iter()
                            .flatten()
                            .zip(slow.rgb.iter().flatten())
                            .map(|(a, b)| (a - b).abs())
                            .fold(0.0f32, f32::max);
                        assert!(worst < 1e-5, "{what}: {worst}");
                    } else {
                        assert_eq!(fast.rgb, slow.rgb, "{what}");
                    }
                    assert!(fast.alpha.iter().any(|&a| a > 0.5), "{what}: empty image");
                }
            }
        }
    }
}

#[test]
fn simd_rays_are_the_scalar_rays_on_axis_aligned_views() {
    // The SIMD loop sets up eight rays at once; the scalar loop one at a time. Views
    // along the axes give rays that do not move along two axes (orthographic: every
    // ray; perspective: the central ones), and 37x23 pixels leave partial tiles.
    let mut renderer = Renderer::from_source(shepp_logan(40), None).unwrap();
    for view in [View::Left, View::Anterior, View::Superior] {
        for projection in [Projection::Orthographic, Projection::Perspective] {
            let scene = Scene {
                camera: CameraSpec {
                    view,
                    projection,
                    ..Default::default()
                },
                lobe: lobe(LobeKind::EnergyFit, 40.0, Geometry::Phong),
                ..scene(37, 23)
            };
            renderer.kernel = Kernel::Auto;
            let fast = renderer.render(&scene, &|_| {}).unwrap().image;
            renderer.kernel = Kernel::Scalar;
            let slow = renderer.render(&scene, &|_| {}).unwrap().image;
            let what = format!("{view:?} {projection:?}");
            assert_eq!(fast.alpha, slow.alpha, "{what}");
            assert_eq!(fast.rgb, slow.rgb, "{what}");
            assert_eq!(fast.stats.shaded, slow.stats.shaded, "{what}");
            assert!(fast.alpha.iter().any(|&a| a > 0.5), "{what}: empty image");
        }
    }
}

#[test]
fn simd_tricubic_is_the_scalar_tricubic_within_rounding() {
    // The SIMD loop evaluates the B-spline from its 64 taps read as 16 four-wide rows
    // per sample, the scalar loop tap by tap: the same spline up to float rounding, so the same
    // image within a small tolerance, in `local` and `shadows`, point sampled and
    // pre-integrated, with the gradients (and so the shading) the scalar loop's.
    let mut renderer = Renderer::from_source(shepp_logan(40), None).unwrap();
    for model in [
        glint_render::LightingModel::Local,
        glint_render::LightingModel::Shadows,
    ] {
        for sampling in [Sampling::Point, Sampling::PreIntegrated] {
            let scene = Scene {
                sampling,
                filter: glint_render::Filter::Tricubic,
                camera: CameraSpec {
                    azimuth: 33.0,
                    elevation: -21.0,
                    ..Default::default()
                },
                lighting: glint_render::Lighting {
                    model,
                    ..Default::default()
                },
                lobe: lobe(LobeKind::EnergyFit, 40.0, Geometry::Phong),
                ..scene(45, 37)
            };
            renderer.kernel = Kernel::Auto;
            let fast = renderer.render(&scene, &|_| {}).unwrap().image;
            renderer.kernel = Kernel::Scalar;
            let slow = renderer.render(&scene, &|_| {}).unwrap().image;
            let what = format!("{model:?} {sampling:?}");
            let worst = |a: &[f32], b: &[f32]| {
                a.iter()
                    .zip(b)
                    .map(|(x, y)| (x - y).abs())
                    .fold(0.0f32, f32::max)
            };
            let (fa, sa) = (fast.rgb.concat(), slow.rgb.concat());
            assert!(worst(&fa, &sa) < 1e-3, "{what}: rgb {}", worst(&fa, &sa));
            let wa = worst(&fast.alpha, &slow.alpha);
            assert!(wa < 1e-3, "{what}: alpha {wa}");
            assert!(fast.alpha.iter().any(|&a| a > 0.5), "{what}: empty image");
        }
    }
}

/// The MNI152 T1 template from scripts/fetch-samples, or `None` when it is missing
/// outside strict mode (glint_testkit; in strict mode a missing sample fails the test).
fn mni152() -> Option<Volume> {
    let path = glint_testkit::sample("mni152_t1_09a.nii.gz")?;
    Some(glint_io::read_volume(&path, &glint_io::ReadOptions::default()).unwrap())
}

#[test]
fn mni152_brain_renders_the_same_with_every_shortcut_off() {
    // The benchmark scene at a small size: the SIMD loop against the scalar one, and
    // skipping (leaps, start bounds) against none, on real data; then the picture:
    // a brain filling much of the frame, shaded (not flat), with highlights.
    let Some(volume) = mni152() else { return };
    let scene = Scene {
        input: Input::Path("mni152.nii.gz".into()),
        preset: Some("mr-t2-brain".into()),
        camera: CameraSpec {
            view: View::Left,
            ..Default::default()
        },
        gate: 0.0,
        ..scene(80, 80)
    };
    let mut renderer = Renderer::from_source(volume.clone(), None).unwrap();
    let fast = renderer.render(&scene, &|_| {}).unwrap().image;
    renderer.kernel = Kernel::Scalar;
    let reference = renderer.render(&scene, &|_| {}).unwrap().image;
    renderer.kernel = Kernel::Auto;
    assert_eq!(fast.rgb, reference.rgb);
    assert_eq!(fast.alpha, reference.alpha);
    let no_skip = Scene {
        skip_empty: false,
        ..scene.clone()
    };
    let slow = renderer.render(&no_skip, &|_| {}).unwrap().image;
    assert_eq!(fast.rgb, slow.rgb);
    assert!(fast.stats.samples * 4 < slow.stats.samples);

    let lum: Vec<f32> = fast
        .rgb
        .iter()
        .zip(&fast.alpha)
        .filter(|(_, &a)| a > 0.5)
        .map(|(c, _)| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2])
        .collect();
    let covered = lum.len() as f32 / fast.alpha.len() as f32;
    assert!(
        (0.3..0.85).contains(&covered),
        "brain covers {covered} of the frame"
    );
    let mean = lum.iter().sum::<f32>() / lum.len() as f32;
    let sd = (lum.iter().map(|l| (l - mean).powi(2)).sum::<f32>() / lum.len() as f32).sqrt();
    let max = lum.iter().cloned().fold(0.0, f32::max);
    assert!(sd > 0.1 * mean, "flat shading: mean {mean}, sd {sd}");
    assert!(
        max > mean + 2.0 * sd,
        "no highlight: mean {mean}, sd {sd}, max {max}"
    );
}

/// Ring measure the Shepp-Logan phantom's image (its `phantom` preset, 512x512,
/// anterior, step 0.5) stays under with pre-integrated sampling. Measured 0.88
/// (examples/rings.rs); point-sampled, the same image measured 1.23, its wood grain
/// the thin shells that samples half a voxel apart hit or miss.
const SHEPP_LOGAN_RING_BOUND: f64 = 1.0;

#[test]
fn pre_integration_takes_the_slicing_rings_off_the_shepp_logan_phantom() {
    let mut scene = Scene {
        sampling: Sampling::PreIntegrated,
        ..Scene::phantom(
            phantom::Phantom::SheppLogan,
            phantom::Phantom::DEFAULT_SIZE,
            Scene::default().size,
        )
    };
    let mut renderer = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    let rendered = renderer.render(&scene, &|_| {}).unwrap();
    assert_eq!(rendered.scene.preset.as_deref(), Some("phantom"));
    assert_eq!(rendered.scene.step, 0.5);
    let m = rendered.image.ring_measure().unwrap();
    assert!(m < SHEPP_LOGAN_RING_BOUND, "ring measure {m}");
    scene.sampling = Sampling::Point;
    let point = renderer.render(&scene, &|_| {}).unwrap().image;
    let mp = point.ring_measure().unwrap();
    assert!(
        mp > SHEPP_LOGAN_RING_BOUND,
        "point-sampled ring measure {mp}"
    );
}

/// The default scene ([`Scene::default`]: the head phantom with its preset, 512x512,
/// anterior, step 0.5, headlight).
fn default_image() -> glint_render::Image {
    let scene = Scene::default();
    assert_eq!(
        scene.input,
        Input::Phantom {
            name: phantom::Phantom::Head,
            size: phantom::Phantom::DEFAULT_SIZE
        }
    );
    Renderer::open(&scene, &ReadOptions::default())
        .unwrap()
        .render(&scene, &|_| {})
        .unwrap()
        .image
}

/// Ring measure ([`glint_render::Image::ring_measure`]) the default image stays under.
/// Measured 0.77 grey levels (examples/rings.rs); before jitter and the head phantom's
/// 4-voxel ramps the same view gave 1.35 (2-voxel ramps), and the Shepp-Logan phantom
/// gives 1.6-1.7: the bound separates them.
const DEFAULT_RING_BOUND: f64 = 0.9;

#[test]
fn default_image_has_no_rings_and_is_deterministic() {
    let a = default_image();
    let m = a.ring_measure().unwrap();
    assert!(m < DEFAULT_RING_BOUND, "ring measure {m}");
    // Same scene, same bytes.
    let b = default_image();
    let png_a = a.encode_png(glint_render::Depth::Eight).unwrap();
    assert_eq!(png_a, b.encode_png(glint_render::Depth::Eight).unwrap());
}

/// A slab facing the anterior camera on `n`^3 (1 mm voxels): value 1 over the middle
/// half in x and z, four voxels thick in y; its front face is a plane at one depth.
fn slab(n: usize) -> Volume {
    let inside = |a: usize| (n / 4..3 * n / 4).contains(&a);
    let mut v = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let on = inside(i) && inside(k) && (n / 2 - 2..n / 2 + 2).contains(&j);
                v.push(if on { 1.0 } else { 0.0 });
            }
        }
    }
    Volume::new([n; 3], [1.0; 3], Samples::F32(v)).unwrap()
}

/// A path-traced scene of the opaque slab, unshaded, `spp` samples, 48x48.
fn slab_scene(spp: u32) -> Scene {
    let tf = TransferFunction::from_flat(
        &[0.0, 0.0, 0.4, 0.0, 0.6, 1.0, 1.0, 1.0],
        &[0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0],
    )
    .unwrap();
    let mut scene = scene(48, 48);
    scene.transfer_function = Some(tf);
    scene.material = flat_material();
    scene.lighting = glint_render::Lighting {
        model: glint_render::LightingModel::Path,
        spp: Some(spp),
        ..Default::default()
    };
    scene
}

/// Pixels of the middle row whose coverage is between 0.1 and 0.9: the width of the
/// slab's two edges, blurred.
fn edge_width(image: &glint_render::Image) -> usize {
    let y = image.height / 2;
    (0..image.width)
        .filter(|&x| (0.1..0.9).contains(&image.alpha[(y * image.width + x) as usize]))
        .count()
}

#[test]
fn a_thin_lens_keeps_the_plane_in_focus_sharp_and_blurs_the_rest() {
    let volume = slab(32);
    let pinhole = render(&volume, &slab_scene(16));
    // Aperture 0 is the pinhole bit for bit, whatever the focus.
    let mut zero = slab_scene(16);
    zero.camera.aperture = 0.0;
    zero.camera.focus = Some(glint_render::Focus::Distance(20.0));
    assert_eq!(render(&volume, &zero).image, pinhole.image);
    let sharp = edge_width(&pinhole.image);
    assert!(sharp <= 4, "pinhole edges {sharp} px wide");
    // Autofocus on the front face under the centre: its edges stay sharp.
    let mut lens = slab_scene(16);
    lens.camera.aperture = 4.0;
    let focused = render(&volume, &lens);
    let eye = focused.scene.derived.as_ref().unwrap().eye;
    let focus = focused
        .scene
        .derived
        .as_ref()
        .unwrap()
        .focus_mm
        .expect("auto focus");
    // The front face (y = 17.5 mm, between the last voxel of 1 and the first of 0) lies that far from the eye, along the view (-y).
    assert!(
        (focus - f64::from(eye[1] - 17.5)).abs() < 1.5,
        "{focus} vs {eye:?}"
    );
    assert!(
        edge_width(&focused.image) <= sharp + 2,
        "{}",
        edge_width(&focused.image)
    );
    // Focused at half the distance, the face's edges spread over many pixels.
    lens.camera.focus = Some(glint_render::Focus::Distance(focus / 2.0));
    let blurred = edge_width(&render(&volume, &lens).image);
    assert!(
        blurred >= sharp + 8,
        "out of focus: {blurred} px, pinhole {sharp}"
    );
    // Local lighting renders a pinhole, lens or not.
    let mut local = lens.clone();
    local.lighting = Default::default();
    let mut local_pinhole = slab_scene(1);
    local_pinhole.lighting = Default::default();
    assert_eq!(
        render(&volume, &local).image,
        render(&volume, &local_pinhole).image
    );
}

#[test]
fn the_tone_curve_maps_the_radiance_and_keeps_the_path_samples() {
    let volume = shepp_logan(24);
    let mut scene = slab_scene(3);
    scene.transfer_function = None;
    scene.material = MaterialOverrides::default();
    let mut renderer = Renderer::from_source(volume, None).unwrap();
    let radiance = renderer.render_linear(&scene, &|_| {}).unwrap().image;
    assert_eq!(renderer.render(&scene, &|_| {}).unwrap().image, radiance);
    for tone in glint_render::Tone::ALL {
        let toned = Scene {
            exposure: 1.0,
            tone: *tone,
            ..scene.clone()
        };
        let shown = renderer.render(&toned, &|_| {}).unwrap().image;
        // The same samples (none traced again), through the curve.
        assert_eq!(renderer.path_samples(), 3);
        let mut expected = radiance.clone();
        glint_render::tone_map(&mut expected, 1.0, *tone);
        assert_eq!(shown, expected, "{tone}");
        assert_ne!(shown, radiance, "{tone}");
    }
}

#[test]
fn film_and_lens_fields_patch_and_stay_out_of_default_scenes() {
    let scene = Scene::default();
    let json = scene.to_json().unwrap();
    for key in ["exposure", "tone", "aperture", "focus"] {
        assert!(!json.contains(key), "{key} in {json}");
    }
    let patch = serde_json::json!({
        "exposure": -1.5,
        "tone": "agx",
        "camera": {"aperture": 2.5, "focus": "auto"}
    });
    let next = scene.patch(patch.as_object().unwrap()).unwrap();
    assert_eq!((next.exposure, next.tone), (-1.5, glint_render::Tone::Agx));
    assert_eq!(next.camera.aperture, 2.5);
    assert_eq!(next.camera.focus, Some(glint_render::Focus::AUTO));
    assert_eq!(next.camera.view, scene.camera.view);
    assert_eq!(Scene::from_json(&next.to_json().unwrap()).unwrap(), next);
    let next = next
        .patch(
            serde_json::json!({"camera": {"focus": 300}})
                .as_object()
                .unwrap(),
        )
        .unwrap();
    assert_eq!(
        next.camera.focus,
        Some(glint_render::Focus::Distance(300.0))
    );
    for bad in [
        serde_json::json!({"tone": "filmic"}),
        serde_json::json!({"camera": {"focus": "near"}}),
    ] {
        assert!(scene.patch(bad.as_object().unwrap()).is_err(), "{bad}");
    }
}

/// Every probe name `scripts/fetch-samples` fetches loads as a 512x256 map of finite,
/// non-negative radiance with some light in it (the `@pmndrs/assets` files decode:
/// OpenEXR with DWAB compression, read by the `exr` crate); an unknown name is refused
/// naming the known ones.
#[test]
fn the_fetched_environment_probes_load_by_name() {
    if glint_testkit::sample("hdri/lab.exr").is_none() {
        return;
    }
    for name in glint_render::FETCHED_ENVIRONMENTS {
        let map = glint_render::load_environment(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(map.size(), [512, 256], "{name}");
        let texels = map.texels();
        assert!(
            texels.iter().flatten().all(|v| v.is_finite() && *v >= 0.0),
            "{name}"
        );
        let mean: f32 = texels.iter().map(|t| t[1]).sum::<f32>() / texels.len() as f32;
        assert!(mean > 0.01, "{name}: mean green {mean}");
    }
    let e = glint_render::load_environment("labb")
        .unwrap_err()
        .to_string();
    assert!(e.contains("workshop") && e.contains("studio"), "{e}");
}
