//! Test fixtures shared by the batch forms' tests (`batch.rs`, `shadowed.rs`): the
//! shaders every path is checked with, deterministic batches and the bit-for-bit check;
//! and the sphere quadrature of the scattering and environment-map tests.

use std::f64::consts::PI as PI64;

use glint_lobe::{Geometry, LobeKind};

use crate::camera::{Camera, CameraSpec};
use crate::lighting::{Light, Material, ShadeBatch, Shader};
use crate::Vec3;

/// A deterministic spread of values in [-1, 1) (a Weyl sequence).
pub(crate) fn spread(k: usize, salt: f32) -> f32 {
    let x = (k as f32 * 0.618_034 + salt).fract();
    2.0 * x - 1.0
}

pub(crate) fn shaders(gate: f32) -> Vec<Shader> {
    let cam = Camera::frame(&CameraSpec::default(), Vec3::ZERO, 1.0, 8, 8).unwrap();
    let lights = vec![
        Light::HEADLIGHT,
        Light {
            azimuth: 40.0,
            elevation: 25.0,
            intensity: 0.7,
        },
        Light {
            azimuth: -120.0,
            elevation: -10.0,
            intensity: 1.3,
        },
    ];
    let mut out = Vec::new();
    for geometry in [Geometry::Phong, Geometry::Blinn] {
        for kind in [LobeKind::EnergyFit, LobeKind::Exact, LobeKind::Schlick] {
            let s = Shader::new(
                kind,
                37.0,
                4,
                geometry,
                Material::default(),
                lights.clone(),
                gate,
            )
            .unwrap();
            out.push(s.placed(&cam));
        }
    }
    out
}

/// Fills a batch of `n` samples: normals (or gradients scaled by `scale`), views
/// and colours from deterministic spreads, with a few degenerate normals.
pub(crate) fn fill(b: &mut ShadeBatch, n: usize, scale: f32) {
    b.set_len(n);
    for k in 0..n {
        let g = Vec3::new(spread(k, 0.1), spread(k, 0.37), spread(k, 0.71)) * scale;
        let g = match k % 17 {
            0 => Vec3::ZERO,
            1 => Vec3::new(f32::NAN, 0.0, 1.0),
            2 => Vec3::new(f32::INFINITY, 0.0, 0.0),
            _ => g,
        };
        let v = Vec3::new(spread(k, 0.5) * 0.3, spread(k, 0.9) * 0.3, 1.0).normalize_or_zero();
        for a in 0..3 {
            b.normal[a][k] = g.get(a);
            b.view[a][k] = v.get(a);
            b.color[a][k] = 0.5 + 0.5 * spread(k, 0.2 * a as f32);
        }
    }
}

/// The batch's result for sample `k` against the scalar form, bit for bit.
pub(crate) fn check(got: &ShadeBatch, want: impl Fn(usize) -> [f32; 3], n: usize, what: &str) {
    for k in 0..n {
        let g = [got.color[0][k], got.color[1][k], got.color[2][k]];
        let w = want(k);
        assert_eq!(
            g.map(f32::to_bits),
            w.map(f32::to_bits),
            "{what}, sample {k}: {g:?} vs {w:?}"
        );
    }
}

/// The midpoint rule over the sphere on a `rows × 2·rows` grid in (θ, φ).
pub(crate) fn sphere_integral(rows: usize, mut f: impl FnMut(Vec3) -> f64) -> f64 {
    let d = PI64 / rows as f64;
    let (dt, dp) = (d, d);
    let mut sum = 0.0;
    for i in 0..rows {
        let t = (i as f64 + 0.5) * dt;
        for j in 0..2 * rows {
            let p = (j as f64 + 0.5) * dp;
            let d = Vec3::new(
                (t.sin() * p.cos()) as f32,
                (t.sin() * p.sin()) as f32,
                t.cos() as f32,
            );
            sum += f(d) * t.sin() * dt * dp;
        }
    }
    sum
}
