use std::f64::consts::PI as PI64;

use glint_lobe::{Geometry, LobeKind};

use super::*;
use crate::camera::{Camera, CameraSpec};
use crate::lighting::fixtures::sphere_integral;
use crate::lighting::{power_heuristic, Bsdf, Material, Shader};

/// A deterministic uniform generator (a 64-bit LCG's high bits).
fn uniform(seed: u64) -> impl FnMut() -> f32 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 40) as f32) / (1u64 << 24) as f32
    }
}

/// The lights the sampling tests check, each with the point it is seen from: a sphere
/// filling a broad cone, a sphere below the small-angle threshold, a tilted rectangle.
fn lights() -> Vec<(AreaLight, Vec3)> {
    vec![
        (
            AreaLight::sphere(Vec3::new(1.0, 2.0, 3.0), 2.0, [2.0, 1.0, 0.5]).unwrap(),
            Vec3::new(1.5, 2.5, -1.0),
        ),
        (
            AreaLight::sphere(Vec3::new(0.0, 0.0, 200.0), 2.0, [1.0; 3]).unwrap(),
            Vec3::ZERO,
        ),
        (
            AreaLight::rect(
                Vec3::new(0.0, 0.0, 4.0),
                Vec3::new(0.0, 2.0, 0.0),
                Vec3::new(3.0, 0.0, 1.0),
                [1.0; 3],
            )
            .unwrap(),
            Vec3::new(-3.0, 1.0, 0.0),
        ),
    ]
}

#[test]
fn the_pdf_integrates_to_one_over_the_sphere() {
    for (k, (light, p)) in lights().into_iter().enumerate().filter(|(k, _)| *k != 1) {
        let total = sphere_integral(1500, |d| f64::from(light.pdf(p, d)));
        assert!((total - 1.0).abs() < 5e-3, "light {k}: ∫pdf = {total}");
    }
    // The small sphere subtends 3e-4 sr: integrate over its cone alone, finely, in
    // the cone's own frame.
    let (light, p) = lights()[1];
    let (n, theta_max) = (2000, (2.0f64 / 200.0).asin() * 1.2);
    let mut total = 0.0;
    for i in 0..n {
        let t = (i as f64 + 0.5) * theta_max / n as f64;
        for j in 0..n {
            let f = (j as f64 + 0.5) * 2.0 * PI64 / n as f64;
            let d = Vec3::new(
                (t.sin() * f.cos()) as f32,
                (t.sin() * f.sin()) as f32,
                t.cos() as f32,
            );
            let dw = t.sin() * (theta_max / n as f64) * (2.0 * PI64 / n as f64);
            total += f64::from(light.pdf(p, d)) * dw;
        }
    }
    assert!((total - 1.0).abs() < 1e-2, "small sphere: ∫pdf = {total}");
}

#[test]
fn samples_lie_on_the_light_with_the_density_pdf_reports() {
    for (k, (light, p)) in lights().into_iter().enumerate() {
        let mut u = uniform(7 + k as u64);
        for _ in 0..2000 {
            let s = light
                .sample(p, [u(), u()])
                .expect("the point sees the light");
            assert!((s.wi.length() - 1.0).abs() < 1e-5);
            let q = p + s.wi * s.dist;
            match light.shape() {
                AreaShape::Sphere { center, radius } => {
                    let off = ((q - center).length() - radius).abs();
                    assert!(off < 2e-3 * radius, "light {k}: {off} off the sphere");
                }
                AreaShape::Rect {
                    center,
                    edge_u,
                    edge_v,
                } => {
                    let n = edge_u.cross(edge_v).normalize_or_zero();
                    assert!((q - center).dot(n).abs() < 1e-4, "light {k}: off the plane");
                }
            }
            let pdf = light.pdf(p, s.wi);
            // A direction on the cone's very edge may miss the sphere by rounding.
            if pdf > 0.0 {
                assert!(
                    (pdf / s.pdf - 1.0).abs() < 1e-3,
                    "light {k}: {pdf} vs {}",
                    s.pdf
                );
                let t = light.intersect(p, s.wi).unwrap();
                assert!(
                    (t - s.dist).abs() < 1e-3 * s.dist.max(1.0),
                    "light {k}: {t} vs {}",
                    s.dist
                );
            }
            assert_eq!(s.radiance, light.radiance());
        }
    }
}

#[test]
fn the_samples_have_the_moments_of_the_pdf() {
    // The mean direction and the mean of its squares over 200,000 samples against
    // the pdf's own, by quadrature: a wrong distribution over the cone or the
    // rectangle (e.g. uniform in θ, or area sampling without d²/cos) moves them.
    for (k, (light, p)) in lights().into_iter().enumerate().filter(|(k, _)| *k != 1) {
        let moments = |d: Vec3| [d.x, d.y, d.z, d.x * d.x, d.y * d.y, d.z * d.z].map(f64::from);
        let mut want = [0.0f64; 6];
        for (a, w) in want.iter_mut().enumerate() {
            *w = sphere_integral(1000, |d| f64::from(light.pdf(p, d)) * moments(d)[a]);
        }
        let n = 200_000;
        let mut got = [0.0f64; 6];
        let mut u = uniform(11 + k as u64);
        for _ in 0..n {
            let s = light.sample(p, [u(), u()]).unwrap();
            for (g, m) in got.iter_mut().zip(moments(s.wi)) {
                *g += m / f64::from(n);
            }
        }
        for a in 0..6 {
            assert!(
                (got[a] - want[a]).abs() < 3e-3,
                "light {k}, moment {a}: sampled {} vs pdf {}",
                got[a],
                want[a]
            );
        }
    }
}

/// The irradiance at `p` on a plane of unit normal `n` by `count` samples of the
/// light: the mean of `L·max(n·wi, 0)/pdf`.
fn sampled_irradiance(light: &AreaLight, p: Vec3, n: Vec3, count: u32) -> f64 {
    let mut u = uniform(3);
    let mut sum = 0.0;
    for _ in 0..count {
        if let Some(s) = light.sample(p, [u(), u()]) {
            sum += f64::from(s.radiance[0] * s.wi.dot(n).max(0.0) / s.pdf);
        }
    }
    sum / f64::from(count)
}

#[test]
fn a_sphere_gives_its_closed_form_irradiance_on_its_axis() {
    // E = π·L·(r/d)² on a plane facing a sphere of radius r at distance d.
    for (r, d) in [(1.0f32, 1.5f32), (2.0, 10.0), (0.5, 300.0)] {
        let light = AreaLight::sphere(Vec3::new(0.0, 0.0, d), r, [3.0; 3]).unwrap();
        let want = PI64 * 3.0 * f64::from(r / d).powi(2);
        let got = sampled_irradiance(&light, Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0), 100_000);
        assert!(
            (got / want - 1.0).abs() < 3e-3,
            "r {r}, d {d}: {got} vs {want}"
        );
        let (dir, e) = light.irradiance(Vec3::ZERO).unwrap();
        assert!((dir.z - 1.0).abs() < 1e-6);
        assert!((f64::from(e) / want - 1.0).abs() < 1e-4, "{e} vs {want}");
    }
}

/// The form factor from a point to a parallel rectangle of sides `a`, `b` at distance
/// `c` with the point facing one of its corners (Howell's catalogue, B-3).
fn corner_form_factor(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI64)
}

#[test]
fn a_rectangle_gives_its_form_factor_irradiance_on_its_axis() {
    // A w×h rectangle at distance d facing the point: four corner form factors of
    // w/2 × h/2, E = π·L·F.
    for (w, h, d) in [(2.0f32, 1.0f32, 1.0f32), (4.0, 4.0, 10.0), (1.0, 3.0, 0.5)] {
        let light = AreaLight::rect(
            Vec3::new(0.0, 0.0, d),
            Vec3::new(0.0, h, 0.0),
            Vec3::new(w, 0.0, 0.0),
            [2.0; 3],
        )
        .unwrap();
        let f = 4.0 * corner_form_factor(f64::from(w) / 2.0, f64::from(h) / 2.0, f64::from(d));
        let want = PI64 * 2.0 * f;
        let got = sampled_irradiance(&light, Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0), 200_000);
        assert!(
            (got / want - 1.0).abs() < 1e-2,
            "{w}x{h} at {d}: {got} vs {want}"
        );
    }
    // The far rectangle's point-source irradiance is close; the near one's is not.
    let far = AreaLight::rect(
        Vec3::new(0.0, 0.0, 10.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        [1.0; 3],
    )
    .unwrap();
    let want = PI64 * 4.0 * corner_form_factor(0.5, 0.5, 10.0);
    let (_, e) = far.irradiance(Vec3::ZERO).unwrap();
    assert!((f64::from(e) / want - 1.0).abs() < 5e-3, "{e} vs {want}");
}

#[test]
fn the_back_of_a_rectangle_and_the_inside_of_a_sphere_are_dark() {
    let rect = AreaLight::rect(
        Vec3::ZERO,
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        [1.0; 3],
    )
    .unwrap();
    let below = Vec3::new(0.1, 0.0, -2.0);
    assert!(rect.sample(below, [0.3, 0.7]).is_none());
    assert_eq!(rect.pdf(below, Vec3::new(0.0, 0.0, 1.0)), 0.0);
    assert!(rect.intersect(below, Vec3::new(0.0, 0.0, 1.0)).is_none());
    let above = Vec3::new(0.1, 0.0, 2.0);
    assert_eq!(rect.intersect(above, Vec3::new(0.0, 0.0, -1.0)), Some(2.0));
    let sphere = AreaLight::sphere(Vec3::ZERO, 1.0, [1.0; 3]).unwrap();
    assert!(sphere
        .sample(Vec3::new(0.2, 0.0, 0.0), [0.5, 0.5])
        .is_none());
    assert!(sphere
        .intersect(Vec3::new(0.2, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0))
        .is_none());
    assert_eq!(
        sphere.intersect(Vec3::new(-3.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)),
        Some(2.0)
    );
}

#[test]
fn zero_negative_and_nan_sizes_are_refused() {
    let c = Vec3::ZERO;
    for r in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        assert!(AreaLight::sphere(c, r, [1.0; 3]).is_err(), "radius {r}");
    }
    let (u, v) = (Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
    assert!(AreaLight::rect(c, Vec3::ZERO, v, [1.0; 3]).is_err());
    assert!(AreaLight::rect(c, u, Vec3::new(0.0, f32::NAN, 0.0), [1.0; 3]).is_err());
    assert!(AreaLight::rect(c, u, Vec3::new(1.0, 1.0, 0.0), [1.0; 3]).is_err());
    assert!(AreaLight::sphere(c, 1.0, [1.0, -1.0, 0.0]).is_err());
    assert!(AreaLight::sphere(Vec3::new(f32::NAN, 0.0, 0.0), 1.0, [1.0; 3]).is_err());
    let e = AreaLight::sphere(c, 0.0, [1.0; 3]).unwrap_err().to_string();
    assert!(!e.contains('\n') && e.contains("radius"), "{e}");
}

/// The reflected radiance towards `wo` of the light through `bsdf` by `strategy`: 0
/// the light's sampling (two samples), 1 the scattering model's (two), 2 one of each
/// weighted by the power heuristic. Mean and variance per estimate over `n`.
fn reflected(light: &AreaLight, bsdf: &Bsdf<'_>, wo: Vec3, strategy: u32, n: u32) -> (f64, f64) {
    let (mut sum, mut sq) = (0.0f64, 0.0f64);
    let mut next = uniform(99);
    let (lights, scatters, k) = match strategy {
        0 => (2, 0, 0.5),
        1 => (0, 2, 0.5),
        _ => (1, 1, 1.0),
    };
    for _ in 0..n {
        let mut l = [0.0f32; 3];
        for _ in 0..lights {
            if let Some(s) = light.sample(Vec3::ZERO, [next(), next()]) {
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
            let Some(s) = bsdf.sample(wo, [next(), next(), next()]) else {
                continue;
            };
            if light.intersect(Vec3::ZERO, s.wi).is_some() {
                let w = if strategy == 2 {
                    power_heuristic(s.pdf, light.pdf(Vec3::ZERO, s.wi))
                } else {
                    1.0
                };
                let le = light.radiance();
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

/// Prints and checks one MIS case: the means of the three strategies agree within
/// their noise; returns the variances (light, scattering, MIS).
fn mis_case(name: &str, light: &AreaLight, bsdf: &Bsdf<'_>, wo: Vec3) -> [f64; 3] {
    let n = 200_000;
    let se = |v: f64| (v / f64::from(n)).sqrt();
    let (l, var_l) = reflected(light, bsdf, wo, 0, n);
    let (s, var_s) = reflected(light, bsdf, wo, 1, n);
    let (m, var_m) = reflected(light, bsdf, wo, 2, n);
    eprintln!(
        "{name}: means light {l:.5} ± {:.5}, scattering {s:.5} ± {:.5}, MIS {m:.5} ± {:.5}",
        se(var_l),
        se(var_s),
        se(var_m)
    );
    eprintln!(
        "{name}: variances light {var_l:.4e}, scattering {var_s:.4e}, MIS {var_m:.4e}: MIS / best single {:.3}",
        var_m / var_l.min(var_s)
    );
    for (what, x, v) in [("light", l, var_l), ("scattering", s, var_s)] {
        let tol = 4.0 * (se(v) + se(var_m)) + 1e-9;
        assert!(
            (x - m).abs() < tol,
            "{name}: {what} {x} vs MIS {m} (±{tol})"
        );
    }
    [var_l, var_s, var_m]
}

#[test]
fn mis_has_the_mean_of_either_strategy_and_less_variance() {
    // Veach's two cases (1997, fig. 9.8) with one light each: (a) a small bright
    // sphere (radius 0.2 mm at 10 mm, radiance 500) seen by a medium of g = 0.9 whose
    // phase function peaks 8.5° from it: the phase function's sampling seldom finds
    // it: the light's sampling wins; (b) a glossy surface (Phong, shininess 2000,
    // specular 1, diffuse 0.2) under a 4x4 mm rectangle 2 mm above it that holds the
    // mirror direction: the rectangle's sampling seldom finds the narrow lobe, the
    // lobe's sampling finds it but samples the diffuse part by the cosine, over the
    // whole hemisphere.
    let cam = Camera::frame(&CameraSpec::default(), Vec3::ZERO, 1.0, 8, 8).unwrap();
    let shader = |g: f32, n: f64, material: Material| {
        Shader::new(
            LobeKind::EnergyFit,
            n,
            4,
            Geometry::Phong,
            material,
            vec![],
            0.0,
        )
        .unwrap()
        .with_anisotropy(g)
        .unwrap()
        .placed(&cam)
    };
    let forward = shader(0.9, 60.0, Material::default());
    let medium = forward.scattering([0.8; 3], Vec3::ZERO).choose(|| 0.0);
    assert!(!medium.is_surface());
    let sphere = AreaLight::sphere(Vec3::new(0.0, 0.0, 10.0), 0.2, [500.0; 3]).unwrap();
    let wo = -Vec3::new(0.15, 0.0, 1.0).normalize_or_zero();
    let [l, s, m] = mis_case("small sphere, medium g=0.9", &sphere, &medium, wo);
    assert!(m < s / 1000.0 && m < 2.5 * l, "{l} {s} {m}");

    let glossy = shader(
        0.0,
        2000.0,
        Material {
            ambient: 0.0,
            diffuse: 0.2,
            specular: 1.0,
            shade: true,
        },
    );
    let surface = glossy
        .scattering([0.8; 3], Vec3::new(0.0, 0.0, -10.0))
        .choose(|| 0.0);
    assert!(surface.is_surface());
    let rect = AreaLight::rect(
        Vec3::new(2.0, 0.0, 2.0),
        Vec3::new(0.0, 4.0, 0.0),
        Vec3::new(4.0, 0.0, 0.0),
        [5.0; 3],
    )
    .unwrap();
    let wo = Vec3::new(-1.5, 0.0, 1.0).normalize_or_zero();
    let [l, s, m] = mis_case("rectangle, glossy surface", &rect, &surface, wo);
    // The rectangle's solid-angle sampling is already good here: MIS costs a third
    // more than it (half its samples go to the lobe) and an order less than the
    // lobe's alone.
    assert!(m < s / 10.0 && m < 2.0 * l, "{l} {s} {m}");
}
