//! Resolving a scene: every default chosen (the one place glint picks what the user
//! did not say), written back into the scene, and the settings each pipeline needs.

use std::sync::Arc;

use glint_core::camera::Camera;
use glint_core::{
    Clip, Image, Legend, Light, Material, MaterialOverrides, RenderError, RenderMode, RenderStats,
    ScalarColors, Shader, MAX_LIGHTS,
};
use glint_raster::{SurfaceSettings, Surfaces, SURFACE_COLOR};
use glint_volume::{
    preset, ClassifySettings, Field, FrameSettings, Kernel, LabelVolume, LightingModel,
    TransferFunction,
};

use super::{Input, Scene, Transport, DEFAULT_SHININESS};
use crate::hwlobe::HwCache;
use crate::meshes::{MeshSet, DEFAULT_SSAA, SURFACE_MATERIAL, SURFACE_SHININESS};

/// A scene with every default chosen, and what the ray caster or the rasterizer
/// needs to render it.
#[derive(Clone, Debug)]
pub struct Resolved {
    /// The scene with every default written in.
    pub scene: Scene,
    /// The lighting.
    pub shader: Shader,
    /// How the image is made.
    pub plan: Plan,
}

/// How a resolved scene is rendered.
#[derive(Clone, Debug)]
#[allow(clippy::large_enum_variant)]
pub enum Plan {
    /// Ray casting the volume.
    Volume {
        /// The transfer function.
        tf: TransferFunction,
        /// What the classification depends on.
        classify: ClassifySettings,
        /// What the frame depends on.
        frame: FrameSettings,
        /// Meshes drawn in the volume with the same camera, when the scene has any:
        /// rays stop at the nearest surface and the volume composites over it.
        meshes: Option<MeshLayer>,
        /// How light reaches the samples.
        transport: Transport,
    },
    /// Rasterising the meshes (and the volume's isosurface).
    Surface {
        /// The meshes, read.
        surfaces: Arc<Surfaces>,
        /// Size, supersampling, camera, colours.
        settings: SurfaceSettings,
        /// The colours of the scalar overlays, when any.
        colors: Option<ScalarColors>,
        /// The labels shown, when the scene has a label map with a legend.
        legend: Option<Legend>,
    },
}

/// Meshes rasterised into a ray-cast volume's frame ([`Plan::Volume`]).
#[derive(Clone, Debug)]
pub struct MeshLayer {
    /// The meshes, read (`None`: none, only a label volume).
    pub surfaces: Option<Arc<Surfaces>>,
    /// Size, supersampling, colours (the camera is the volume's).
    pub settings: SurfaceSettings,
    /// The colours of the scalar overlays, when any.
    pub colors: Option<ScalarColors>,
    /// The labels shown, when the scene has a label map with a legend.
    pub legend: Option<Legend>,
    /// The label map ray cast as a volume, when the scene draws it so, and its
    /// sample step (voxels of the label grid's smallest edge).
    pub label_volume: Option<(Arc<LabelVolume>, f64)>,
    /// The scene's clip planes and crop box, which cut the label volume as they cut
    /// the intensity volume.
    pub clip: Clip,
}

impl MeshLayer {
    /// Draws the meshes with `camera`, then composites `frame` (rendered by `volume`,
    /// given each pixel's distance to the surfaces) over them: volume colour plus
    /// (1 - volume opacity) times what lies behind (the surfaces over the background).
    pub(crate) fn render(
        &self,
        camera: &Camera,
        shader: &Shader,
        volume: impl FnOnce(&[f32]) -> Result<Image, RenderError>,
    ) -> Result<Image, RenderError> {
        let bg = self.settings.background;
        let (w, h) = (self.settings.width, self.settings.height);
        let (mut behind, mut far) = match &self.surfaces {
            Some(s) => s.render_layer(camera, shader, &self.settings, self.colors.as_ref())?,
            None => {
                let n = w as usize * h as usize;
                let empty = Image {
                    width: w,
                    height: h,
                    rgb: vec![bg; n],
                    alpha: vec![0.0; n],
                    stats: RenderStats::default(),
                };
                (empty, vec![f32::INFINITY; n])
            }
        };
        if let Some((labels, step)) = &self.label_volume {
            // The label volume in front of the surfaces, then the volume in front of
            // both.
            let (front, first) =
                labels.render_layer(camera, shader, (w, h), bg, *step, (&far, &self.clip))?;
            over(&mut behind, &front, bg);
            for (f, l) in far.iter_mut().zip(first) {
                *f = f.min(l);
            }
        }
        let mut image = volume(&far)?;
        for ((rgb, a), (b_rgb, b_a)) in image
            .rgb
            .iter_mut()
            .zip(image.alpha.iter_mut())
            .zip(behind.rgb.iter().zip(&behind.alpha))
        {
            let t = 1.0 - *a;
            for i in 0..3 {
                rgb[i] += t * (b_rgb[i] - bg[i]);
            }
            *a += t * b_a;
        }
        image.stats.shaded += behind.stats.shaded;
        Ok(image)
    }
}

/// Puts `front` (RGB over `bg`, alpha its opacity) over `behind` (the same), in place.
fn over(behind: &mut Image, front: &Image, bg: [f32; 3]) {
    for ((rgb, a), (f_rgb, f_a)) in behind
        .rgb
        .iter_mut()
        .zip(behind.alpha.iter_mut())
        .zip(front.rgb.iter().zip(&front.alpha))
    {
        let t = 1.0 - f_a;
        for i in 0..3 {
            rgb[i] = f_rgb[i] + t * (rgb[i] - bg[i]);
        }
        *a = f_a + t * *a;
    }
    behind.stats.shaded += front.stats.shaded;
    behind.stats.samples += front.stats.samples;
}

/// The lights of a scene: at most [`MAX_LIGHTS`], and at least one unless the
/// environment may light it alone (`path` lighting).
/// Most splits of an environment map's median cut in `shadows` (8 lights).
pub(crate) const SHADOWS_ENV_SPLITS: u32 = 3;

/// `shader` with a `shadows` scene's environment map as directional lights: its
/// median cut into the most lights (at most `2^SHADOWS_ENV_SPLITS`, a power of two)
/// that fit beside the scene's other lights ([`MAX_LIGHTS`] in all).
fn environment_lights(shader: Shader, lighting: &super::Lighting) -> Result<Shader, RenderError> {
    let Some(name) = lighting
        .environment_map
        .as_ref()
        .filter(|_| lighting.model == LightingModel::Shadows)
    else {
        return Ok(shader);
    };
    let room = MAX_LIGHTS.saturating_sub(shader.lights_without_environment());
    if room == 0 {
        return Err(RenderError::Parameter(format!(
            "an environment map in shadows lighting needs room for its lights: at most {} lights and area lights with it",
            MAX_LIGHTS - 1
        )));
    }
    let splits = (room.ilog2()).min(SHADOWS_ENV_SPLITS);
    let rotation = lighting.environment_rotation.unwrap_or(0.0);
    let intensity = lighting.environment_intensity.unwrap_or(1.0);
    // The last map's lights are kept: a viewer resolves its scene every frame, and a
    // large probe takes a while to read.
    let mut last = LAST_MEDIAN_CUT.lock().unwrap_or_else(|e| e.into_inner());
    let lights = match &*last {
        Some((key, lights)) if *key == (name.clone(), rotation, intensity, splits) => {
            lights.clone()
        }
        _ => {
            let map = super::load_environment(name)?.placed(rotation, intensity)?;
            let lights = map.median_cut(splits);
            *last = Some(((name.clone(), rotation, intensity, splits), lights.clone()));
            lights
        }
    };
    shader.with_environment_lights(lights)
}

/// The map, rotation, intensity and splits of the last median cut, and its lights.
type MedianCutCache = Option<((String, f64, f32, u32), Vec<(glint_core::Vec3, f32)>)>;

/// The last median cut [`environment_lights`] made.
static LAST_MEDIAN_CUT: std::sync::Mutex<MedianCutCache> = std::sync::Mutex::new(None);

fn check_lights(lights: &[Light], environment_alone: bool) -> Result<(), RenderError> {
    if lights.is_empty() && !environment_alone {
        return Err(RenderError::Parameter(
            "the scene has no light: give at least one (the headlight is azimuth 0, elevation 0), \
             or light it by the environment alone with path lighting (or an environment map in shadows)"
                .into(),
        ));
    }
    if lights.len() > MAX_LIGHTS {
        return Err(RenderError::Parameter(format!(
            "{} lights: at most {MAX_LIGHTS}",
            lights.len()
        )));
    }
    Ok(())
}

/// The centre of `field`'s box of voxel centres, world mm: what area lights are
/// placed about.
fn volume_center(field: &Field) -> glint_core::Vec3 {
    let c = field.index_to_world(field.dims().map(|d| (d.max(1) - 1) as f64 / 2.0));
    glint_core::Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32)
}

impl Scene {
    /// Resolves a surface scene: `field` the volume (if any), `set` its meshes and
    /// isosurface as read for this scene.
    pub(crate) fn resolve_surface(
        &self,
        field: Option<&Field>,
        set: &MeshSet,
        hw: &HwCache,
    ) -> Result<Resolved, RenderError> {
        let mut scene = self.clone();
        scene.derived = None;
        match (&scene.input, scene.mode) {
            (_, RenderMode::Surface) => {}
            // A scene of meshes only: rasterising is the only way to render it.
            (Input::None, RenderMode::Composite) => scene.mode = RenderMode::Surface,
            (Input::None, mode) => {
                return Err(RenderError::Parameter(format!(
                    "mode {} needs a volume; a scene of meshes only renders in surface mode",
                    mode.name()
                )))
            }
            (_, mode) => {
                return Err(RenderError::Parameter(format!(
                    "mode {} needs the volume, which this renderer does not hold",
                    mode.name()
                )))
            }
        }
        scene.iso = scene.surface_iso(field);
        if field.is_none() && self.iso.is_some() {
            return Err(RenderError::Parameter(
                "an iso value needs a volume to extract the isosurface from".into(),
            ));
        }
        check_lights(&scene.lights, false)?;
        if !scene.lighting.area_lights.is_empty() {
            return Err(RenderError::Parameter(
                "area lights light a volume: a surface scene takes directional lights only".into(),
            ));
        }
        scene.clip().validate()?;
        scene.lighting.resolve(RenderMode::Surface)?;
        let material = scene.material.apply(SURFACE_MATERIAL);
        material.validate()?;
        scene.material = MaterialOverrides {
            ambient: Some(material.ambient),
            diffuse: Some(material.diffuse),
            specular: Some(material.specular),
            shade: Some(material.shade),
        };
        let n = *scene.lobe.n.get_or_insert(SURFACE_SHININESS);
        let layer = scene.resolve_mesh_layer(set)?;
        let surfaces = match (layer.surfaces, &layer.label_volume) {
            (Some(s), None) => s,
            _ => {
                return Err(RenderError::Parameter(
                    "a label volume is ray cast in a volume's frame: give the intensity volume and a ray-cast mode, or draw the labels as surfaces".into(),
                ))
            }
        };
        scene.camera.validate()?;
        glint_core::tone::check_exposure(scene.exposure)?;
        let specular = scene.lobe.specular(n, hw)?;
        let shader = Shader::with_specular(
            specular,
            scene.lobe.geometry,
            material,
            scene.lights.clone(),
            0.0,
        )?;
        Ok(Resolved {
            scene,
            shader,
            plan: Plan::Surface {
                surfaces,
                settings: layer.settings,
                colors: layer.colors,
                legend: layer.legend,
            },
        })
    }

    /// The meshes' part of a scene with meshes, `set` as read for it: writes the
    /// supersampling, mesh colours, colour maps and ranges back into the scene.
    fn resolve_mesh_layer(&mut self, set: &MeshSet) -> Result<MeshLayer, RenderError> {
        let ssaa = *self.ssaa.get_or_insert(DEFAULT_SSAA);
        let mut mesh_colors: Vec<[f32; 3]> = self
            .meshes
            .iter_mut()
            .map(|m| *m.color.get_or_insert(SURFACE_COLOR))
            .collect();
        mesh_colors.extend(&set.extra_colors);
        if let Some(l) = &mut self.labels {
            // A scene with labels has their lookup in its mesh set.
            let smoothing = (set.labels.as_ref()).map_or(1.0, |k| k.default_smoothing());
            l.resolve(smoothing);
        }
        let colors = set.resolve_overlays(&mut self.meshes)?;
        let settings = SurfaceSettings {
            width: self.size[0],
            height: self.size[1],
            ssaa,
            camera: self.camera,
            background: self.background,
            color: SURFACE_COLOR,
            mesh_colors,
        };
        settings.validate()?;
        Ok(MeshLayer {
            surfaces: set.surfaces_for(&self.clip(), self.clip_caps)?,
            settings,
            colors,
            legend: set.legend.clone(),
            label_volume: set.label_volume.clone().map(|v| (v, self.step)),
            clip: self.clip(),
        })
    }

    /// Resolves a scene of a volume with meshes in a ray-cast mode: the volume's
    /// settings as [`Scene::resolve_for`] chooses them, and the meshes drawn in its
    /// frame.
    pub(crate) fn resolve_hybrid(
        &self,
        field: &Field,
        set: &MeshSet,
        hw: &HwCache,
    ) -> Result<Resolved, RenderError> {
        let mut volume = self.clone();
        let meshes = std::mem::take(&mut volume.meshes);
        let labels = volume.labels.take();
        volume.ssaa = None;
        let mut resolved = volume.resolve_cached(field, hw)?;
        resolved.scene.meshes = meshes;
        resolved.scene.labels = labels;
        resolved.scene.ssaa = self.ssaa;
        let layer = resolved.scene.resolve_mesh_layer(set)?;
        if let Plan::Volume { meshes, .. } = &mut resolved.plan {
            *meshes = Some(layer);
        }
        Ok(resolved)
    }

    /// Chooses every default for `field` and builds the settings and shader: the one
    /// place where glint picks anything the user did not say.
    pub fn resolve_for(&self, field: &Field) -> Result<Resolved, RenderError> {
        self.resolve_cached(field, &HwCache::default())
    }

    /// [`Scene::resolve_for`], taking a `hw` lobe's table from `hw` when it has it.
    pub(crate) fn resolve_cached(
        &self,
        field: &Field,
        hw: &HwCache,
    ) -> Result<Resolved, RenderError> {
        if self.is_surface() || self.has_meshes() {
            return Err(RenderError::Parameter(
                "a scene with meshes is resolved by a Renderer, which reads them".into(),
            ));
        }
        let mut scene = self.clone();
        scene.derived = None;
        // Presets, the MIP ramp, the default iso value and the gate follow the robust
        // range (0.5th-99.5th percentile), so a few outlier voxels cannot black out
        // the image.
        let (lo, hi) = field.robust_range();
        let (tf, base, power) = scene.resolve_classification(lo, hi)?;
        let material = scene.material.apply(base);
        scene.material = MaterialOverrides {
            ambient: Some(material.ambient),
            diffuse: Some(material.diffuse),
            specular: Some(material.specular),
            shade: Some(material.shade),
        };
        let n = *scene.lobe.n.get_or_insert(power);
        let iso = match (scene.mode, scene.iso) {
            (RenderMode::Iso, iso) => *scene.iso.get_or_insert(iso.unwrap_or((lo + hi) / 2.0)),
            (_, Some(_)) => {
                return Err(RenderError::Parameter(
                    "an iso value is only used in iso mode".into(),
                ))
            }
            (_, None) => 0.0,
        };
        check_lights(
            &scene.lights,
            scene.lighting.model == LightingModel::Path
                || !scene.lighting.area_lights.is_empty()
                || scene.lighting.environment_map.is_some(),
        )?;
        if !scene.gate.is_finite() || !(0.0..=1.0).contains(&scene.gate) {
            return Err(RenderError::Parameter(format!(
                "gate {}: expected a fraction in 0..=1",
                scene.gate
            )));
        }
        let gate = (scene.gate * (hi - lo) as f64 / field.min_spacing()) as f32;
        let classify = ClassifySettings {
            mode: scene.mode,
            iso,
            step: scene.step,
            skip_empty: scene.skip_empty,
            sampling: scene.sampling,
            opacity_unit: scene.opacity_unit,
        };
        classify.validate()?;
        let frame = FrameSettings {
            width: scene.size[0],
            height: scene.size[1],
            camera: scene.camera,
            background: scene.background,
            kernel: Kernel::Auto,
            clip: scene.clip(),
        };
        frame.validate()?;
        scene.camera.validate()?;
        glint_core::tone::check_exposure(scene.exposure)?;
        let (transport, anisotropy) = scene.lighting.resolve(scene.mode)?;
        let specular = scene.lobe.specular(n, hw)?;
        let shader = Shader::with_specular(
            specular,
            scene.lobe.geometry,
            material,
            scene.lights.clone(),
            gate,
        )?
        .with_anisotropy(anisotropy)?
        .with_surface_weight(scene.lighting.surface_weight.unwrap_or(1.0))?
        .with_area_lights(scene.lighting.area_lights.clone(), volume_center(field))?;
        let shader = environment_lights(shader, &scene.lighting)?;
        Ok(Resolved {
            scene,
            shader,
            plan: Plan::Volume {
                tf,
                classify,
                frame,
                meshes: None,
                transport,
            },
        })
    }

    /// The transfer function (windowed at the scene's window and level, when it has
    /// them), the material it comes with and the default shininess, for a volume whose
    /// values span `lo..=hi`; writes the preset (or the MIP ramp) that was chosen back
    /// into the scene.
    fn resolve_classification(
        &mut self,
        lo: f32,
        hi: f32,
    ) -> Result<(TransferFunction, Material, f64), RenderError> {
        let (tf, material, power) = self.resolve_function(lo, hi)?;
        match self.window_level {
            Some(wl) => Ok((tf.with_window_level(wl)?, material, power)),
            None => Ok((tf, material, power)),
        }
    }

    /// [`Scene::resolve_classification`] before the window and level.
    fn resolve_function(
        &mut self,
        lo: f32,
        hi: f32,
    ) -> Result<(TransferFunction, Material, f64), RenderError> {
        if let Some(tf) = &self.transfer_function {
            tf.validate()?;
            let power = match &self.preset {
                Some(name) => preset(name)?.specular_power(),
                None => DEFAULT_SHININESS,
            };
            return Ok((tf.clone(), Material::default(), power));
        }
        let name = match (&self.preset, &self.input) {
            (Some(p), _) => p.clone(),
            (None, Input::Phantom { name, .. }) => name.preset().into(),
            // Hounsfield units reach air at -1000: CT.
            (None, Input::Path(_)) if lo < -500.0 => "ct-bone".into(),
            (None, Input::Path(_) | Input::None) => "mr-t2-brain".into(),
        };
        let p = preset(&name)?;
        if self.mode == RenderMode::Mip && self.preset.is_none() {
            // MIP without a preset: a grey ramp over the volume's range, written back
            // as an inline transfer function.
            let ramp = TransferFunction::from_flat(
                &[lo as f64, 0.0, (hi as f64).max(lo as f64 + 1e-6), 1.0],
                &[lo as f64, 1.0, 1.0, 1.0],
            )?;
            self.transfer_function = Some(ramp.clone());
            return Ok((ramp, p.material(), p.specular_power()));
        }
        self.preset = Some(p.name.to_string());
        Ok((
            p.transfer_function(hi as f64)?,
            p.material(),
            p.specular_power(),
        ))
    }
}
