//! The lighting of a scene: which light-transport model (`local`, `shadows`, `path`)
//! and its settings, and the defaults [`Scene::resolve`](super::Scene) writes back.

use serde::{Deserialize, Serialize};

use glint_core::lighting::AreaLightSpec;
use glint_core::{RenderError, RenderMode, MAX_ANISOTROPY};
use glint_volume::{
    check_spp, check_time_budget, LightingModel, PathSettings, Sampler, ShadowSettings,
};

use crate::denoise::Denoise;

/// Samples per pixel of a `path` scene that does not say (a few seconds at 512x512
/// on two cores; docs/lighting.md).
pub const DEFAULT_SPP: u32 = 64;

/// Scattering events of a `path` scene that does not say: enough for light to cross
/// a skull's bone and come back (docs/lighting.md shows 1 to 16).
pub const DEFAULT_BOUNCES: u32 = 4;

/// Radiance of the uniform environment of a `path` scene that does not say: half the
/// intensity of the default headlight, so the key light still shapes the image.
pub const DEFAULT_ENVIRONMENT: f32 = 0.5;

/// How a scene is lit: the model and its settings. Settings left unset are chosen by
/// [`Scene::resolve`](super::Scene::resolve_for) for the model (and written back);
/// settings another model uses are refused, so a scene says nothing it does not do.
///
/// ```
/// use glint_render::{Input, Lighting, LightingModel, Phantom, ReadOptions, Renderer, Scene};
///
/// let scene = Scene {
///     input: Input::Phantom { name: Phantom::SheppLogan, size: 24 },
///     size: [16, 16],
///     lighting: Lighting { model: LightingModel::Path, spp: Some(2), ..Lighting::default() },
///     ..Scene::default()
/// };
/// let mut renderer = Renderer::open(&scene, &ReadOptions::default()).unwrap();
/// let rendered = renderer.render(&scene, &|_| {}).unwrap();
/// // The resolved scene names the defaults it used.
/// assert_eq!(rendered.scene.lighting.bounces, Some(glint_render::DEFAULT_BOUNCES));
/// assert_eq!(rendered.scene.lighting.seed, Some(0));
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Lighting {
    /// The light-transport model.
    pub model: LightingModel,
    /// `path`: samples per pixel [default: [`DEFAULT_SPP`]].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spp: Option<u32>,
    /// `path`: most scattering events of a path [default: [`DEFAULT_BOUNCES`]].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bounces: Option<u32>,
    /// `path`: the seed of the pixels' random numbers [default: 0].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// `path`: radiance of the uniform white environment [default:
    /// [`DEFAULT_ENVIRONMENT`]].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub environment: Option<f32>,
    /// `shadows` and `path`: the Henyey-Greenstein anisotropy of the medium's phase
    /// function, -0.95..=0.95 [default: 0, isotropic].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub anisotropy: Option<f32>,
    /// `shadows`: local ambient occlusion on the ambient term [default: false].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub occlusion: Option<bool>,
    /// `path`: where the paths' random numbers come from [default: `sobol`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sampler: Option<Sampler>,
    /// `path`: a time budget per frame in milliseconds (more than 0, at most one
    /// hour): the frame adds passes of samples, one per pixel until each holds a
    /// few, then where the noise is, until the budget is spent or no pixel below
    /// `spp` is noisy; `spp` is then the most a pixel takes [default: none: every
    /// pixel takes `spp`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_budget: Option<f64>,
    /// `path`: camera rays that meet no matter see the environment (opaque) instead
    /// of the background [default: false].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub show_environment: Option<bool>,
    /// `path`: how the image is denoised ([`Denoise`]: `none`, `atrous`, `oidn`,
    /// `auto`) [default: none, the mean of the samples]. Left unset by a resolve
    /// when not given, so scenes without it keep their JSON.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub denoise: Option<Denoise>,
    /// `path` and `shadows`: an environment map (in `path` instead of the uniform
    /// environment; in `shadows` as a few directional lights fitted to it): an
    /// equirectangular `.hdr` or `.exr` file, or a name: built in (`studio`;
    /// [`ENVIRONMENT_NAMES`](crate::ENVIRONMENT_NAMES)) or fetched by
    /// `scripts/fetch-samples` ([`FETCHED_ENVIRONMENTS`](crate::FETCHED_ENVIRONMENTS))
    /// [default: none].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub environment_map: Option<String>,
    /// `path` and `shadows`: degrees the environment map is turned about the vertical (superior)
    /// axis, -360..=360 [default: 0 with a map].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub environment_rotation: Option<f64>,
    /// `path` and `shadows`: the environment map's radiance scale [default: 1 with a map].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub environment_intensity: Option<f32>,
    /// `shadows` and `path`: scale of the surface part of the hybrid, 0..=1: 1 the
    /// gradient gate's weight as it is, 0 a pure medium (extinction, albedo and phase
    /// function only, what Mitsuba 3's `volpath` renders) [default: 1]. Left unset by a
    /// resolve when not given, so scenes without it keep their JSON.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surface_weight: Option<f32>,
    /// Every model: spheres and rectangles of constant radiance placed about the
    /// volume's centre ([`AreaLightSpec`]); `path` samples them (soft shadows),
    /// `local` and `shadows` take each as the directional light of its irradiance at
    /// the volume's centre [default: none]. Left out of the JSON when empty.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub area_lights: Vec<AreaLightSpec>,
}

/// The light transport of a resolved volume scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Transport {
    /// Every light reaches every sample.
    Local,
    /// Light volumes per light, optional ambient occlusion.
    Shadows(ShadowSettings),
    /// Path tracing to `spp` samples per pixel.
    Path {
        /// Samples per pixel.
        spp: u32,
        /// Bounces, seed, environment, sampler, time budget.
        settings: PathSettings,
        /// How the image is denoised ([`Denoise::effective`]: `auto` resolved).
        denoise: Denoise,
    },
}

impl Lighting {
    /// Whether it is the default (`local`, nothing set): scenes then leave it out of
    /// their JSON, so a local scene's file is what it was before lighting models.
    pub fn is_default(&self) -> bool {
        *self == Lighting::default()
    }

    /// The fields that are set, with their names.
    fn set_fields(&self) -> [(&'static str, bool); 14] {
        [
            ("spp", self.spp.is_some()),
            ("bounces", self.bounces.is_some()),
            ("seed", self.seed.is_some()),
            ("environment", self.environment.is_some()),
            ("anisotropy", self.anisotropy.is_some()),
            ("occlusion", self.occlusion.is_some()),
            ("sampler", self.sampler.is_some()),
            ("time_budget", self.time_budget.is_some()),
            ("show_environment", self.show_environment.is_some()),
            ("denoise", self.denoise.is_some()),
            ("environment_map", self.environment_map.is_some()),
            ("environment_rotation", self.environment_rotation.is_some()),
            (
                "environment_intensity",
                self.environment_intensity.is_some(),
            ),
            ("surface_weight", self.surface_weight.is_some()),
        ]
    }

    /// The fields `model` uses.
    fn used_by(model: LightingModel) -> &'static [&'static str] {
        match model {
            LightingModel::Local => &[],
            LightingModel::Shadows => &[
                "anisotropy",
                "occlusion",
                "surface_weight",
                "environment_map",
                "environment_rotation",
                "environment_intensity",
            ],
            LightingModel::Path => &[
                "spp",
                "bounces",
                "seed",
                "environment",
                "anisotropy",
                "sampler",
                "time_budget",
                "show_environment",
                "denoise",
                "environment_map",
                "environment_rotation",
                "environment_intensity",
                "surface_weight",
            ],
        }
    }

    /// This lighting with the fields its model does not use cleared (what a front end
    /// does when the user picks another model).
    pub fn for_model(&self, model: LightingModel) -> Lighting {
        let used = Lighting::used_by(model);
        let keep = |name: &str| used.contains(&name);
        Lighting {
            model,
            spp: self.spp.filter(|_| keep("spp")),
            bounces: self.bounces.filter(|_| keep("bounces")),
            seed: self.seed.filter(|_| keep("seed")),
            environment: self.environment.filter(|_| keep("environment")),
            anisotropy: self.anisotropy.filter(|_| keep("anisotropy")),
            occlusion: self.occlusion.filter(|_| keep("occlusion")),
            sampler: self.sampler.filter(|_| keep("sampler")),
            time_budget: self.time_budget.filter(|_| keep("time_budget")),
            show_environment: self.show_environment.filter(|_| keep("show_environment")),
            denoise: self.denoise.filter(|_| keep("denoise")),
            environment_map: self
                .environment_map
                .clone()
                .filter(|_| keep("environment_map")),
            environment_rotation: self
                .environment_rotation
                .filter(|_| keep("environment_rotation")),
            environment_intensity: self
                .environment_intensity
                .filter(|_| keep("environment_intensity")),
            surface_weight: self.surface_weight.filter(|_| keep("surface_weight")),
            area_lights: self.area_lights.clone(),
        }
    }

    /// Chooses the model's defaults (written into `self`) and checks every value and
    /// the render `mode`: `shadows` lights composite and iso renders, `path` composite
    /// ones; a surface render takes `local` only. Returns the transport and the phase
    /// function's anisotropy.
    pub(crate) fn resolve(&mut self, mode: RenderMode) -> Result<(Transport, f32), RenderError> {
        let model = self.model;
        let used = Lighting::used_by(model);
        if let Some((name, _)) = self
            .set_fields()
            .into_iter()
            .find(|(name, set)| *set && !used.contains(name))
        {
            return Err(RenderError::Parameter(format!(
                "lighting.{name} is not used by {} lighting",
                model.name()
            )));
        }
        let allowed = match model {
            LightingModel::Local => true,
            LightingModel::Shadows => matches!(mode, RenderMode::Composite | RenderMode::Iso),
            LightingModel::Path => mode == RenderMode::Composite,
        };
        if !allowed {
            return Err(RenderError::Parameter(format!(
                "{} lighting does not light {} mode",
                model.name(),
                mode.name()
            )));
        }
        let anisotropy = match model {
            LightingModel::Local => 0.0,
            _ => *self.anisotropy.get_or_insert(0.0),
        };
        if !anisotropy.is_finite() || anisotropy.abs() > MAX_ANISOTROPY {
            return Err(RenderError::Parameter(format!(
                "lighting.anisotropy {anisotropy}: expected -{MAX_ANISOTROPY}..={MAX_ANISOTROPY}"
            )));
        }
        if let Some(w) = self.surface_weight.filter(|w| !(0.0..=1.0).contains(w)) {
            return Err(RenderError::Parameter(format!(
                "lighting.surface_weight {w}: expected 0..=1"
            )));
        }
        let transport = match model {
            LightingModel::Local => Transport::Local,
            LightingModel::Shadows => {
                self.resolve_environment_map()?;
                Transport::Shadows(ShadowSettings {
                    occlusion: *self.occlusion.get_or_insert(false),
                })
            }
            LightingModel::Path => {
                let spp = *self.spp.get_or_insert(DEFAULT_SPP);
                check_spp(spp)?;
                let settings = PathSettings {
                    bounces: *self.bounces.get_or_insert(DEFAULT_BOUNCES),
                    seed: *self.seed.get_or_insert(0),
                    environment: self.resolve_environment()?,
                    sampler: *self.sampler.get_or_insert(Sampler::default()),
                    time_budget: self.time_budget.map(check_time_budget).transpose()?,
                    show_environment: *self.show_environment.get_or_insert(false),
                };
                settings.validate()?;
                let denoise = self.denoise.unwrap_or_default().effective()?;
                Transport::Path {
                    spp,
                    settings,
                    denoise,
                }
            }
        };
        Ok((transport, anisotropy))
    }
}

impl Lighting {
    /// The uniform environment's radiance (written back), or with a map 0 and the
    /// map's rotation and intensity written back; a map's settings without a map,
    /// or a map and a uniform radiance, are refused.
    fn resolve_environment(&mut self) -> Result<f32, RenderError> {
        if self.environment_map.is_none() {
            self.resolve_environment_map()?;
            return Ok(*self.environment.get_or_insert(DEFAULT_ENVIRONMENT));
        }
        if let Some(e) = self.environment {
            return Err(RenderError::Parameter(format!(
                "lighting.environment {e} and an environment_map: give one (the map replaces the uniform environment)"
            )));
        }
        self.resolve_environment_map()?;
        Ok(0.0)
    }

    /// With a map, its rotation and intensity written back; without one, its
    /// settings refused.
    fn resolve_environment_map(&mut self) -> Result<(), RenderError> {
        if self.environment_map.is_none() {
            if self.environment_rotation.is_some() || self.environment_intensity.is_some() {
                return Err(RenderError::Parameter(
                    "lighting.environment_rotation and environment_intensity need an environment_map".into(),
                ));
            }
            return Ok(());
        }
        self.environment_rotation.get_or_insert(0.0);
        self.environment_intensity.get_or_insert(1.0);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use glint_volume::Phantom;
    use serde_json::json;

    use super::*;
    use crate::{Input, ReadOptions, Renderer, Scene};

    fn small(lighting: Lighting) -> Scene {
        Scene {
            input: Input::Phantom {
                name: Phantom::SheppLogan,
                size: 24,
            },
            size: [20, 16],
            lighting,
            ..Scene::default()
        }
    }

    fn path(spp: u32) -> Lighting {
        Lighting {
            model: LightingModel::Path,
            spp: Some(spp),
            ..Lighting::default()
        }
    }

    #[test]
    fn local_scenes_leave_lighting_out_of_their_json() {
        let scene = small(Lighting::default());
        let text = scene.to_json().unwrap();
        assert!(!text.contains("lighting"), "{text}");
        let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
        let done = r.render(&scene, &|_| {}).unwrap();
        assert!(done.scene.lighting.is_default());
        assert!(!done.scene.to_json().unwrap().contains("lighting"));
    }

    #[test]
    fn resolving_writes_each_models_defaults_back() {
        let mut r = Renderer::open(&small(Lighting::default()), &ReadOptions::default()).unwrap();
        let shadows = Lighting {
            model: LightingModel::Shadows,
            ..Lighting::default()
        };
        let s = r.resolve(&small(shadows)).unwrap().scene.lighting;
        assert_eq!(
            (s.anisotropy, s.occlusion, s.spp),
            (Some(0.0), Some(false), None)
        );
        let p = r
            .resolve(&small(Lighting {
                model: LightingModel::Path,
                ..Lighting::default()
            }))
            .unwrap()
            .scene
            .lighting;
        assert_eq!(p.spp, Some(DEFAULT_SPP));
        assert_eq!(p.bounces, Some(DEFAULT_BOUNCES));
        assert_eq!(p.seed, Some(0));
        assert_eq!(p.environment, Some(DEFAULT_ENVIRONMENT));
        assert_eq!(p.occlusion, None);
    }

    #[test]
    fn settings_of_another_model_and_unlit_modes_are_refused() {
        let mut r = Renderer::open(&small(Lighting::default()), &ReadOptions::default()).unwrap();
        let bad = [
            (
                small(Lighting {
                    spp: Some(4),
                    ..Lighting::default()
                }),
                "lighting.spp",
            ),
            (
                small(Lighting {
                    occlusion: Some(true),
                    ..path(2)
                }),
                "lighting.occlusion",
            ),
            (
                small(Lighting {
                    anisotropy: Some(1.5),
                    ..path(2)
                }),
                "anisotropy",
            ),
            (small(path(0)), "spp 0"),
            (
                Scene {
                    mode: glint_core::RenderMode::Iso,
                    ..small(path(2))
                },
                "iso mode",
            ),
            (
                Scene {
                    mode: glint_core::RenderMode::Mip,
                    ..small(Lighting {
                        model: LightingModel::Shadows,
                        ..Lighting::default()
                    })
                },
                "mip mode",
            ),
            (
                small(Lighting {
                    bounces: Some(0),
                    ..path(2)
                }),
                "bounces 0",
            ),
            (
                small(Lighting {
                    surface_weight: Some(0.0),
                    ..Lighting::default()
                }),
                "lighting.surface_weight is not used by local",
            ),
            (
                small(Lighting {
                    surface_weight: Some(1.5),
                    ..path(2)
                }),
                "surface_weight 1.5",
            ),
        ];
        for (scene, needle) in bad {
            let err = r.resolve(&scene).unwrap_err().to_string();
            assert!(err.contains(needle), "{needle}: {err}");
        }
        // Picking a model keeps only its own settings.
        let l = Lighting {
            occlusion: Some(true),
            anisotropy: Some(0.2),
            ..path(8)
        }
        .for_model(LightingModel::Shadows);
        assert_eq!(
            (l.spp, l.occlusion, l.anisotropy),
            (None, Some(true), Some(0.2))
        );
    }

    #[test]
    fn area_lights_round_trip_light_every_model_and_bad_ones_are_one_line() {
        use glint_core::lighting::{AreaShapeSpec, LightFrame};
        let light = AreaLightSpec {
            shape: AreaShapeSpec::Sphere { radius: 10.0 },
            frame: LightFrame::Camera,
            position: [0.0, 0.0, 40.0],
            radiance: [20.0; 3],
        };
        let with = |model: LightingModel, area: Vec<AreaLightSpec>| Scene {
            lights: vec![],
            ..small(Lighting {
                model,
                spp: (model == LightingModel::Path).then_some(2),
                area_lights: area,
                ..Lighting::default()
            })
        };
        // The JSON names the lights when there are some, and nothing else changes.
        let text = with(LightingModel::Path, vec![light]).to_json().unwrap();
        assert!(text.contains("area_lights"), "{text}");
        let back = Scene::from_json(&text).unwrap();
        assert_eq!(back.lighting.area_lights, vec![light]);
        assert!(!small(path(2)).to_json().unwrap().contains("area_lights"));
        // Every model is lit by them alone (no directional light).
        let mut r = Renderer::open(&small(path(2)), &ReadOptions::default()).unwrap();
        for model in LightingModel::ALL {
            let done = r.render(&with(model, vec![light]), &|_| {}).unwrap();
            let lit = done.image.rgb.iter().map(|c| c[1]).fold(0.0f32, f32::max);
            assert!(lit > 0.0, "{}: {lit}", model.name());
        }
        // Bad lights: one line, naming what is wrong.
        let rect_at_centre = AreaLightSpec {
            shape: AreaShapeSpec::Rect { size: [10.0, 10.0] },
            position: [0.0; 3],
            ..light
        };
        let bad = [
            (AreaShapeSpec::Sphere { radius: 0.0 }, "size 0"),
            (AreaShapeSpec::Sphere { radius: f64::NAN }, "size NaN"),
            (AreaShapeSpec::Rect { size: [5.0, -1.0] }, "size -1"),
        ];
        for (shape, needle) in bad {
            let scene = with(LightingModel::Path, vec![AreaLightSpec { shape, ..light }]);
            let err = r.render(&scene, &|_| {}).unwrap_err().to_string();
            assert!(
                err.contains(needle) && !err.contains('\n'),
                "{needle}: {err}"
            );
        }
        let err = (r.render(&with(LightingModel::Shadows, vec![rect_at_centre]), &|_| {}))
            .unwrap_err()
            .to_string();
        assert!(err.contains("centre") && !err.contains('\n'), "{err}");
    }

    #[test]
    fn a_surface_weight_of_one_is_the_default_and_zero_a_pure_medium() {
        let render = |w: Option<f32>| {
            let scene = small(Lighting {
                surface_weight: w,
                ..path(2)
            });
            let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
            let done = r.render(&scene, &|_| {}).unwrap();
            assert_eq!(done.scene.lighting.surface_weight, w, "left as given");
            done.image
        };
        let unset = render(None);
        assert_eq!(render(Some(1.0)), unset, "1 multiplies exactly");
        // The phantom's edges are surfaces: without them the image changes.
        assert_ne!(render(Some(0.0)), unset);
    }

    #[test]
    fn samples_accumulate_while_only_the_count_changes() {
        let scene = small(path(4));
        let fresh = Renderer::open(&scene, &ReadOptions::default())
            .unwrap()
            .render(&scene, &|_| {})
            .unwrap();
        assert_eq!(fresh.scene.lighting.spp, Some(4));
        let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
        for spp in [1, 2, 4] {
            let step = r.render(&small(path(spp)), &|_| {}).unwrap();
            assert_eq!(r.path_samples(), spp);
            assert_eq!(step.scene.lighting.spp, Some(spp));
            if spp == 4 {
                // Three batches give the one-batch image bit for bit.
                assert_eq!(step.image, fresh.image);
            }
        }
        // Anything else changed starts again (and gives another image).
        let mut moved = small(path(4));
        moved.camera.azimuth = 40.0;
        let other = r.render(&moved, &|_| {}).unwrap();
        assert_eq!(r.path_samples(), 4);
        assert_ne!(other.image, fresh.image);
        r.render(&small(path(1)), &|_| {}).unwrap();
        assert_eq!(r.path_samples(), 1, "a new scene starts from no samples");
        // Fewer samples than held: start again.
        r.render(&small(path(3)), &|_| {}).unwrap();
        r.render(&small(path(2)), &|_| {}).unwrap();
        assert_eq!(r.path_samples(), 2);
        // The dumped scene renders the same image again.
        let again = Scene::from_json(&fresh.scene.to_json().unwrap()).unwrap();
        let re = Renderer::open(&again, &ReadOptions::default())
            .unwrap()
            .render(&again, &|_| {})
            .unwrap();
        assert_eq!(re.image, fresh.image);
    }

    #[test]
    fn a_cancelled_path_render_drops_its_samples_and_the_next_starts_clean() {
        use std::sync::atomic::{AtomicBool, Ordering};
        use std::sync::Arc;
        let scene = small(path(4));
        let fresh = Renderer::open(&scene, &ReadOptions::default())
            .unwrap()
            .render(&scene, &|_| {})
            .unwrap();
        let flag = Arc::new(AtomicBool::new(false));
        let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
        r.set_cancel(Some(flag.clone()));
        r.render(&small(path(2)), &|_| {}).unwrap();
        assert_eq!(r.path_samples(), 2);
        // Cancelled once the first row is done: some rows got samples, most did not.
        let cancelled = r.render(&scene, &|_| flag.store(true, Ordering::Relaxed));
        assert!(
            matches!(cancelled, Err(RenderError::Cancelled)),
            "{cancelled:?}"
        );
        assert_eq!(r.path_samples(), 0, "a part-added batch is dropped");
        // With the flag cleared the same scene renders as a fresh renderer's.
        flag.store(false, Ordering::Relaxed);
        let again = r.render(&scene, &|_| {}).unwrap();
        assert_eq!(again.image, fresh.image);
        assert_eq!(r.path_samples(), 4);
    }

    #[test]
    fn shadows_darken_and_reuse_their_light_volumes() {
        let lit = Lighting {
            model: LightingModel::Shadows,
            ..Lighting::default()
        };
        let mut scene = small(lit);
        scene.lights = vec![glint_core::Light {
            azimuth: 50.0,
            elevation: 30.0,
            intensity: 1.0,
        }];
        let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
        let a = r.render(&scene, &|_| {}).unwrap();
        let again = r.render(&scene, &|_| {}).unwrap();
        assert_eq!(a.image, again.image);
        let local = r
            .render(
                &Scene {
                    lighting: Lighting::default(),
                    ..scene.clone()
                },
                &|_| {},
            )
            .unwrap();
        let sum = |i: &glint_core::Image| i.rgb.iter().map(|c| f64::from(c[1])).sum::<f64>();
        assert!(
            sum(&a.image) < sum(&local.image),
            "shadows removed no light"
        );
        // A patch merges lighting field by field.
        let p = scene
            .patch(
                json!({"lighting": {"occlusion": true}})
                    .as_object()
                    .unwrap(),
            )
            .unwrap();
        assert_eq!(p.lighting.model, LightingModel::Shadows);
        assert_eq!(p.lighting.occlusion, Some(true));
        let ao = r.render(&p, &|_| {}).unwrap();
        assert_ne!(ao.image, a.image);
    }
}
