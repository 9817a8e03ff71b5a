//! The area lights' light in `path` ([`AreaLight`], placed by the shader): at each
//! scattering event one direction drawn from each light by solid angle, its
//! transmittance by ratio tracking up to the light's surface (soft shadows), and the
//! lights met by the scattered paths, the two combined by multiple importance sampling
//! with the power heuristic (Veach 1997, as `envlight.rs` does for the environment
//! map): a direction a light drew is weighted by `p_light² / (p_light² + p_bsdf²)`, a
//! direction the scattering model drew that meets the light by `p_bsdf² / (p_light² +
//! p_bsdf²)`, both per steradian. Each light is its own estimator (one sample per
//! light per event, from a Sobol pair of its own for the first four events). Camera rays do not see the lights (they light the volume only);
//! a scattered path that meets one ends there. A scene without area lights draws no
//! number here: its images are the same bit for bit.

use std::f32::consts::PI;

use glint_core::lighting::AreaLight;
use glint_core::{power_heuristic, Bsdf, Vec3};

use super::path::{EnvStrategy, PathTracer};
use super::rng::Rng;
use super::tracking::IndexRay;

impl PathTracer<'_> {
    /// The world point of index-space point `p`.
    #[inline]
    pub(super) fn world_point(&self, p: Vec3) -> Vec3 {
        let w = self
            .track
            .field
            .index_to_world([p.x, p.y, p.z].map(f64::from));
        Vec3::new(w[0] as f32, w[1] as f32, w[2] as f32)
    }

    /// Adds the area lights' direct light at index point `p` through `bsdf` towards
    /// `wo` at event `event` (counted from 0): per light one direction drawn by solid
    /// angle (its pair of the sampler's numbers, [`Rng::area_dim`]),
    /// its radiance times the transmittance up to the light, weighted against the
    /// scattering model's density.
    #[inline]
    pub(super) fn area_direct(
        &self,
        (p, bsdf, wo): (Vec3, &Bsdf<'_>, Vec3),
        (rng, event): (&mut Rng, u32),
        beta: [f32; 3],
        radiance: &mut [f32; 3],
    ) {
        let lights = self.shader.area_lights();
        if lights.is_empty() {
            return;
        }
        let pw = self.world_point(p);
        let t0 = if bsdf.is_surface() {
            self.surface_bias
        } else {
            0.0
        };
        for (i, light) in lights.iter().enumerate() {
            let u = [0, 1].map(|k| rng.area_dim(event, i as u32, k));
            if self.area_strategy == EnvStrategy::Scatter {
                continue;
            }
            let Some(s) = light.sample(pw, u) else {
                continue;
            };
            if s.dist <= t0 {
                continue;
            }
            let f = bsdf.f(wo, s.wi);
            if f == [0.0; 3] {
                continue;
            }
            let weight = match self.area_strategy {
                EnvStrategy::Mis => power_heuristic(s.pdf, bsdf.pdf(wo, s.wi)),
                _ => 1.0,
            };
            let shadow = IndexRay {
                o: p,
                d: self.index_dir(s.wi),
            };
            if self.mesh_hit_between(&shadow, t0, s.dist).is_some() {
                continue;
            }
            let tr = self.track.transmittance(&shadow, t0, s.dist, rng);
            if tr <= 0.0 {
                continue;
            }
            // f is π times the BSDF (times the cosine for a surface).
            let k = weight * tr / (PI * s.pdf);
            for c in 0..3 {
                radiance[c] += beta[c] * f[c] * s.radiance[c] * k;
            }
        }
    }

    /// What ends a segment of a path besides the volume and its collisions: for a
    /// scattered ray (after `events > 0` events) over `(t0, t1)`, the meshes' first
    /// hit and the nearest area light in front of it (its index and distance); for a
    /// camera ray no mesh hit (it stops at `t1`, the meshes' depth), and the nearest
    /// area light only where the scene shows the environment and no mesh is behind
    /// (the camera then sees the light, opaque, as it sees the map).
    #[inline]
    pub(super) fn stops(
        &self,
        ray: &IndexRay,
        wdir: Vec3,
        (t0, t1): (f32, f32),
        events: u32,
    ) -> (Option<f32>, Option<(usize, f32)>) {
        if events == 0 {
            let shown = self.settings.show_environment && t1 == f32::INFINITY;
            return (
                None,
                shown.then(|| self.area_hit(ray.o, wdir, t0)).flatten(),
            );
        }
        let mesh = self.mesh_hit_between(ray, t0, t1);
        let area =
            (self.area_hit(ray.o, wdir, t0)).filter(|&(_, t)| t < mesh.unwrap_or(f32::INFINITY));
        (mesh, area)
    }

    /// The nearest area light the scattered ray from index point `o` along unit world
    /// `wdir` meets past `t0`: its index and distance (mm).
    #[inline]
    pub(super) fn area_hit(&self, o: Vec3, wdir: Vec3, t0: f32) -> Option<(usize, f32)> {
        let lights = self.shader.area_lights();
        if lights.is_empty() {
            return None;
        }
        let ow = self.world_point(o);
        (lights.iter().enumerate())
            .filter_map(|(i, l)| l.intersect(ow, wdir).map(|t| (i, t)))
            .filter(|&(_, t)| t > t0)
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }

    /// The radiance a path scattered from index point `o` along unit `wdir` (drawn
    /// with density `scatter_pdf`) takes from area light `i`, which it meets: the
    /// light's radiance weighted against the light's own density; a camera ray
    /// (`events == 0`, no density) takes it whole.
    #[inline]
    pub(super) fn area_escape(
        &self,
        i: usize,
        o: Vec3,
        wdir: Vec3,
        (scatter_pdf, events): (f32, u32),
    ) -> [f32; 3] {
        let light: &AreaLight = &self.shader.area_lights()[i];
        if events == 0 {
            return light.radiance();
        }
        let weight = match self.area_strategy {
            EnvStrategy::Mis => power_heuristic(scatter_pdf, light.pdf(self.world_point(o), wdir)),
            EnvStrategy::Light => 0.0,
            EnvStrategy::Scatter => 1.0,
        };
        light.radiance().map(|l| l * weight)
    }
}
