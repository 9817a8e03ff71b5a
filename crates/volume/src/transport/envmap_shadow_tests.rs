//! An environment map's directional stand-ins in `shadows` (its median cut) against
//! the map itself, both through the path tracer.

use glint_core::{EnvMap, Light, Vec3};

use super::tests::{albedo_one, path_frame, path_frame_env, small_scene};
use super::*;

/// A dim sky (0.2) with a bright patch (radiance 40, 12° in radius) 40° above the
/// horizon at azimuth 60°.
fn patch_map() -> EnvMap {
    let (w, h) = (256u32, 128u32);
    let (theta0, phi0) = (50f32.to_radians(), 60f32.to_radians());
    let c = Vec3::new(
        theta0.sin() * phi0.cos(),
        theta0.sin() * phi0.sin(),
        theta0.cos(),
    );
    let cos_r = 12f32.to_radians().cos();
    let texels = (0..w * h)
        .map(|i| {
            let theta = std::f32::consts::PI * ((i / w) as f32 + 0.5) / h as f32;
            let phi = 2.0 * std::f32::consts::PI * ((i % w) as f32 + 0.5) / w as f32;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            if d.dot(c) > cos_r {
                [40.0; 3]
            } else {
                [0.2; 3]
            }
        })
        .collect();
    EnvMap::new(w, h, texels).unwrap()
}

#[test]
fn the_median_cut_stand_ins_give_the_maps_mean() {
    // The ball over the floor under the map, single scattering, 64 samples: the map
    // by next-event estimation and MIS against its 4 and 8 median-cut lights as
    // directional lights (intensity Φ/π, what `shadows` takes), both in `path`, so
    // the difference is the stand-ins' alone (not `shadows`' own approximations).
    // Printed for docs/lighting.md.
    let (class, _, frame) = small_scene();
    let camera = class.camera(&frame).unwrap();
    let map = patch_map();
    let settings = PathSettings {
        bounces: 1,
        seed: 7,
        environment: 0.0,
        sampler: Sampler::Sobol,
        time_budget: None,
        show_environment: false,
    };
    let reference = path_frame_env(
        &class,
        &albedo_one(vec![], 0.05),
        &frame,
        &settings,
        &map,
        64,
    );
    let lum = |c: [f32; 3]| f64::from(0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]);
    for splits in [2, 3] {
        // Each world direction as a light relative to this camera.
        let lights: Vec<Light> = (map.median_cut(splits).iter())
            .map(|&(d, e)| Light {
                azimuth: f64::from(d.dot(camera.right).atan2(-d.dot(camera.forward))).to_degrees(),
                elevation: f64::from(d.dot(camera.up).clamp(-1.0, 1.0).asin()).to_degrees(),
                intensity: e / std::f32::consts::PI,
            })
            .collect();
        for (l, (d, _)) in lights.iter().zip(map.median_cut(splits)) {
            assert!(l.direction(&camera).dot(d) > 0.9999, "{l:?} {d:?}");
        }
        let mut img = PathImage::new(frame.width, frame.height);
        let stand_in = path_frame(
            &class,
            &albedo_one(lights, 0.05),
            &frame,
            &settings,
            &mut img,
            64,
        )
        .unwrap();
        let (mut a, mut b, mut diff) = (0.0, 0.0, 0.0);
        for (x, y) in reference.rgb.iter().zip(&stand_in.rgb) {
            let (x, y) = (lum(*x), lum(*y));
            a += x;
            b += y;
            diff += (x - y).abs();
        }
        let err = (b - a) / a;
        eprintln!(
            "{} lights: mean {:.4} against the map's {:.4} ({:+.1}%), mean absolute difference per pixel {:.1}% of the mean",
            1 << splits,
            b / reference.rgb.len() as f64,
            a / reference.rgb.len() as f64,
            100.0 * err,
            100.0 * diff / a
        );
        assert!(err.abs() < 0.15, "{err}");
    }
}
