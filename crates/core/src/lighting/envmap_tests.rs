use std::f64::consts::PI as PI64;

use glint_lobe::{Geometry, LobeKind};

use super::*;
use crate::camera::{Camera, CameraSpec};
use crate::lighting::fixtures::sphere_integral;
use crate::lighting::{Bsdf, Material, Shader};

/// A map with structure: a dim sky brighter towards the top, a broad warm patch (30°
/// about polar angle 32°, azimuth 180°) and a small bright source (radiance `sun`) of
/// `radius` degrees at polar angle 50°, azimuth 70°.
fn probe(w: u32, h: u32, sun: f32, radius: f32) -> EnvMap {
    let c = Vec3::new(
        50f32.to_radians().sin() * 70f32.to_radians().cos(),
        50f32.to_radians().sin() * 70f32.to_radians().sin(),
        50f32.to_radians().cos(),
    );
    let cos_r = radius.to_radians().cos();
    let patch = Vec3::new(-(32f32.to_radians().sin()), 0.0, 32f32.to_radians().cos());
    let cos_patch = 30f32.to_radians().cos();
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
            let sky = 0.1 + 0.2 * theta.cos().max(0.0);
            let mut t = [sky, sky, sky * 1.2];
            if d.dot(patch) > cos_patch {
                t = [3.0, 2.5, 2.0];
            }
            if d.dot(c) > cos_r {
                t = [sun; 3];
            }
            texels.push(t);
        }
    }
    EnvMap::new(w, h, texels).unwrap()
}

#[test]
fn the_pdf_integrates_to_one_and_matches_the_samples() {
    for rotation in [0.0, 37.0, -200.0] {
        let map = probe(64, 32, 50.0, 8.0).placed(rotation, 2.0).unwrap();
        let total = sphere_integral(512, |d| f64::from(map.pdf(d)));
        assert!(
            (total - 1.0).abs() < 2e-3,
            "rotation {rotation}: ∫pdf = {total}"
        );
        // Each sample's density is the map's pdf in its direction, its radiance the
        // map's (times the intensity).
        for k in 0..200 {
            let u = [
                (k as f32 * 0.618_034).fract(),
                (k as f32 * 0.414_213 + 0.1).fract(),
            ];
            let s = map.sample(u).unwrap();
            assert!((s.wi.length() - 1.0).abs() < 1e-5);
            let pdf = map.pdf(s.wi);
            assert!((s.pdf - pdf).abs() <= 1e-3 * pdf, "{} vs {pdf}", s.pdf);
            assert_eq!(s.radiance, map.eval(s.wi));
        }
    }
}

#[test]
fn a_constant_map_is_uniform_and_sampled_uniformly() {
    let map = EnvMap::constant([0.7; 3], 32, 16).unwrap();
    for d in [
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.3, -0.4, -0.8).normalize_or_zero(),
    ] {
        assert_eq!(map.eval(d), [0.7; 3]);
    }
    // The density is 1/4π up to the rows' piecewise-constant sin θ.
    let want = 1.0 / (4.0 * PI);
    // (At a row's centre, up to the midpoint rule's integral of sin θ over 16 rows.)
    let centre = PI * 5.5 / 16.0;
    let d = Vec3::new(centre.sin(), 0.0, centre.cos());
    assert!((map.pdf(d) - want).abs() < 4e-3 * want, "{}", map.pdf(d));
    // A black map draws nothing and has no density.
    let black = EnvMap::constant([0.0; 3], 8, 4).unwrap();
    assert!(black.sample([0.3, 0.6]).is_none());
    let d = Vec3::new(0.6, 0.0, 0.8);
    assert_eq!(black.pdf(d), 0.0);
}

#[test]
fn sampled_directions_pass_a_chi_square_test() {
    // Directions binned on a θ x φ grid against the pdf's integral over each bin
    // (Mitsuba's and pbrt's χ² tests of their samplers do the same).
    let map = probe(64, 32, 30.0, 10.0).placed(45.0, 1.0).unwrap();
    // Bins aligned with the texels (32 x 64), so the pdf times sin θ is constant over
    // each quadrature cell's texel and the expected counts are exact.
    let (nt, np) = (16usize, 32usize);
    let n = 200_000u32;
    let mut observed = vec![0f64; nt * np];
    let bin = |d: Vec3| {
        let t = f64::from(d.z.clamp(-1.0, 1.0)).acos();
        let p = f64::from(d.y).atan2(f64::from(d.x)).rem_euclid(2.0 * PI64);
        let i = ((t / PI64 * nt as f64) as usize).min(nt - 1);
        let j = ((p / (2.0 * PI64) * np as f64) as usize).min(np - 1);
        i * np + j
    };
    // A deterministic independent sequence (SplitMix64).
    let mut state = 0x1234_5678_9abc_def0u64;
    let mut next = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    };
    for _ in 0..n {
        let s = map.sample([next(), next()]).unwrap();
        observed[bin(s.wi)] += 1.0;
    }
    // Expected counts: the pdf integrated over each bin (fine midpoint quadrature).
    let mut expected = vec![0f64; nt * np];
    let sub = 8usize;
    let (dt, dp) = (PI64 / (nt * sub) as f64, 2.0 * PI64 / (np * sub) as f64);
    for i in 0..nt * sub {
        let t = (i as f64 + 0.5) * dt;
        for j in 0..np * sub {
            let p = (j as f64 + 0.5) * dp;
            let d = Vec3::new(
                (t.sin() * p.cos()) as f32,
                (t.sin() * p.sin()) as f32,
                t.cos() as f32,
            );
            expected[(i / sub) * np + j / sub] +=
                f64::from(map.pdf(d)) * t.sin() * dt * dp * f64::from(n);
        }
    }
    // Bins expecting fewer than 5 are pooled (the usual rule).
    let (mut chi2, mut dof, mut pool_o, mut pool_e) = (0.0, 0usize, 0.0, 0.0);
    for (o, e) in observed.iter().zip(&expected) {
        if *e < 5.0 {
            pool_o += o;
            pool_e += e;
        } else {
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pool_e > 0.0 {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e.max(1.0);
        dof += 1;
    }
    let dof = (dof - 1) as f64;
    // The 0.1% point of χ² with dof degrees of freedom (Wilson-Hilferty).
    let z = 3.09;
    let limit = dof * (1.0 - 2.0 / (9.0 * dof) + z * (2.0 / (9.0 * dof)).sqrt()).powi(3);
    eprintln!("χ² {chi2:.1} on {dof} degrees of freedom, 0.1% point {limit:.1}");
    assert!(chi2 < limit, "χ² {chi2} > {limit} ({dof} dof)");
    // A wrong pdf fails: the samples of the map unrotated against the rotated pdf.
    let unrotated = probe(64, 32, 30.0, 10.0);
    let mut moved = vec![0f64; nt * np];
    for _ in 0..n {
        moved[bin(unrotated.sample([next(), next()]).unwrap().wi)] += 1.0;
    }
    let wrong: f64 = (moved.iter().zip(&expected))
        .filter(|(_, e)| **e >= 5.0)
        .map(|(o, e)| (o - e) * (o - e) / e)
        .sum();
    assert!(wrong > 10.0 * limit, "the wrong pdf's χ² {wrong}");
}

#[test]
fn bad_maps_are_refused_in_one_line() {
    let one = |r: Result<EnvMap, RenderError>| {
        let e = r.unwrap_err().to_string();
        assert!(!e.contains('\n'), "{e}");
        e
    };
    assert!(one(EnvMap::new(2, 1, vec![[0.0; 3], [f32::NAN, 0.0, 0.0]])).contains("(1, 0)"));
    assert!(one(EnvMap::new(1, 2, vec![[0.0; 3], [0.0, -1.0, 0.0]])).contains("(0, 1)"));
    assert!(one(EnvMap::new(1, 1, vec![[f32::INFINITY; 3]])).contains("finite"));
    assert!(one(EnvMap::new(0, 4, vec![])).contains("0x4"));
    assert!(one(EnvMap::new(1 << 20, 4, vec![])).contains("texels"));
    assert!(one(EnvMap::new(2, 2, vec![[0.0; 3]; 3])).contains("holds 3"));
    let ok = || EnvMap::constant([1.0; 3], 4, 2).unwrap();
    assert!(one(ok().placed(f64::NAN, 1.0)).contains("rotation"));
    assert!(one(ok().placed(0.0, -1.0)).contains("intensity"));
    assert!(one(ok().placed(0.0, f32::INFINITY)).contains("intensity"));
}

#[test]
fn rotation_turns_the_map_about_the_vertical_axis() {
    let map = probe(64, 32, 50.0, 8.0);
    let turned = probe(64, 32, 50.0, 8.0).placed(90.0, 3.0).unwrap();
    // The source at azimuth 70° is at 160° once turned by 90°.
    let at = |phi: f32| {
        let (t, p) = (50f32.to_radians(), phi.to_radians());
        Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
    };
    assert_eq!(map.eval(at(70.0)), [50.0; 3]);
    assert_eq!(turned.eval(at(160.0)), [150.0; 3]);
    assert!(turned.eval(at(70.0))[0] < 1.0);
}

/// The variance of a one-event estimator of the map's light reflected by a surface:
/// `strategy` 0 the map's sampling alone, 1 the scattering model's alone, 2 both by
/// the power heuristic (two samples per estimate in each). Returns (mean, variance) of the luminance
/// over `n` estimates.
fn reflected(map: &EnvMap, bsdf: &Bsdf<'_>, wo: Vec3, strategy: u32, n: u32) -> (f64, f64) {
    let (mut sum, mut sq) = (0.0f64, 0.0f64);
    let mut state = 99u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 40) as f32) / (1u64 << 24) as f32
    };
    for _ in 0..n {
        let mut l = [0.0f32; 3];
        // Two samples per estimate for every strategy (equal cost): two of the map's,
        // two of the scattering model's, or one of each weighted by MIS.
        let (lights, scatters, k) = match strategy {
            0 => (2, 0, 0.5),
            1 => (0, 2, 0.5),
            _ => (1, 1, 1.0),
        };
        for _ in 0..lights {
            if let Some(s) = map.sample([next(), next()]) {
                let f = bsdf.f(wo, s.wi);
                let w = if strategy == 2 {
                    power_heuristic(s.pdf, bsdf.pdf(wo, s.wi))
                } else {
                    1.0
                };
                for c in 0..3 {
                    l[c] += k * f[c] / PI * s.radiance[c] * w / s.pdf;
                }
            }
        }
        for _ in 0..scatters {
            if let Some(s) = bsdf.sample(wo, [next(), next(), next()]) {
                let le = map.eval(s.wi);
                let w = if strategy == 2 {
                    power_heuristic(s.pdf, map.pdf(s.wi))
                } else {
                    1.0
                };
                for c in 0..3 {
                    l[c] += k * s.weight[c] * le[c] * w;
                }
            }
        }
        let y = f64::from(crate::color::luminance_f32(l));
        sum += y;
        sq += y * y;
    }
    let mean = sum / f64::from(n);
    (mean, sq / f64::from(n) - mean * mean)
}

#[test]
fn mis_has_the_mean_of_either_strategy_and_less_variance() {
    // A small bright source (3° in radius, radiance 400) and a broad patch (30°,
    // radiance 3) seen by a strongly forward-scattering medium (g = 0.9) looking into
    // the patch: the phase function's sampling finds the patch but rarely the source,
    // the map's finds the source but spreads its samples over the patch, where the
    // phase function peaks (Veach's glossy plates, 1997, fig. 9.8, in a medium).
    let cam = Camera::frame(&CameraSpec::default(), Vec3::ZERO, 1.0, 8, 8).unwrap();
    let shader = Shader::new(
        LobeKind::EnergyFit,
        20.0,
        4,
        Geometry::Phong,
        Material::default(),
        vec![],
        0.0,
    )
    .unwrap()
    .with_anisotropy(0.9)
    .unwrap()
    .placed(&cam);
    let bsdf = shader.scattering([0.8; 3], Vec3::ZERO).choose(|| 0.0);
    assert!(!bsdf.is_surface());
    let patch = Vec3::new(-(32f32.to_radians().sin()), 0.0, 32f32.to_radians().cos());
    let wo = -patch;
    let map = probe(256, 128, 400.0, 3.0);
    let n = 400_000;
    let (light, var_light) = reflected(&map, &bsdf, wo, 0, n);
    let (scatter, var_scatter) = reflected(&map, &bsdf, wo, 1, n);
    let (mis, var_mis) = reflected(&map, &bsdf, wo, 2, n);
    let se = |v: f64| (v / f64::from(n)).sqrt();
    eprintln!(
        "means: light {light:.4} ± {:.4}, scattering {scatter:.4} ± {:.4}, MIS {mis:.4} ± {:.4}",
        se(var_light),
        se(var_scatter),
        se(var_mis)
    );
    eprintln!(
        "variances: light {var_light:.4}, scattering {var_scatter:.4}, MIS {var_mis:.4}: MIS / best single {:.3}",
        var_mis / var_light.min(var_scatter)
    );
    for (name, m, v) in [
        ("light", light, var_light),
        ("scatter", scatter, var_scatter),
    ] {
        let tol = 4.0 * (se(v) + se(var_mis));
        assert!((m - mis).abs() < tol, "{name} {m} vs MIS {mis} (±{tol})");
    }
    assert!(var_mis < var_light.min(var_scatter) / 3.0);
}

#[test]
fn the_guide_tables_find_the_binary_searchs_segment() {
    // The guided search is an exact replacement: for numbers spread over [0, 1), the
    // ends, and the CDF entries themselves (where a tie decides), every row's and the
    // marginal's segment is the full binary search's.
    let map = probe(200, 100, 4000.0, 3.0);
    let mut cdfs: Vec<&Guided> = map.conditional.iter().collect();
    cdfs.push(&map.marginal);
    let mut checked = 0;
    for g in cdfs {
        let mut us: Vec<f32> = (0..997).map(|i| i as f32 / 997.0).collect();
        us.extend(g.cdf.iter().copied().filter(|&c| c < 1.0));
        us.extend([0.0, 1.0 - f32::EPSILON, 0.5 * f32::EPSILON]);
        for u in us {
            assert_eq!(
                g.first_above(u),
                g.cdf.partition_point(|&c| c <= u),
                "u = {u}"
            );
            checked += 1;
        }
    }
    assert!(checked > 100 * 997, "{checked}");
}
