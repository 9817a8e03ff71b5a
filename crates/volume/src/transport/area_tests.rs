//! Area lights in `path` against closed forms and against each strategy alone, and
//! their directional stand-ins in `shadows`.

use glint_core::lighting::{AreaLightSpec, AreaShapeSpec, LightFrame};
use glint_core::{Shader, Vec3};
use glint_lobe::Geometry;

use super::path::{EnvStrategy, PathTracer};
use super::tests::{
    albedo_one, classify, green_mean_and_variance, path_frame, small_scene, volume, white,
};
use super::*;
use crate::classification::Classification;
use crate::raycast::FrameSettings;

/// The centre of `class`'s volume, world mm (what the scene places area lights about).
fn center(class: &Classification) -> Vec3 {
    let f = class.field();
    let c = f.index_to_world(f.dims().map(|d| (d - 1) as f64 / 2.0));
    Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32)
}

/// A light `dist` mm above the volume's centre (superior, +z) of `shape` and radiance.
fn above(shape: AreaShapeSpec, dist: f64, radiance: f32) -> AreaLightSpec {
    AreaLightSpec {
        shape,
        frame: LightFrame::Volume,
        position: [0.0, 0.0, dist],
        radiance: [radiance; 3],
    }
}

/// The mean radiance (green) of the central 8x8 pixels of a 16x16 frame looking down
/// (superior) at a white Lambertian floor, single scattering, no environment, under
/// `shader` (with `area` placed about the volume's centre), by `model`.
fn floor_from_above(shader: Shader, area: Vec<AreaLightSpec>, model: LightingModel) -> f64 {
    let floor = volume(
        [24, 24, 24],
        [1.0; 3],
        |_, _, k| if k <= 12.0 { 1.0 } else { 0.0 },
    );
    let class = classify(&floor, &white(&[(0.0, 0.0), (1.0, 0.999)]));
    let shader = shader.with_area_lights(area, center(&class)).unwrap();
    let frame = FrameSettings {
        width: 16,
        height: 16,
        camera: glint_core::CameraSpec {
            view: glint_core::View::Superior,
            ..Default::default()
        },
        ..Default::default()
    };
    let image = match model {
        LightingModel::Path => {
            let settings = PathSettings {
                bounces: 1,
                seed: 2,
                environment: 0.0,
                sampler: Sampler::Sobol,
                time_budget: None,
                show_environment: false,
            };
            let mut img = PathImage::new(16, 16);
            path_frame(&class, &shader, &frame, &settings, &mut img, 256).unwrap()
        }
        _ => {
            let sf = class
                .shadow_field(&shader, &frame, &ShadowSettings { occlusion: false }, None)
                .unwrap();
            super::tests::shadows_frame(&class, &shader, &frame, &sf).unwrap()
        }
    };
    let mut sum = 0.0;
    for y in 4..12 {
        for x in 4..12 {
            sum += f64::from(image.rgb[y * 16 + x][1]);
        }
    }
    sum / 64.0
}

#[test]
fn a_far_area_light_is_its_irradiance_on_a_lambertian_floor() {
    // A sphere of radius r at distance d gives E = π·L·(r/d)²: r = 100, d = 2000 and
    // L = 400 is E = π, a headlight of intensity 1 (radiance 1 off a white floor, as
    // `one_light_is_one_irradiance_for_the_medium_and_the_surface`). A 200x200 mm
    // rectangle at 2000 mm of L = 1/F the same, F its form factor (A/(π·d²) less
    // 0.3%). `shadows` takes each as a headlight of intensity 1: the same image as
    // under the headlight itself.
    let sphere = above(AreaShapeSpec::Sphere { radius: 100.0 }, 2000.0, 400.0);
    let f = {
        let (x, c) = (100.0f64, 2000.0f64);
        let s = (1.0 + (x / c).powi(2)).sqrt();
        4.0 * 2.0 * (x / c / s * (x / c / s).atan()) / (2.0 * std::f64::consts::PI)
    };
    let rect = above(
        AreaShapeSpec::Rect { size: [200.0; 2] },
        2000.0,
        (1.0 / f) as f32,
    );
    let headlight = floor_from_above(
        albedo_one(vec![glint_core::Light::HEADLIGHT], 0.0),
        vec![],
        LightingModel::Shadows,
    );
    for (name, light) in [("sphere", sphere), ("rectangle", rect)] {
        let path = floor_from_above(albedo_one(vec![], 0.0), vec![light], LightingModel::Path);
        let shadows =
            floor_from_above(albedo_one(vec![], 0.0), vec![light], LightingModel::Shadows);
        eprintln!("{name}: path {path:.4} (want 1), shadows {shadows:.4} (the headlight's {headlight:.4})");
        assert!((path - 1.0).abs() < 0.02, "{name}: path {path}");
        // The rectangle's stand-in is a point source of its area: 0.3% over its
        // form factor here.
        assert!(
            (shadows / headlight - 1.0).abs() < 5e-3,
            "{name}: shadows {shadows}"
        );
    }
}

/// The `path` image (single scattering, no environment, 64 samples) of the ball over
/// the floor under `shader`.
fn ball_path(shader: &Shader) -> glint_core::Image {
    let (class, _, frame) = small_scene();
    let settings = PathSettings {
        bounces: 1,
        seed: 5,
        environment: 0.0,
        sampler: Sampler::Sobol,
        time_budget: None,
        show_environment: false,
    };
    let mut img = PathImage::new(frame.width, frame.height);
    path_frame(&class, shader, &frame, &settings, &mut img, 64).unwrap()
}

#[test]
fn the_stand_in_of_shadows_errs_as_the_light_nears() {
    // A sphere light towards the viewer at distance d from the volume's centre
    // (radius 15 mm, L = (d/15)², so its irradiance at the centre is π, a headlight
    // of intensity 1) against that headlight, both in `path` (single scattering):
    // the difference is what `shadows`' stand-in (the headlight) leaves out: the
    // light's fall-off over the volume (the ball's 48 mm), its direction's spread
    // and its soft shadow. Printed for docs/lighting.md.
    let (class, _, _) = small_scene();
    let reference = ball_path(&albedo_one(vec![glint_core::Light::HEADLIGHT], 0.05));
    let lum = |c: [f32; 3]| f64::from(0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]);
    let mut errors = Vec::new();
    for d in [60.0f64, 150.0, 600.0] {
        let light = AreaLightSpec {
            shape: AreaShapeSpec::Sphere { radius: 15.0 },
            frame: LightFrame::Camera,
            position: [0.0, 0.0, d],
            radiance: [((d / 15.0) * (d / 15.0)) as f32; 3],
        };
        let shader = albedo_one(vec![], 0.05)
            .with_area_lights(vec![light], center(&class))
            .unwrap();
        let img = ball_path(&shader);
        let (mut a, mut b, mut diff) = (0.0, 0.0, 0.0);
        for (x, y) in img.rgb.iter().zip(&reference.rgb) {
            let (x, y) = (lum(*x), lum(*y));
            a += x;
            b += y;
            diff += (x - y).abs();
        }
        eprintln!(
            "sphere light at {d} mm: mean {:.4} against the stand-in's {:.4} ({:+.1}%), mean absolute difference per pixel {:.1}% of the mean",
            a / img.rgb.len() as f64,
            b / img.rgb.len() as f64,
            100.0 * (b - a) / a,
            100.0 * diff / a
        );
        errors.push(((b - a) / a).abs());
    }
    // Far away the stand-in is the light (within the noise of 64 samples).
    assert!(errors[2] < 0.05, "{errors:?}");
    assert!(errors[0] > errors[2], "{errors:?}");
}

#[test]
fn mis_of_the_area_lights_agrees_with_each_strategy() {
    // The ball over the floor lit by a small bright sphere (radius 2 mm, L = 300) and
    // a broad rectangle (80x80 mm, L = 0.5), no directional light, no environment,
    // 3 bounces: the three strategies' means agree within their noise.
    let (class, shader, frame) = small_scene();
    let c = center(&class);
    let lights = vec![
        AreaLightSpec {
            shape: AreaShapeSpec::Sphere { radius: 2.0 },
            frame: LightFrame::Camera,
            position: [30.0, 40.0, 40.0],
            radiance: [300.0; 3],
        },
        AreaLightSpec {
            shape: AreaShapeSpec::Rect { size: [80.0, 80.0] },
            frame: LightFrame::Volume,
            position: [-40.0, 0.0, 50.0],
            radiance: [0.5, 0.6, 0.7],
        },
    ];
    let shader = Shader::with_specular(
        shader.specular().clone(),
        Geometry::Blinn,
        *shader.material(),
        vec![],
        shader.gate(),
    )
    .unwrap()
    .with_anisotropy(0.3)
    .unwrap()
    .with_area_lights(lights, c)
    .unwrap();
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
    assert_eq!(placed.area_lights().len(), 2);
    assert_eq!(placed.directional_lights().len(), 0);
    assert_eq!(placed.world_lights().len(), 2, "the stand-ins");
    let size = [frame.width, frame.height];
    let spp = 48u32;
    let run = |strategy: EnvStrategy| {
        let mut tracer = PathTracer::new(
            class.field(),
            class.medium(),
            &placed,
            camera,
            size,
            settings,
        )
        .unwrap();
        tracer.area_strategy = strategy;
        green_mean_and_variance(&tracer, size, spp)
    };
    let (mis, var_mis) = run(EnvStrategy::Mis);
    let (light, var_light) = run(EnvStrategy::Light);
    let (scatter, var_scatter) = run(EnvStrategy::Scatter);
    eprintln!(
        "path under area lights: mean MIS {mis:.4}, light {light:.4}, scattering {scatter:.4}; \
         variance per sample MIS {var_mis:.4}, light {var_light:.4}, scattering {var_scatter:.4}"
    );
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
}

#[test]
fn shaders_without_area_lights_place_only_their_lights() {
    let (class, shader, frame) = small_scene();
    let camera = class.camera(&frame).unwrap();
    let placed = shader.placed(&camera);
    assert!(placed.area_lights().is_empty());
    assert_eq!(placed.directional_lights(), placed.world_lights());
}

#[test]
fn camera_rays_see_the_area_lights_where_the_environment_is_shown() {
    // A large sphere light (radius 200 mm, radiance 2.5) 300 mm behind the volume's
    // centre, away from the camera, in a black environment: with
    // `show_environment` the pixels that meet no matter see it, opaque and at its
    // radiance; without it they see the background, as before.
    let (class, _, frame) = small_scene();
    let light = AreaLightSpec {
        shape: AreaShapeSpec::Sphere { radius: 200.0 },
        frame: LightFrame::Camera,
        position: [0.0, 0.0, -300.0],
        radiance: [2.5; 3],
    };
    let shader = albedo_one(vec![], 0.05)
        .with_area_lights(vec![light], center(&class))
        .unwrap();
    let image = |show: bool| {
        let settings = PathSettings {
            bounces: 1,
            seed: 3,
            environment: 0.0,
            sampler: Sampler::Sobol,
            time_budget: None,
            show_environment: show,
        };
        let mut img = PathImage::new(frame.width, frame.height);
        path_frame(&class, &shader, &frame, &settings, &mut img, 4).unwrap()
    };
    let seen = |img: &glint_core::Image| {
        (img.rgb.iter().zip(&img.alpha))
            .filter(|(c, &a)| **c == [2.5; 3] && a == 1.0)
            .count()
    };
    let (shown, hidden) = (image(true), image(false));
    assert!(seen(&shown) > 0, "no pixel sees the light");
    assert_eq!(seen(&hidden), 0);
    // Where the light is not shown those pixels are transparent.
    for ((c, &a), &b) in (shown.rgb.iter().zip(&shown.alpha)).zip(&hidden.alpha) {
        if *c == [2.5; 3] && a == 1.0 {
            assert!(b < 1.0, "{b}");
        }
    }
}
