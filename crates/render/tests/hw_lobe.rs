//! Rendering with a hardware unit's arithmetic (the scene's `hw` lobe, a table of
//! `glint_hw::Unit`'s output over its cosine codes): the SIMD loop gives the scalar
//! loop's image bit for bit (the per-sample value is tested against `Unit::eval` in
//! `shading.rs` and `scene.rs`), and the image differs from float K_v's by no more
//! than the unit's quantisation allows.

use glint_hw::{Config, Input as HwInput, Unit};
use glint_lobe::{Geometry, LobeKind};
use glint_render::{
    CameraSpec, Image, Kernel, Light, LobeSpec, Phantom, ReadOptions, Renderer, Scene, SceneLobe,
};

/// Shininess of the scenes (an integer: the unit's n input takes it exactly).
const N: f64 = 60.0;

fn scene(geometry: Geometry, lobe: SceneLobe, unit: &Config) -> Scene {
    Scene {
        camera: CameraSpec {
            azimuth: 33.0,
            elevation: -21.0,
            ..Default::default()
        },
        lights: vec![
            Light::HEADLIGHT,
            Light {
                azimuth: 50.0,
                elevation: 30.0,
                intensity: 0.7,
            },
        ],
        lobe: LobeSpec {
            kind: lobe,
            n: Some(N),
            geometry,
            ..LobeSpec::hw(unit.clone())
        },
        gate: 0.0,
        ..Scene::phantom(Phantom::SheppLogan, 48, [48, 40])
    }
}

/// Largest |a - b| over every channel of every pixel.
fn worst(a: &Image, b: &Image) -> f32 {
    a.rgb
        .iter()
        .flatten()
        .zip(b.rgb.iter().flatten())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

/// The most a sample's specular value from `unit` (n = [`N`]) can differ from float
/// K_v's, derived from `Unit::eval` and K_v's formula (not from the renderer): a
/// sample at cosine `c` gets the unit's output at the code `k = round(c·2^f)`, whose
/// cosine `c_k = k/2^f` is within `h = 2^-(f+1)` of `c`, so
/// `|U_k - K(c)| <= |U_k - K(c_k)| + max |K(c_k ± h) - K(c_k)|` (K is monotonic
/// between codes). Plus 1e-6 for K's evaluation in f32.
fn sample_bound(unit: &Unit) -> f64 {
    let c = unit.config();
    let two_v = f64::from(1u32 << c.v);
    let a = (N + 1.0) / (two_v + 1.0);
    let k = |x: f64| (1.0 - a * (1.0 - x.clamp(-1.0, 1.0))).max(0.0).powf(two_v);
    let f = unit.formats().cos_frac;
    let one = 1i64 << f;
    let h = 0.5 / one as f64;
    let full = unit.full_scale();
    let mut bound = 0.0f64;
    for code in -one..=one {
        let out = unit
            .eval(&HwInput {
                cos: code,
                n: N as u32,
                ks: [full; 3],
            })
            .unwrap();
        let u = f64::from((out.rgb[0] as f64 / full as f64) as f32);
        let ck = code as f64 / one as f64;
        let between = (k(ck + h) - k(ck)).abs().max((k(ck - h) - k(ck)).abs());
        bound = bound.max((u - k(ck)).abs() + between);
    }
    bound + 1e-6
}

#[test]
fn simd_loop_gives_the_scalar_loops_image_with_a_units_table() {
    if glint_testkit::strict() && cfg!(target_arch = "x86_64") {
        assert!(
            Kernel::simd_available(),
            "no AVX2+FMA: the SIMD loop is not tested"
        );
    }
    let config = Config::default();
    let mut renderer = Renderer::open(
        &scene(Geometry::Phong, SceneLobe::Hw, &config),
        &ReadOptions::default(),
    )
    .unwrap();
    for out_bits in [8, 12] {
        let config = Config {
            out_bits,
            ..Config::default()
        };
        for geometry in [Geometry::Phong, Geometry::Blinn] {
            let what = format!("{out_bits}-bit output, {geometry}");
            let s = scene(geometry, SceneLobe::Hw, &config);
            renderer.kernel = Kernel::Auto;
            let fast = renderer.render(&s, &|_| {}).unwrap().image;
            renderer.kernel = Kernel::Scalar;
            let slow = renderer.render(&s, &|_| {}).unwrap().image;
            assert_eq!(fast.rgb, slow.rgb, "{what}");
            assert_eq!(fast.alpha, slow.alpha, "{what}");
            assert!(fast.alpha.iter().any(|&a| a > 0.5), "{what}: empty image");
        }
    }
}

#[test]
fn a_hw_render_differs_from_float_k_by_at_most_the_quantisation() {
    let mut renderer = Renderer::open(
        &scene(Geometry::Phong, SceneLobe::Hw, &Config::default()),
        &ReadOptions::default(),
    )
    .unwrap();
    for out_bits in [8, 10, 12] {
        let config = Config {
            out_bits,
            ..Config::default()
        };
        let unit = Unit::new(config.clone()).unwrap();
        let per_sample = sample_bound(&unit);
        for geometry in [Geometry::Phong, Geometry::Blinn] {
            let what = format!("{out_bits}-bit output, {geometry}");
            let hw = renderer
                .render(&scene(geometry, SceneLobe::Hw, &config), &|_| {})
                .unwrap();
            let k = renderer
                .render(
                    &scene(geometry, LobeKind::EnergyFit.into(), &config),
                    &|_| {},
                )
                .unwrap();
            // A pixel is a composite of shaded samples with weights summing to at
            // most 1, and only the specular term differs: k_s · Σ intensity · the
            // per-sample bound.
            let s = &hw.scene;
            let lights: f32 = s.lights.iter().map(|l| l.intensity).sum();
            let ks = s.material.specular.unwrap();
            let bound = f64::from(ks * lights) * per_sample;
            let d = f64::from(worst(&hw.image, &k.image));
            assert!(d > 0.0, "{what}: the unit changed nothing");
            assert!(d <= bound, "{what}: {d} from float K_4, bound {bound}");
            assert_eq!(hw.image.alpha, k.image.alpha, "{what}: opacity changed");
            eprintln!("{what}: worst {d:.2e}, bound {bound:.2e}");
        }
    }
}
