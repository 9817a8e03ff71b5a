//! The environment map's light in `path` ([`EnvMap`]): next-event estimation of the
//! map at each scattering event (a direction drawn from the map's luminance, its
//! transmittance by ratio tracking, as the directional lights'), and the map seen by
//! the paths that leave the volume, the two combined by multiple importance sampling
//! with the power heuristic (Veach 1997): a direction the map drew is weighted by
//! `p_map² / (p_map² + p_bsdf²)`, one the scattering model drew by
//! `p_bsdf² / (p_map² + p_bsdf²)`, both densities per steradian (`Bsdf::pdf`,
//! [`EnvMap::pdf`]). Without a map the uniform environment is lit as before (the paths
//! that leave see it), bit for bit.

use std::f32::consts::PI;

use glint_core::{power_heuristic, Bsdf, EnvMap, Vec3};

use super::path::{EnvStrategy, PathTracer};
use super::rng::Rng;
use super::tracking::IndexRay;

impl PathTracer<'_> {
    /// The radiance seen along unit `wdir` by a path that leaves the volume after
    /// `events` scattering events (its last direction drawn with density
    /// `scatter_pdf`): the uniform environment's, or the map's ([`Self::env_escape`]).
    #[inline]
    pub(super) fn escaped(&self, wdir: Vec3, events: u32, scatter_pdf: f32) -> [f32; 3] {
        match self.env_map {
            None => [self.settings.environment; 3],
            Some(map) => self.env_escape(map, wdir, events, scatter_pdf),
        }
    }

    /// Adds the map's direct light at `p` through `bsdf` towards `wo`: one direction
    /// drawn from the map (event `event`'s two numbers), its radiance times the
    /// transmittance towards it, weighted against the scattering model's density.
    #[inline]
    pub(super) fn env_direct(
        &self,
        map: &EnvMap,
        (p, bsdf, wo): (Vec3, &Bsdf<'_>, Vec3),
        (rng, event): (&mut Rng, u32),
        beta: [f32; 3],
        radiance: &mut [f32; 3],
    ) {
        let u = [rng.light_dim(event, 0), rng.light_dim(event, 1)];
        if self.env_strategy == EnvStrategy::Scatter {
            return;
        }
        let Some(s) = map.sample(u) else {
            return;
        };
        let f = bsdf.f(wo, s.wi);
        if f == [0.0; 3] {
            return;
        }
        let weight = match self.env_strategy {
            EnvStrategy::Mis => power_heuristic(s.pdf, bsdf.pdf(wo, s.wi)),
            _ => 1.0,
        };
        // f is π times the BSDF (times the cosine for a surface): see glint-core's
        // scattering model.
        let k = weight / (PI * s.pdf);
        let Some(survival) = self.env_survival(map, beta, f, s.radiance, k, rng) else {
            return;
        };
        let t0 = if bsdf.is_surface() {
            self.surface_bias
        } else {
            0.0
        };
        let shadow = IndexRay {
            o: p,
            d: self.index_dir(s.wi),
        };
        if self.mesh_hit_from(&shadow, t0).is_some() {
            return;
        }
        let tr = self.track.transmittance(&shadow, t0, f32::INFINITY, rng);
        if tr <= 0.0 {
            return;
        }
        let k = weight * tr / (PI * s.pdf);
        let k = if survival < 1.0 { k / survival } else { k };
        for c in 0..3 {
            radiance[c] += beta[c] * f[c] * s.radiance[c] * k;
        }
    }

    /// Russian roulette on the map's shadow ray: the probability of tracing it,
    /// `min(1, c / (r m))` for the contribution `c` it would add unshadowed
    /// (the largest channel of `beta f L k`) the map's mean radiance `m` and `r` the tracer's `env_roulette`, or `None`
    /// when it is not traced (one independent number drawn, only where the probability
    /// is below one). A traced ray's contribution is divided by the probability, so the
    /// estimate's mean is unchanged (Arvo and Kirk 1990; pbrt-v4 applies the same
    /// test to a path's throughput); the rays skipped are those that could add little.
    #[inline]
    fn env_survival(
        &self,
        map: &EnvMap,
        beta: [f32; 3],
        f: [f32; 3],
        l: [f32; 3],
        k: f32,
        rng: &mut Rng,
    ) -> Option<f32> {
        let c = (0..3)
            .map(|i| beta[i] * f[i] * l[i] * k)
            .fold(0.0f32, f32::max);
        if c.is_nan() || c <= 0.0 {
            return None;
        }
        let scale = self.env_roulette * map.mean_radiance();
        if c >= scale {
            return Some(1.0);
        }
        let q = c / scale;
        (rng.uniform() < q).then_some(q)
    }

    /// The map's radiance seen along unit `wdir` by a path that leaves the volume
    /// after `events` scattering events, its last direction drawn with density
    /// `scatter_pdf`: weighted against the map's own density after an event, in full
    /// for a camera ray.
    #[inline]
    pub(super) fn env_escape(
        &self,
        map: &EnvMap,
        wdir: Vec3,
        events: u32,
        scatter_pdf: f32,
    ) -> [f32; 3] {
        let weight = if events == 0 {
            1.0
        } else {
            match self.env_strategy {
                EnvStrategy::Mis => power_heuristic(scatter_pdf, map.pdf(wdir)),
                EnvStrategy::Light => 0.0,
                EnvStrategy::Scatter => 1.0,
            }
        };
        if weight == 0.0 {
            return [0.0; 3];
        }
        map.eval(wdir).map(|l| l * weight)
    }
}
