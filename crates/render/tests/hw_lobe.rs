//! Rendering with a hardware unit's arithmetic (`glint_lobe::Specular::Table` built by
//! `glint_hw::Unit::cos_table`): the SIMD loop gives the scalar loop's image bit for
//! bit (the scalar loop's per-sample value is tested against `Unit::eval` in
//! `shading.rs`), and the image is close to, but not the same as, float K_v's.

use glint_hw::{Config, Unit};
use glint_lobe::{Geometry, LobeKind, Specular};
use glint_render::{
    CameraSpec, Input, Kernel, Light, LobeSpec, Phantom, Renderer, Resolved, Scene,
};

fn scene(geometry: Geometry) -> Scene {
    Scene {
        input: Input::Phantom {
            name: Phantom::SheppLogan,
            size: 48,
        },
        size: [48, 40],
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
            kind: LobeKind::EnergyFit,
            n: Some(60.0),
            v: 4,
            geometry,
        },
        gate: 0.0,
        ..Scene::default()
    }
}

/// `resolved` with its specular term replaced by `unit`'s table for the scene's n.
fn with_unit(mut resolved: Resolved, unit: &Unit) -> Resolved {
    let n = unit.n_code(resolved.scene.lobe.n.unwrap()).unwrap();
    let table = unit.cos_table(n).unwrap();
    resolved.shader.set_specular(Specular::from(table));
    resolved
}

#[test]
fn simd_loop_gives_the_scalar_loops_image_with_a_units_table() {
    if std::env::var_os("CI").is_some() && cfg!(target_arch = "x86_64") {
        assert!(
            Kernel::simd_available(),
            "no AVX2+FMA: the SIMD loop is not tested"
        );
    }
    let mut renderer = Renderer::open(&scene(Geometry::Phong).input).unwrap();
    for out_bits in [8, 12] {
        let unit = Unit::new(Config {
            out_bits,
            ..Config::default()
        })
        .unwrap();
        for geometry in [Geometry::Phong, Geometry::Blinn] {
            let what = format!("{out_bits}-bit output, {geometry}");
            renderer.kernel = Kernel::Auto;
            let float = renderer.resolve(&scene(geometry)).unwrap();
            let hw = with_unit(float.clone(), &unit);
            let fast = renderer.render_resolved(hw, &|_| {}).unwrap().image;
            let k = renderer.render_resolved(float, &|_| {}).unwrap().image;
            renderer.kernel = Kernel::Scalar;
            let hw = with_unit(renderer.resolve(&scene(geometry)).unwrap(), &unit);
            let slow = renderer.render_resolved(hw, &|_| {}).unwrap().image;
            assert_eq!(fast.rgb, slow.rgb, "{what}");
            assert_eq!(fast.alpha, slow.alpha, "{what}");
            assert!(fast.alpha.iter().any(|&a| a > 0.5), "{what}: empty image");
            // Against float K_4 of the same n: the same picture within the unit's
            // error (about 1 LSB of 8 bits per lobe value, times the material's
            // specular and the lights), but not the same numbers.
            let worst = fast
                .rgb
                .iter()
                .flatten()
                .zip(k.rgb.iter().flatten())
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max);
            assert!(worst > 0.0, "{what}: the table changed nothing");
            assert!(worst < 0.02, "{what}: {worst} from float K_4");
        }
    }
}
