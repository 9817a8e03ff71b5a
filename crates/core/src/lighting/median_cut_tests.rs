use std::f32::consts::PI;

use super::*;
use crate::lighting::envmap::EnvMap;

/// The irradiance the lights give a surface of unit normal `n`: `Σ Φ·max(n·d, 0)`.
fn irradiance(lights: &[(Vec3, f32)], n: Vec3) -> f32 {
    lights.iter().map(|&(d, e)| e * n.dot(d).max(0.0)).sum()
}

#[test]
fn a_constant_map_gives_equal_lights_of_its_whole_energy_and_no_net_flux() {
    // A constant map of radiance L (luminance 0.7, intensity 2): its energy over the
    // sphere is 4π·L exactly, and on every plane the irradiance of either side is
    // π·L (a full hemisphere), so the net flux Σ Φ·d is 0.
    let l = 0.7 * 2.0;
    let map = EnvMap::constant([0.7; 3], 512, 256)
        .unwrap()
        .placed(30.0, 2.0)
        .unwrap();
    assert!((map.mean_luminance() - l).abs() < 1e-5 * l);
    for splits in [2, 3] {
        let lights = map.median_cut(splits);
        assert_eq!(lights.len(), 1 << splits);
        let total: f32 = lights.iter().map(|l| l.1).sum();
        assert!((total - 4.0 * PI * l).abs() < 1e-4 * total, "{total}");
        for &(d, e) in &lights {
            assert!((d.length() - 1.0).abs() < 1e-5);
            assert!(
                (e - total / lights.len() as f32).abs() < 1e-3 * total,
                "{e}"
            );
        }
        let flux = lights.iter().fold(Vec3::ZERO, |a, &(d, e)| a + d * e);
        assert!(flux.length() < 1e-3 * total, "{flux:?}");
        // On the six axis planes' sides the few lights' clamped cosines approximate
        // the hemisphere's π·L only roughly (4 lights: 0.71x to 1.41x; the ambient
        // occlusion and the medium's phase function spread it in `shadows`).
        let axes = [
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        ];
        for n in axes.into_iter().flat_map(|a| [a, a * -1.0]) {
            let e = irradiance(&lights, n);
            eprintln!(
                "{} lights, n = {n:?}: E = {e:.4}, pi L = {:.4}",
                lights.len(),
                PI * l
            );
            assert!((e - PI * l).abs() < 0.5 * PI * l, "{n:?}: {e}");
        }
    }
}

#[test]
fn a_small_bright_source_gets_a_light_within_a_few_degrees() {
    // A dim sky (luminance about 0.1) with a source of radiance 2000 and 2° in radius
    // at polar angle 50°, azimuth 70° (turned by the map's rotation of 40°): it
    // holds about three quarters of the map's energy.
    let w = 1024;
    let h = 512;
    let (theta0, phi0) = (50f32.to_radians(), 70f32.to_radians());
    let c = Vec3::new(
        theta0.sin() * phi0.cos(),
        theta0.sin() * phi0.sin(),
        theta0.cos(),
    );
    let cos_r = 2f32.to_radians().cos();
    let mut texels = Vec::new();
    for y in 0..h {
        let theta = PI * (y as f32 + 0.5) / h as f32;
        for x in 0..w {
            let phi = 2.0 * PI * (x as f32 + 0.5) / w as f32;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            texels.push(if d.dot(c) > cos_r {
                [2000.0; 3]
            } else {
                [0.1; 3]
            });
        }
    }
    let map = EnvMap::new(w, h, texels)
        .unwrap()
        .placed(40.0, 1.0)
        .unwrap();
    let phi1 = phi0 + 40f32.to_radians();
    let sun = Vec3::new(
        theta0.sin() * phi1.cos(),
        theta0.sin() * phi1.sin(),
        theta0.cos(),
    );
    for splits in [2, 3] {
        let lights = map.median_cut(splits);
        let (d, e) = lights
            .iter()
            .copied()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        let angle = d.dot(sun).clamp(-1.0, 1.0).acos().to_degrees();
        let total: f32 = lights.iter().map(|l| l.1).sum();
        eprintln!(
            "{} lights: the brightest {angle:.2} deg from the source, {:.3} of the energy",
            lights.len(),
            e / total
        );
        assert!(angle < 3.0, "{angle}");
        // Much of the source's energy 2000·2π(1 - cos 2°) lies in lights near it (the
        // rest in regions it shares with the sky, whose centroids it pulls).
        let near: f32 = (lights.iter())
            .filter(|l| l.0.dot(sun) > 5f32.to_radians().cos())
            .map(|l| l.1)
            .sum();
        let source = 2000.0 * 2.0 * PI * (1.0 - cos_r);
        eprintln!("  lights within 5 deg: {near:.3}, the source {source:.3}");
        assert!(near > 0.5 * source, "{near} {source}");
    }
}

#[test]
fn a_black_map_gives_no_light() {
    let map = EnvMap::constant([0.0; 3], 64, 32).unwrap();
    assert!(map.median_cut(3).is_empty());
    assert_eq!(map.mean_luminance(), 0.0);
}

#[test]
fn a_red_and_blue_map_gives_red_and_blue_lights_of_its_whole_power() {
    // Red radiance (1, 0, 0) towards +z (rows of polar angle under 90°), blue
    // (0, 0, b) towards -z, b chosen so both hemispheres hold the same luminance
    // (0.2126 = 0.0722 b): the energy's median in polar angle is the equator, so
    // every region after the third split is one colour.
    let (w, h) = (512, 256);
    let b = 0.2126 / 0.0722;
    let texels: Vec<[f32; 3]> = (0..w * h)
        .map(|i| {
            if i / w < h / 2 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 0.0, b]
            }
        })
        .collect();
    let intensity = 2.0;
    let map = EnvMap::new(w as u32, h as u32, texels)
        .unwrap()
        .placed(25.0, intensity)
        .unwrap();
    for splits in [3, 4, 6] {
        let lights = map.median_cut_rgb(splits);
        assert_eq!(lights.len(), 1 << splits);
        for &(d, [r, g, bl]) in &lights {
            assert_eq!(g, 0.0);
            if d.z > 0.0 {
                assert!(r > 0.0 && bl == 0.0, "{d:?}: {r} {g} {bl}");
            } else {
                assert!(r == 0.0 && bl > 0.0, "{d:?}: {r} {g} {bl}");
            }
        }
        // Each hemisphere's power is its radiance times 2π sr, the intensity applied.
        let total = lights.iter().fold([0.0f64; 3], |mut t, (_, p)| {
            for c in 0..3 {
                t[c] += f64::from(p[c]);
            }
            t
        });
        let truth = [1.0, 0.0, f64::from(b)].map(|l| l * 2.0 * std::f64::consts::PI * 2.0);
        for c in [0, 2] {
            assert!(
                (total[c] - truth[c]).abs() < 1e-4 * truth[c],
                "{splits} splits, channel {c}: {} against {}",
                total[c],
                truth[c]
            );
        }
        // The luminance of each light's power is median_cut's energy, same direction.
        for ((d, p), (d2, e)) in lights.iter().zip(map.median_cut(splits)) {
            assert_eq!(*d, d2);
            let lum = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
            assert!((lum - e).abs() < 1e-4 * e, "{lum} {e}");
        }
    }
}
