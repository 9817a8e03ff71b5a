//! Tests of the one scattering model: the local and shadowed models are `ambient +
//! Σ I·f`, the densities integrate to one, samples carry their own density and the
//! weight `f/(π·pdf)`, and the sampled estimator of the albedo agrees with `f`
//! integrated over the sphere.

use std::f64::consts::PI as PI64;

use super::*;
use crate::lighting::fixtures::{shaders, sphere_integral};
use crate::lighting::Material;

/// A deterministic uniform stream in `[0, 1)` (SplitMix64).
struct Uniform(u64);

impl Uniform {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 40) as f32 / (1u64 << 24) as f32
    }
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

#[test]
fn local_and_shadowed_models_are_ambient_plus_the_lights_times_f() {
    let views = [
        Vec3::new(0.2, -0.1, 1.0),
        Vec3::new(-0.6, 0.3, 0.5),
        Vec3::new(0.0, 0.9, -0.4),
    ];
    let base = [0.8, 0.5, 0.3];
    for shader in shaders(0.0) {
        let shader = shader.with_anisotropy(0.4).unwrap();
        let m = *shader.material();
        let lights = shader.world_lights().to_vec();
        let t: Vec<f32> = (0..lights.len()).map(|i| 0.9 - 0.3 * i as f32).collect();
        for v in views.map(Vec3::normalize_or_zero) {
            let ray = shader.for_ray(v);
            for n in [v, Vec3::new(0.3, 0.4, 0.5), Vec3::new(-0.7, 0.1, 0.2)] {
                let n = n.normalize_or_zero();
                // A surface point: c·ambient + Σ I·f.
                let surface = shader.scattering_normal(base, n).choose(|| 0.0);
                assert!(surface.is_surface());
                let got = shader.shade_normal(base, n, v);
                let mut want = base.map(|c| c * m.ambient);
                for &(l, i) in &lights {
                    let f = surface.f(v, l);
                    (0..3).for_each(|c| want[c] += i * f[c]);
                }
                for c in 0..3 {
                    assert!(close(got[c], want[c], 1e-5), "{got:?} vs {want:?}");
                }
                // A strong gradient (full surface weight), shadowed: c·ambient·occ +
                // Σ I·T·f; the same for the medium where the gradient is zero.
                for (grad, medium) in [(n * -4.0, false), (Vec3::ZERO, true)] {
                    let s = shader.scattering(base, grad);
                    assert_eq!(s.surface().is_none(), medium);
                    let bsdf = s.choose(|| 0.0);
                    assert_eq!(bsdf.is_surface(), !medium);
                    let got = shader.shade_shadowed(base, grad, &ray, &t, 0.6);
                    let mut want = base.map(|c| c * m.ambient * 0.6);
                    for (&(l, i), &t) in lights.iter().zip(&t) {
                        let f = bsdf.f(v, l);
                        (0..3).for_each(|c| want[c] += i * t * f[c]);
                    }
                    for c in 0..3 {
                        assert!(close(got[c], want[c], 1e-5), "{got:?} vs {want:?}");
                    }
                }
            }
        }
    }
}

#[test]
fn an_unshaded_material_is_its_colour_in_every_model() {
    let m = Material {
        shade: false,
        ..Material::default()
    };
    let shader = Shader::new(
        glint_lobe::LobeKind::Exact,
        10.0,
        4,
        glint_lobe::Geometry::Phong,
        m,
        vec![crate::lighting::Light::HEADLIGHT],
        0.0,
    )
    .unwrap();
    let v = Vec3::new(0.0, 0.0, 1.0);
    let ray = shader.for_ray(v);
    let base = [0.3, 0.6, 0.9];
    assert_eq!(shader.shade(base, v * -3.0, &ray), base);
    assert_eq!(shader.shade_normal(base, v, v), base);
    assert_eq!(
        shader.shade_shadowed(base, v * -3.0, &ray, &[0.5], 0.5),
        base
    );
    // A path scatters it as the medium.
    let s = shader.scattering(base, v * -3.0);
    assert!(s.surface().is_none());
    assert!(!s
        .choose(|| unreachable!("no surface, no draw"))
        .is_surface());
}

#[test]
fn a_surface_is_chosen_with_the_probability_of_its_weight() {
    let shader = &shaders(0.5)[0];
    let grad = Vec3::new(0.0, 0.0, -0.8); // weight (0.8 - 0.5) / 0.5 = 0.6
    let s = shader.scattering([1.0; 3], grad);
    let w = s.surface().unwrap().weight;
    assert!(close(w, 0.6, 1e-6), "{w}");
    assert!(s.choose(|| 0.59).is_surface());
    assert!(!s.choose(|| 0.61).is_surface());
}

#[test]
fn densities_integrate_to_one_and_samples_carry_their_density_and_weight() {
    let wos = [Vec3::new(0.1, 0.2, 1.0), Vec3::new(0.8, -0.3, 0.3)];
    let base = [0.9, 0.7, 0.4];
    let mut u = Uniform(7);
    for (k, shader) in shaders(0.0).into_iter().enumerate() {
        let g = [0.0, 0.5, -0.7][k % 3];
        let shader = shader.with_anisotropy(g).unwrap();
        shader.check_sampling().unwrap();
        let blinn = shader.geometry() == glint_lobe::Geometry::Blinn;
        let normal = Vec3::new(0.0, 0.0, 1.0);
        for wo in wos.map(Vec3::normalize_or_zero) {
            let surface = shader.scattering_normal(base, normal).choose(|| 0.0);
            let medium = shader.scattering(base, Vec3::ZERO).choose(|| 0.0);
            for (bsdf, name) in [(surface, "surface"), (medium, "medium")] {
                let total = sphere_integral(300, |wi| f64::from(bsdf.pdf(wo, wi)));
                // Blinn's lobe loses the draws whose half vector faces away from wo.
                let ok = if blinn && bsdf.is_surface() {
                    total < 1.0 + 3e-3 && total > 0.8
                } else {
                    (total - 1.0).abs() < 3e-3
                };
                assert!(ok, "shader {k} {name}: ∫pdf = {total}");
                for _ in 0..2000 {
                    let Some(s) = bsdf.sample(wo, [u.next(), u.next(), u.next()]) else {
                        continue;
                    };
                    assert!((s.wi.length() - 1.0).abs() < 1e-4);
                    assert!(close(s.pdf, bsdf.pdf(wo, s.wi), 1e-4), "{name}");
                    let f = bsdf.f(wo, s.wi);
                    // One irradiance π·I for both parts: f/π is the BSDF (times N·wi).
                    for (w, f) in s.weight.iter().zip(f) {
                        assert!(close(*w, f / (PI * s.pdf), 2e-4), "{name}");
                    }
                }
            }
        }
    }
}

#[test]
fn sampled_albedo_matches_f_integrated_over_the_sphere() {
    // The estimator a path tracer forms, the mean of the weights, against the
    // directional albedo ∫ f/π dω (surface and medium alike) by quadrature.
    let base = [0.9, 0.7, 0.4];
    let wo = Vec3::new(0.3, -0.2, 0.9).normalize_or_zero();
    let normal = Vec3::new(0.0, 0.0, 1.0);
    let mut u = Uniform(11);
    for (k, shader) in shaders(0.0).into_iter().enumerate() {
        let shader = shader.with_anisotropy(0.6).unwrap();
        let surface = shader.scattering_normal(base, normal).choose(|| 0.0);
        let medium = shader.scattering(base, Vec3::ZERO).choose(|| 0.0);
        for (bsdf, over) in [(surface, PI64), (medium, PI64)] {
            let want = sphere_integral(400, |wi| f64::from(bsdf.f(wo, wi)[0]) / over);
            let n = 200_000;
            let got: f64 = (0..n)
                .filter_map(|_| bsdf.sample(wo, [u.next(), u.next(), u.next()]))
                .map(|s| f64::from(s.weight[0]))
                .sum::<f64>()
                / f64::from(n);
            assert!(
                (got - want).abs() < 0.01 * want.max(0.1),
                "shader {k}, surface {}: sampled {got} vs integrated {want}",
                bsdf.is_surface()
            );
        }
    }
}

#[test]
fn phase_samples_follow_the_phase_function() {
    // E[wi·wo] = -g in this convention, and a histogram of wi·wo against the density.
    let wo = Vec3::new(0.0, 0.6, 0.8);
    let mut u = Uniform(3);
    for g in [-0.7f32, 0.0, 0.4, 0.85] {
        let n = 400_000;
        let bins = 20;
        let mut hist = vec![0u32; bins];
        let mut mean = 0.0f64;
        for _ in 0..n {
            let wi = sample_phase(g, wo, u.next(), u.next());
            assert!((wi.length() - 1.0).abs() < 1e-4);
            let mu = wi.dot(wo).clamp(-1.0, 1.0);
            mean += f64::from(mu);
            hist[(((mu + 1.0) / 2.0 * bins as f32) as usize).min(bins - 1)] += 1;
        }
        mean /= n as f64;
        assert!((mean + f64::from(g)).abs() < 0.005, "g = {g}: mean {mean}");
        for (b, &count) in hist.iter().enumerate() {
            // The density of μ is (4π p)(μ)/2; its integral over the bin by the
            // midpoint rule on 50 points.
            let (lo, w) = (-1.0 + 2.0 * b as f64 / bins as f64, 2.0 / bins as f64);
            let want: f64 = (0..50)
                .map(|i| {
                    let mu = lo + (i as f64 + 0.5) * w / 50.0;
                    f64::from(phase_hg(g, mu as f32)) / 2.0 * w / 50.0
                })
                .sum();
            let got = f64::from(count) / n as f64;
            assert!(
                (got - want).abs() < 0.003 + 0.03 * want,
                "g = {g}, bin {b}: {got} vs {want}"
            );
        }
    }
}

#[test]
fn cosine_samples_have_mean_cosine_two_thirds() {
    let mut u = Uniform(5);
    let n = 200_000;
    let mean: f64 = (0..n)
        .map(|_| f64::from(cosine_hemisphere(u.next(), u.next())[2]))
        .sum::<f64>()
        / n as f64;
    assert!((mean - 2.0 / 3.0).abs() < 0.003, "{mean}");
}

#[test]
fn a_table_without_shininess_cannot_be_sampled_and_its_samples_end_paths() {
    let table = glint_lobe::CosTable::from_fn(10, |code| (code as f32 / 1024.0).max(0.0)).unwrap();
    let shader = Shader::with_specular(
        glint_lobe::Specular::from(table),
        glint_lobe::Geometry::Phong,
        Material::default(),
        vec![],
        0.0,
    )
    .unwrap();
    assert!(shader.check_sampling().is_err());
    let n = Vec3::new(0.0, 0.0, 1.0);
    let bsdf = shader.scattering_normal([1.0; 3], n).choose(|| 0.0);
    assert_eq!(bsdf.sample(n, [0.5; 3]), None);
    assert_eq!(bsdf.pdf(n, n), 0.0);
}
