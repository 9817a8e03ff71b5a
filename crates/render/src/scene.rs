//! The one description of a render: [`Scene`], a serialisable value (versioned JSON) that
//! every front end builds (the command line, compare mode, the viewer, the Python
//! module, benches and tests), and [`Renderer`], which turns scenes into images.
//!
//! [`Scene::resolve`] is the only place where defaults are chosen (the preset guessed
//! from the data, the shininess from the preset, the iso value from the range, ...);
//! each choice is written back into the resolved scene, so a dumped scene renders the
//! same image again.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use glint_hw::Config as HwConfig;
use glint_io::{open_volume, ReadOptions, Volume};
use glint_lobe::{Geometry, Lobe, LobeKind, Specular};
use serde::{Deserialize, Serialize};

use glint_core::camera::{Camera, CameraSpec, Projection};
use glint_core::{
    Image, Light, Material, MaterialOverrides, RenderError, RenderMode, ScalarColors, Shader,
    Timings, MAX_LIGHTS,
};
use glint_raster::{SurfaceSettings, Surfaces, SURFACE_COLOR};
use glint_volume::{
    preset, Classification, ClassifySettings, Field, FrameSettings, Kernel, Phantom, Prefilter,
    Sampling, TransferFunction,
};

use crate::hwlobe::HwCache;
use crate::meshes::{
    MeshKey, MeshSet, MeshSpec, DEFAULT_SSAA, SURFACE_MATERIAL, SURFACE_SHININESS,
};

/// The scene schema version this build reads and writes.
pub const SCENE_VERSION: u32 = 1;

/// The largest scene file accepted (a scene is a few kilobytes; an inline transfer
/// function of a few hundred points stays far below this).
pub const MAX_SCENE_BYTES: u64 = 1 << 20;

/// Shininess used when neither the scene nor a preset gives one (VTK's usual volume
/// specular power in Slicer's CT presets).
pub const DEFAULT_SHININESS: f64 = 10.0;

/// A render, described completely: what to read, how to classify it, how to light and
/// view it, and the image size. Fields left unset are chosen by [`Scene::resolve`].
///
/// ```
/// use glint_render::{Input, Phantom, Renderer, Scene};
///
/// let scene = Scene {
///     input: Input::Phantom { name: Phantom::SheppLogan, size: 32 },
///     size: [32, 32],
///     ..Scene::default()
/// };
/// let json = scene.to_json().unwrap();
/// assert_eq!(Scene::from_json(&json).unwrap(), scene);
/// let mut renderer = Renderer::open(&scene.input).unwrap();
/// let rendered = renderer.render(&scene, &|_| {}).unwrap();
/// assert_eq!(rendered.image.rgb.len(), 32 * 32);
/// // The resolved scene names what was chosen: the phantom's preset and its power.
/// assert_eq!(rendered.scene.preset.as_deref(), Some("phantom"));
/// assert!(rendered.scene.lobe.n.is_some());
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Scene {
    /// Schema version ([`SCENE_VERSION`]).
    pub version: u32,
    /// The volume ([`Input::None`] for a scene of meshes only).
    pub input: Input,
    /// Surface meshes, rasterised ([`RenderMode::Surface`]). A scene of meshes only
    /// may leave `input` out: a scene read from JSON with meshes and no `input` key
    /// has no volume.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub meshes: Vec<MeshSpec>,
    /// Surface renders: samples per pixel along each axis, 1, 2 or 4 (default
    /// [`DEFAULT_SSAA`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ssaa: Option<u32>,
    /// How samples along a ray make a pixel.
    pub mode: RenderMode,
    /// Iso value for [`RenderMode::Iso`] and for the isosurface [`RenderMode::Surface`]
    /// extracts from the volume (default: the middle of the value range).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iso: Option<f32>,
    /// Transfer-function and material preset (default: guessed from the data); unused
    /// when `transfer_function` is given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub preset: Option<String>,
    /// An inline transfer function, which replaces the preset's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub transfer_function: Option<TransferFunction>,
    /// Material coefficients that replace the preset's.
    pub material: MaterialOverrides,
    /// The specular lobe.
    pub lobe: LobeSpec,
    /// Directional lights relative to the camera (the headlight is `(0, 0)`).
    pub lights: Vec<Light>,
    /// Camera placement.
    pub camera: CameraSpec,
    /// Image width and height in pixels.
    pub size: [u32; 2],
    /// Sample distance along rays, in voxels of the smallest spacing.
    pub step: f64,
    /// Gradient-magnitude gate, as a fraction of the value range per voxel: samples
    /// with a weaker gradient get no directional shading.
    pub gate: f64,
    /// Empty-space skipping (never changes the image, only the speed).
    pub skip_empty: bool,
    /// How the volume's samples are filtered before trilinear reconstruction
    /// ([`Prefilter`]; `binomial` by default: no "wood grain" rings).
    pub prefilter: Prefilter,
    /// Composite mode: the transfer function read at each sample (`point`, the
    /// default) or integrated over the segments between samples (`pre-integrated`:
    /// thin shells of opacity show whatever the step) ([`Sampling`]).
    pub sampling: Sampling,
    /// The length of matter, in mm, whose opacity the transfer function gives (VTK's
    /// scalar opacity unit distance); absent: one voxel of the smallest spacing.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub opacity_unit: Option<f64>,
    /// Background colour, linear RGB.
    pub background: [f32; 3],
    /// Written by a render for other tools (e.g. scripts/bench_vtk.py): the camera
    /// and transfer function that were used, in world units. Ignored on input.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub derived: Option<Derived>,
}

impl Default for Scene {
    /// The built-in phantom, composite, lobe `k` (n from the preset, v = 4, Phong),
    /// headlight, anterior perspective view, 512x512, step 0.5 voxel.
    fn default() -> Self {
        Scene {
            version: SCENE_VERSION,
            input: Input::default(),
            meshes: Vec::new(),
            ssaa: None,
            mode: RenderMode::Composite,
            iso: None,
            preset: None,
            transfer_function: None,
            material: MaterialOverrides::default(),
            lobe: LobeSpec::default(),
            lights: vec![Light::HEADLIGHT],
            camera: CameraSpec::default(),
            size: [512, 512],
            step: 0.5,
            gate: 0.01,
            skip_empty: true,
            prefilter: Prefilter::default(),
            sampling: Sampling::default(),
            opacity_unit: None,
            background: [0.0; 3],
            derived: None,
        }
    }
}

/// Where the volume comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum Input {
    /// A file (or DICOM directory) any glint reader opens.
    Path(PathBuf),
    /// A built-in phantom sampled on a `size`^3 grid.
    Phantom {
        /// Which phantom.
        name: Phantom,
        /// Grid edge in voxels.
        size: usize,
    },
    /// No volume: a scene of meshes only (`"input": "none"`).
    None,
}

impl Default for Input {
    /// The default phantom at its default size.
    fn default() -> Self {
        Input::Phantom {
            name: Phantom::default(),
            size: Phantom::DEFAULT_SIZE,
        }
    }
}

impl Input {
    /// Reads the file or builds the phantom.
    pub fn open(&self) -> Result<Volume, RenderError> {
        Ok(self.open_with(&ReadOptions::default())?.volume)
    }

    /// The volume with what the reader said and measured.
    pub fn open_with(&self, options: &ReadOptions) -> Result<OpenedVolume, RenderError> {
        match self {
            Input::Path(path) => {
                let file = open_volume(path, options)?;
                Ok(OpenedVolume {
                    volume: file.volume,
                    notes: file.notes,
                    inflate: file.inflate,
                })
            }
            Input::Phantom { name, size } => Ok(OpenedVolume {
                volume: name.volume(*size)?,
                notes: Vec::new(),
                inflate: None,
            }),
            Input::None => Err(RenderError::Parameter(
                "the scene has no volume (input \"none\")".into(),
            )),
        }
    }
}

/// A volume read by [`Input::open_with`].
#[derive(Clone, Debug)]
pub struct OpenedVolume {
    /// The volume.
    pub volume: Volume,
    /// The reader's notes (e.g. DICOM's "geometry assumed: ..."); a phantom has none.
    pub notes: Vec<String>,
    /// Time spent inflating gzip data, when the reader measured it.
    pub inflate: Option<std::time::Duration>,
}

/// Which lobe a scene uses: one of glint-lobe's closed-form lobes, evaluated in f32,
/// or the bit-accurate hardware unit of glint-hw. In scene JSON and on the command line
/// it is a name: a [`LobeKind`]'s (`exact`, `k`, ...) or `hw`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SceneLobe {
    /// A closed-form lobe of glint-lobe.
    Float(LobeKind),
    /// The hardware unit of [`LobeSpec::hw`]: per sample, the cosine is quantised to
    /// the unit's input code, n rounded to its integer input, and the specular value is
    /// the unit's output code over full scale, as `glint_hw::Unit::eval` gives it.
    Hw,
}

impl SceneLobe {
    /// Every lobe, in the order `--help` lists them: glint-lobe's, then `hw`.
    pub const ALL: [SceneLobe; 7] = [
        SceneLobe::Float(LobeKind::Exact),
        SceneLobe::Float(LobeKind::EnergyFit),
        SceneLobe::Float(LobeKind::SlopeFit),
        SceneLobe::Float(LobeKind::Schlick),
        SceneLobe::Float(LobeKind::Gauss),
        SceneLobe::Float(LobeKind::Minimax),
        SceneLobe::Hw,
    ];

    /// The name users type (`exact`, `k`, ..., `hw`).
    pub fn name(self) -> &'static str {
        match self {
            SceneLobe::Float(kind) => kind.name(),
            SceneLobe::Hw => "hw",
        }
    }

    /// The closed-form lobe, `None` for the unit.
    pub fn float(self) -> Option<LobeKind> {
        match self {
            SceneLobe::Float(kind) => Some(kind),
            SceneLobe::Hw => None,
        }
    }
}

impl From<LobeKind> for SceneLobe {
    fn from(kind: LobeKind) -> Self {
        SceneLobe::Float(kind)
    }
}

impl std::fmt::Display for SceneLobe {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for SceneLobe {
    type Err = RenderError;
    /// A [`LobeKind`] name (and its aliases) or `hw`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s.trim().eq_ignore_ascii_case("hw") {
            return Ok(SceneLobe::Hw);
        }
        s.parse::<LobeKind>().map(SceneLobe::Float).map_err(|_| {
            RenderError::Parameter(format!(
                "unknown lobe '{s}': expected one of exact, k, g, schlick, gauss, minimax, hw"
            ))
        })
    }
}

/// The `v` of the default lobe, K_4 (the paper's).
const DEFAULT_V: u32 = 4;

/// The specular lobe of a scene.
///
/// For a `hw` lobe, the unit is [`LobeSpec::hw`] (resolution writes
/// `glint_hw::Config::default()` there when it is unset) and `v` is the unit's: scene
/// JSON that leaves `v` out takes `hw.v`, and a `v` that differs from it is refused
/// when the scene is resolved ([`RenderError::HwV`]). Other lobes ignore `hw` (and keep
/// it, so a front end may switch between `k` and `hw` without losing the unit).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "LobeFields")]
pub struct LobeSpec {
    /// Which lobe.
    #[serde(with = "by_name")]
    pub kind: SceneLobe,
    /// Shininess n (default: the preset's specular power).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub n: Option<f64>,
    /// The power fits raise their base to 2^v (for `hw`: the unit's `v`).
    pub v: u32,
    /// Phong (R·V) or Blinn (N·H).
    #[serde(with = "by_name")]
    pub geometry: Geometry,
    /// The hardware unit of a `hw` lobe: every field of `glint_hw::Config`, missing
    /// ones taking the default's (`glint hw eval --print-config`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hw: Option<HwConfig>,
}

impl Default for LobeSpec {
    /// The paper's lobe: K_4, Phong geometry, n from the preset.
    fn default() -> Self {
        LobeSpec {
            kind: SceneLobe::Float(LobeKind::EnergyFit),
            n: None,
            v: DEFAULT_V,
            geometry: Geometry::Phong,
            hw: None,
        }
    }
}

impl LobeSpec {
    /// The hardware unit `config` as a lobe (its `v`, n from the preset, Phong).
    pub fn hw(config: HwConfig) -> LobeSpec {
        LobeSpec {
            kind: SceneLobe::Hw,
            v: config.v,
            hw: Some(config),
            ..LobeSpec::default()
        }
    }
}

/// [`LobeSpec`] as scene JSON gives it: `v` may be left out, and then follows the
/// lobe (the unit's for `hw`, else [`DEFAULT_V`]).
#[derive(Deserialize)]
#[serde(default, deny_unknown_fields)]
struct LobeFields {
    #[serde(with = "by_name")]
    kind: SceneLobe,
    n: Option<f64>,
    v: Option<u32>,
    #[serde(with = "by_name")]
    geometry: Geometry,
    hw: Option<HwConfig>,
}

impl Default for LobeFields {
    fn default() -> Self {
        let d = LobeSpec::default();
        LobeFields {
            kind: d.kind,
            n: d.n,
            v: None,
            geometry: d.geometry,
            hw: d.hw,
        }
    }
}

impl From<LobeFields> for LobeSpec {
    fn from(f: LobeFields) -> Self {
        let v = f.v.unwrap_or(match (f.kind, &f.hw) {
            (SceneLobe::Hw, Some(config)) => config.v,
            (SceneLobe::Hw, None) => HwConfig::default().v,
            (SceneLobe::Float(_), _) => DEFAULT_V,
        });
        LobeSpec {
            kind: f.kind,
            n: f.n,
            v,
            geometry: f.geometry,
            hw: f.hw,
        }
    }
}

impl LobeSpec {
    /// The specular term for shininess `n`: the closed-form lobe, or the unit's table
    /// (from `cache`), writing the default unit into [`LobeSpec::hw`] when unset.
    fn specular(&mut self, n: f64, cache: &HwCache) -> Result<Specular, RenderError> {
        match self.kind {
            SceneLobe::Float(kind) => Ok(Lobe::<f32>::new(kind, n, self.v)?.into()),
            SceneLobe::Hw => {
                let config = self.hw.get_or_insert_with(HwConfig::default);
                if self.v != config.v {
                    return Err(RenderError::HwV {
                        lobe: self.v,
                        unit: config.v,
                    });
                }
                Ok(Specular::Table(cache.table(config, n)?))
            }
        }
    }
}

/// Serde through a type's name (`FromStr` and `Display`), for glint-lobe's enums,
/// which do not depend on serde.
mod by_name {
    use std::fmt::Display;
    use std::str::FromStr;

    use serde::{de::Error, Deserialize, Deserializer, Serializer};

    pub fn serialize<T: Display, S: Serializer>(x: &T, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(x)
    }

    pub fn deserialize<'de, T, D>(d: D) -> Result<T, D::Error>
    where
        T: FromStr,
        T::Err: Display,
        D: Deserializer<'de>,
    {
        let name = String::deserialize(d)?;
        name.parse().map_err(D::Error::custom)
    }
}

/// What a render used, in world units, for tools that rebuild the scene elsewhere
/// (VTK in scripts/bench_vtk.py). Written by [`Renderer::render`]; ignored on input.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Derived {
    /// Eye position, mm (RAS+).
    pub eye: [f32; 3],
    /// A point on the view axis, mm.
    pub focal_point: [f32; 3],
    /// Up vector.
    pub view_up: [f32; 3],
    /// Perspective: full vertical view angle, degrees.
    pub view_angle_deg: f64,
    /// Orthographic: half the image height, mm.
    pub parallel_scale: f32,
    /// Sample distance, mm (ray-cast volumes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step_mm: Option<f64>,
    /// The smallest voxel spacing, mm (the transfer function's unit distance).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_spacing_mm: Option<f64>,
    /// The transfer function used (ray-cast volumes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub transfer_function: Option<TransferFunction>,
}

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
    },
    /// Rasterising the meshes (and the volume's isosurface).
    Surface {
        /// The meshes, read.
        surfaces: Arc<Surfaces>,
        /// Size, supersampling, camera, colours.
        settings: SurfaceSettings,
        /// The colours of the scalar overlays, when any.
        colors: Option<ScalarColors>,
    },
}

/// Meshes rasterised into a ray-cast volume's frame ([`Plan::Volume`]).
#[derive(Clone, Debug)]
pub struct MeshLayer {
    /// The meshes, read.
    pub surfaces: Arc<Surfaces>,
    /// Size, supersampling, colours (the camera is the volume's).
    pub settings: SurfaceSettings,
    /// The colours of the scalar overlays, when any.
    pub colors: Option<ScalarColors>,
}

impl MeshLayer {
    /// Draws the meshes with `camera`, then composites `frame` (rendered by `volume`,
    /// given each pixel's distance to the surfaces) over them: volume colour plus
    /// (1 - volume opacity) times what lies behind (the surfaces over the background).
    fn render(
        &self,
        camera: &Camera,
        shader: &Shader,
        volume: impl FnOnce(&[f32]) -> Result<Image, RenderError>,
    ) -> Result<Image, RenderError> {
        let (behind, far) =
            self.surfaces
                .render_layer(camera, shader, &self.settings, self.colors.as_ref())?;
        let mut image = volume(&far)?;
        let bg = self.settings.background;
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

impl Scene {
    /// Parses a scene from JSON, checking the version. Errors name the field
    /// (`lobe.kind: unknown lobe ...`).
    pub fn from_json(text: &str) -> Result<Scene, RenderError> {
        let mut de = serde_json::Deserializer::from_str(text);
        let scene: Scene = serde_path_to_error::deserialize(&mut de)
            .map_err(|e| RenderError::Scene(format!("bad scene JSON: {e}")))?;
        de.end()
            .map_err(|e| RenderError::Scene(format!("bad scene JSON: {e}")))?;
        let input_given = !scene.meshes.is_empty()
            && serde_json::from_str::<serde_json::Value>(text)
                .is_ok_and(|v| v.get("input").is_some());
        scene.meshes_only_unless(input_given).check_version()
    }

    /// A scene read with meshes and without an `input` key has no volume (the
    /// default phantom is for scenes of nothing else).
    fn meshes_only_unless(mut self, input_given: bool) -> Scene {
        if !self.meshes.is_empty() && !input_given {
            self.input = Input::None;
        }
        self
    }

    /// A scene from a parsed JSON value (e.g. a viewer's patched scene), checked like
    /// [`Scene::from_json`].
    pub fn from_value(value: serde_json::Value) -> Result<Scene, RenderError> {
        let input_given = value.get("input").is_some();
        let scene: Scene = serde_path_to_error::deserialize(value)
            .map_err(|e| RenderError::Scene(format!("bad scene: {e}")))?;
        scene.meshes_only_unless(input_given).check_version()
    }

    fn check_version(self) -> Result<Scene, RenderError> {
        let scene = self;
        if scene.version == 0 || scene.version > SCENE_VERSION {
            return Err(RenderError::Scene(format!(
                "scene version {} is not supported (this glint reads version {SCENE_VERSION})",
                scene.version
            )));
        }
        Ok(scene)
    }

    /// Reads a scene file (at most [`MAX_SCENE_BYTES`]).
    pub fn from_json_file(path: &std::path::Path) -> Result<Scene, RenderError> {
        let file = |e: RenderError| RenderError::SceneFile {
            path: path.to_path_buf(),
            source: Box::new(e),
        };
        let meta = std::fs::metadata(path).map_err(|e| file(RenderError::Io(e)))?;
        if meta.len() > MAX_SCENE_BYTES {
            return Err(file(RenderError::Scene(format!(
                "{} bytes is too large for a scene (limit {MAX_SCENE_BYTES})",
                meta.len()
            ))));
        }
        let text = std::fs::read_to_string(path).map_err(|e| file(RenderError::Io(e)))?;
        Scene::from_json(&text).map_err(file)
    }

    /// The scene as pretty-printed JSON.
    pub fn to_json(&self) -> Result<String, RenderError> {
        serde_json::to_string_pretty(self).map_err(|e| RenderError::Scene(e.to_string()))
    }

    /// Reads the input and the meshes and resolves the scene against them (one-shot;
    /// a [`Renderer`] keeps the volume, the meshes and the classification across
    /// scenes).
    pub fn resolve(&self) -> Result<Resolved, RenderError> {
        Renderer::open_scene(self)?.resolve(self)
    }

    /// Whether the scene is rasterised (meshes without a volume, or the volume's
    /// isosurface asked for) rather than ray cast (a volume, with or without meshes
    /// drawn into its frame).
    pub fn is_surface(&self) -> bool {
        self.mode == RenderMode::Surface || (!self.meshes.is_empty() && self.input == Input::None)
    }

    /// The iso value of the volume's isosurface in a surface scene (the scene's, else
    /// the middle of the robust range), `None` when the scene has no volume.
    fn surface_iso(&self, field: Option<&Field>) -> Option<f32> {
        let field = field?;
        let (lo, hi) = field.robust_range();
        Some(self.iso.unwrap_or((lo + hi) / 2.0))
    }

    /// Resolves a surface scene: `field` the volume (if any), `set` its meshes and
    /// isosurface as read for this scene.
    fn resolve_surface(
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
        check_lights(&scene.lights)?;
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
        scene.camera.validate()?;
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
                surfaces: layer.surfaces,
                settings: layer.settings,
                colors: layer.colors,
            },
        })
    }

    /// The meshes' part of a scene with meshes, `set` as read for it: writes the
    /// supersampling, mesh colours, colour maps and ranges back into the scene.
    fn resolve_mesh_layer(&mut self, set: &MeshSet) -> Result<MeshLayer, RenderError> {
        let ssaa = *self.ssaa.get_or_insert(DEFAULT_SSAA);
        let mesh_colors = self
            .meshes
            .iter_mut()
            .map(|m| *m.color.get_or_insert(SURFACE_COLOR))
            .collect();
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
            surfaces: set.surfaces.clone(),
            settings,
            colors,
        })
    }

    /// Resolves a scene of a volume with meshes in a ray-cast mode: the volume's
    /// settings as [`Scene::resolve_for`] chooses them, and the meshes drawn in its
    /// frame.
    fn resolve_hybrid(
        &self,
        field: &Field,
        set: &MeshSet,
        hw: &HwCache,
    ) -> Result<Resolved, RenderError> {
        let mut volume = self.clone();
        let meshes = std::mem::take(&mut volume.meshes);
        volume.ssaa = None;
        let mut resolved = volume.resolve_cached(field, hw)?;
        resolved.scene.meshes = meshes;
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
    fn resolve_cached(&self, field: &Field, hw: &HwCache) -> Result<Resolved, RenderError> {
        if self.is_surface() || !self.meshes.is_empty() {
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
        check_lights(&scene.lights)?;
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
        };
        frame.validate()?;
        scene.camera.validate()?;
        let specular = scene.lobe.specular(n, hw)?;
        let shader = Shader::with_specular(
            specular,
            scene.lobe.geometry,
            material,
            scene.lights.clone(),
            gate,
        )?;
        Ok(Resolved {
            scene,
            shader,
            plan: Plan::Volume {
                tf,
                classify,
                frame,
                meshes: None,
            },
        })
    }

    /// The transfer function, the material it comes with and the default shininess,
    /// for a volume whose values span `lo..=hi`; writes the preset (or the MIP ramp)
    /// that was chosen back into the scene.
    fn resolve_classification(
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

/// The lights of a scene: at least one, at most [`MAX_LIGHTS`].
fn check_lights(lights: &[Light]) -> Result<(), RenderError> {
    if lights.is_empty() {
        return Err(RenderError::Parameter(
            "the scene has no light: give at least one (the headlight is azimuth 0, elevation 0)"
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

/// A rendered image and the resolved scene that made it.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The image.
    pub image: Image,
    /// The scene with every default written in, and [`Scene::derived`] filled.
    pub scene: Scene,
    /// Stage times: `read` and the field's stages from [`Renderer::open`] (`meshes`
    /// and `isosurface` when they were read or extracted for this scene), then
    /// `classify` (when the classification was built) and `frame`.
    pub timings: Timings,
    /// The colours of the scalar overlays, for a colour bar
    /// ([`ScalarColors::draw_bar`]); `None` without scalar overlays.
    pub colors: Option<ScalarColors>,
}

/// Renders scenes of one volume and one set of meshes, keeping the field, the meshes
/// read (and the isosurface extracted) and the last classification, so frames that
/// change only the camera, lights, lobe or size do not read, extract or classify again
/// (an interactive viewer, a notebook rendering many views). Cloning is cheap (the
/// data are shared): one clone per viewer client.
#[derive(Clone)]
pub struct Renderer {
    field: Option<Arc<Field>>,
    classification: Option<(TransferFunction, Arc<Classification>)>,
    meshes: Option<(MeshKey, Arc<MeshSet>)>,
    /// The last `hw` lobe's unit and table.
    hw: HwCache,
    /// Which compositing loop frames use (the SIMD one by default).
    pub kernel: Kernel,
    opened: Timings,
    notes: Vec<String>,
    /// The volume the field was built from, kept to rebuild the field when a scene
    /// asks for another [`Prefilter`]; `None` for a renderer made from a field.
    volume: Option<Arc<Volume>>,
}

impl Renderer {
    /// Reads `input` and builds its field (nothing for [`Input::None`]).
    pub fn open(input: &Input) -> Result<Renderer, RenderError> {
        Renderer::open_with(input, &ReadOptions::default())
    }

    /// [`Renderer::open`] with reader options (e.g. `strict`); the reader's notes are
    /// kept ([`Renderer::notes`]).
    pub fn open_with(input: &Input, options: &ReadOptions) -> Result<Renderer, RenderError> {
        Renderer::open_prefiltered(input, options, Prefilter::default())
    }

    /// [`Renderer::open_with`] for `scene`: its input, its field built with the scene's
    /// prefilter (so rendering it builds no second field).
    pub fn open_for(scene: &Scene, options: &ReadOptions) -> Result<Renderer, RenderError> {
        Renderer::open_prefiltered(&scene.input, options, scene.prefilter)
    }

    fn open_prefiltered(
        input: &Input,
        options: &ReadOptions,
        prefilter: Prefilter,
    ) -> Result<Renderer, RenderError> {
        if *input == Input::None {
            return Ok(Renderer {
                field: None,
                classification: None,
                meshes: None,
                hw: HwCache::default(),
                kernel: Kernel::Auto,
                opened: Timings::default(),
                notes: Vec::new(),
                volume: None,
            });
        }
        let start = Instant::now();
        let opened = input.open_with(options)?;
        let mut read = Timings::default();
        // Inflating is reported apart from reading and parsing (issue 12).
        let inflate = opened.inflate.unwrap_or_default();
        read.record("read", start.elapsed().saturating_sub(inflate));
        if let Some(inflate) = opened.inflate {
            read.record("read: inflate", inflate);
        }
        let mut renderer = Renderer::from_shared_volume(Arc::new(opened.volume), prefilter)?;
        read.extend(&renderer.opened);
        renderer.opened = read;
        renderer.notes = opened.notes;
        Ok(renderer)
    }

    /// What the reader said about the input: where the affine came from, what it
    /// assumed (lines starting "geometry assumed:"), dropped dimensions.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// Reads `scene`'s input and its meshes (with their overlays, and the volume's
    /// isosurface in surface mode).
    pub fn open_scene(scene: &Scene) -> Result<Renderer, RenderError> {
        let mut renderer = Renderer::open(&scene.input)?;
        if !scene.meshes.is_empty() || scene.is_surface() {
            renderer.mesh_set(scene)?;
        }
        Ok(renderer)
    }

    /// A renderer of a volume already in memory (copied: the renderer keeps it to
    /// rebuild the field for another [`Prefilter`]).
    pub fn from_volume(volume: &Volume) -> Result<Renderer, RenderError> {
        Renderer::from_shared_volume(Arc::new(volume.clone()), Prefilter::default())
    }

    /// A renderer of a shared volume, its field built with `prefilter` (a scene asking
    /// for another one rebuilds it).
    pub fn from_shared_volume(
        volume: Arc<Volume>,
        prefilter: Prefilter,
    ) -> Result<Renderer, RenderError> {
        let field = Field::with_prefilter(&volume, prefilter)?;
        let mut renderer = Renderer::from_field(Arc::new(field));
        renderer.volume = Some(volume);
        Ok(renderer)
    }

    /// Rebuilds the field when `prefilter` is not the one it was built with (and
    /// forgets what depended on it).
    fn use_prefilter(&mut self, prefilter: Prefilter) -> Result<(), RenderError> {
        let Some(field) = &self.field else {
            return Ok(());
        };
        if field.prefilter() == prefilter {
            return Ok(());
        }
        let Some(volume) = &self.volume else {
            return Err(RenderError::Parameter(format!(
                "prefilter {}: this renderer was given a field built with prefilter {}",
                prefilter.name(),
                field.prefilter().name()
            )));
        };
        let field = Field::with_prefilter(volume, prefilter)?;
        self.opened.extend(field.timings());
        self.field = Some(Arc::new(field));
        self.classification = None;
        self.meshes = None;
        Ok(())
    }

    /// A renderer of a field already built (several renderers, each with its own
    /// classification, can share one field: one per viewer client).
    pub fn from_field(field: Arc<Field>) -> Renderer {
        Renderer {
            opened: field.timings().clone(),
            field: Some(field),
            classification: None,
            meshes: None,
            hw: HwCache::default(),
            kernel: Kernel::Auto,
            notes: Vec::new(),
            volume: None,
        }
    }

    /// The field every scene is rendered from; `None` for a renderer of meshes only.
    pub fn field(&self) -> Option<&Arc<Field>> {
        self.field.as_ref()
    }

    /// The meshes of `scene` (and the isosurface it asks for): the ones read last when
    /// the scene names the same files and iso value, else read now.
    fn mesh_set(&mut self, scene: &Scene) -> Result<Arc<MeshSet>, RenderError> {
        let field = self.field.as_deref();
        let iso = if scene.mode == RenderMode::Surface {
            scene.surface_iso(field)
        } else {
            None
        };
        let key = MeshKey::new(&scene.meshes, iso);
        if let Some((k, set)) = &self.meshes {
            if *k == key {
                return Ok(set.clone());
            }
        }
        let extra = match (field, iso) {
            (Some(f), Some(iso)) => {
                let mesh = self.opened.time("isosurface", || {
                    glint_mesh::extract_grid(f.values(), f.dims(), &f.affine(), iso)
                        .map_err(crate::mesh_error)
                })?;
                if mesh.triangles.is_empty() {
                    return Err(RenderError::Parameter(format!(
                        "no isosurface at iso value {iso}: no voxel edge crosses it"
                    )));
                }
                Some(mesh)
            }
            _ => None,
        };
        let set = self
            .opened
            .time("meshes", || MeshSet::load(&scene.meshes, extra))?;
        let set = Arc::new(set);
        self.meshes = Some((key, set.clone()));
        Ok(set)
    }

    /// Resolves `scene` against this renderer's volume ([`Scene::resolve_for`]) or,
    /// for a surface scene, its meshes (read now if the scene names others); a `hw`
    /// lobe's table is built once per (configuration, n) and kept.
    pub fn resolve(&mut self, scene: &Scene) -> Result<Resolved, RenderError> {
        self.use_prefilter(scene.prefilter)?;
        if scene.is_surface() || self.field.is_none() {
            let set = self.mesh_set(scene)?;
            return scene.resolve_surface(self.field.as_deref(), &set, &self.hw);
        }
        let mut resolved = if !scene.meshes.is_empty() {
            let set = self.mesh_set(scene)?;
            let field = self.field.as_ref().expect("checked above");
            scene.resolve_hybrid(field, &set, &self.hw)?
        } else {
            let field = self.field.as_ref().expect("checked above");
            scene.resolve_cached(field, &self.hw)?
        };
        if let Plan::Volume { frame, .. } = &mut resolved.plan {
            frame.kernel = self.kernel;
        }
        Ok(resolved)
    }

    /// The camera a render of `scene` uses (for a volume it frames what the scene's
    /// transfer function makes visible, so it classifies, and keeps the
    /// classification; for surfaces, the bounding sphere of every mesh).
    pub fn camera(&mut self, scene: &Scene) -> Result<Camera, RenderError> {
        match self.resolve(scene)?.plan {
            Plan::Volume {
                tf,
                classify,
                frame,
                ..
            } => {
                let (class, _) = self.classification(&tf, &classify)?;
                class.camera(&frame)
            }
            Plan::Surface {
                surfaces, settings, ..
            } => surfaces.camera(&settings),
        }
    }

    /// The classification for `tf` and `settings`: the last one when they are the
    /// same, else a new one (which replaces it). Returns it and whether it was built.
    pub fn classification(
        &mut self,
        tf: &TransferFunction,
        settings: &ClassifySettings,
    ) -> Result<(Arc<Classification>, bool), RenderError> {
        if let Some((t, c)) = &self.classification {
            if t == tf && c.settings() == settings {
                return Ok((c.clone(), false));
            }
        }
        let field = self
            .field
            .clone()
            .ok_or_else(|| RenderError::Parameter("the renderer has no volume".into()))?;
        let c = Arc::new(Classification::new(field, tf, settings)?);
        self.classification = Some((tf.clone(), c.clone()));
        Ok((c, true))
    }

    /// Renders `scene` (its input is not read again: the renderer's volume is used;
    /// its meshes are read when they are not the ones read last).
    /// `progress` is called with the number of pixels finished after each tile
    /// (volumes) or once at the end (surfaces).
    pub fn render(
        &mut self,
        scene: &Scene,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Rendered, RenderError> {
        let resolved = self.resolve(scene)?;
        self.render_resolved(resolved, progress)
    }

    /// Renders a scene resolved by [`Renderer::resolve`].
    pub fn render_resolved(
        &mut self,
        resolved: Resolved,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Rendered, RenderError> {
        let mut timings = self.opened.clone();
        let mut scene = resolved.scene;
        let (image, derived, colors) = match resolved.plan {
            Plan::Volume {
                tf,
                classify,
                frame,
                meshes,
            } => {
                let start = Instant::now();
                let (class, built) = self.classification(&tf, &classify)?;
                if built {
                    timings.record("classify", start.elapsed());
                }
                let camera = class.camera(&frame)?;
                let shader = &resolved.shader;
                let image = timings.time("frame", || match &meshes {
                    None => class.render(shader, &frame, progress),
                    Some(layer) => layer.render(&camera, shader, |far| {
                        class.render_in_front(shader, &frame, progress, far)
                    }),
                })?;
                let field = self.field.as_deref().expect("a volume plan has a field");
                let step_mm = scene.step * field.min_spacing();
                let mut d = derived(&camera);
                d.step_mm = Some(step_mm);
                d.min_spacing_mm = Some(field.min_spacing());
                d.transfer_function = Some(tf);
                (image, d, None)
            }
            Plan::Surface {
                surfaces,
                settings,
                colors,
            } => {
                let camera = surfaces.camera(&settings)?;
                let image = timings.time("frame", || {
                    surfaces.render(&camera, &resolved.shader, &settings, colors.as_ref())
                })?;
                progress(u64::from(settings.width) * u64::from(settings.height));
                (image, derived(&camera), colors)
            }
        };
        scene.derived = Some(derived);
        Ok(Rendered {
            image,
            scene,
            timings,
            colors,
        })
    }
}

/// The camera in world units (the volume's fields are filled by the caller).
fn derived(camera: &Camera) -> Derived {
    let focal = camera.eye + camera.forward * 100.0;
    Derived {
        eye: camera.eye.to_array(),
        focal_point: focal.to_array(),
        view_up: camera.up.to_array(),
        view_angle_deg: match camera.projection {
            Projection::Perspective => 2.0 * (camera.half_height as f64).atan().to_degrees(),
            Projection::Orthographic => glint_core::camera::FIELD_OF_VIEW_DEG,
        },
        parallel_scale: camera.half_height,
        step_mm: None,
        min_spacing_mm: None,
        transfer_function: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> Scene {
        Scene {
            input: Input::Phantom {
                name: Phantom::SheppLogan,
                size: 24,
            },
            size: [24, 20],
            ..Scene::default()
        }
    }

    /// The field follows the scene's prefilter: rebuilt from the kept volume when a
    /// scene asks for another one, with a different image; a renderer given only a
    /// field refuses another prefilter with a typed error.
    #[test]
    fn the_field_follows_the_scenes_prefilter() {
        let scene = small();
        assert_eq!(scene.prefilter, Prefilter::Binomial);
        let mut r = Renderer::open(&scene.input).unwrap();
        let smooth = r.render(&scene, &|_| {}).unwrap();
        assert_eq!(r.field().unwrap().prefilter(), Prefilter::Binomial);
        let raw_scene = Scene {
            prefilter: Prefilter::None,
            ..scene.clone()
        };
        let raw = r.render(&raw_scene, &|_| {}).unwrap();
        assert_eq!(r.field().unwrap().prefilter(), Prefilter::None);
        assert_ne!(smooth.image.rgb, raw.image.rgb);
        assert_eq!(raw.scene.prefilter, Prefilter::None);
        let volume = scene.input.open().unwrap();
        let mut fixed = Renderer::from_field(Arc::new(Field::new(&volume).unwrap()));
        let err = fixed.render(&scene, &|_| {}).unwrap_err();
        assert!(matches!(err, RenderError::Parameter(_)), "{err}");
        assert!(fixed.render(&raw_scene, &|_| {}).is_ok());
        // Opened for the scene, the field is built once, with its prefilter.
        let opened = Renderer::open_for(&raw_scene, &ReadOptions::default()).unwrap();
        assert_eq!(opened.field().unwrap().prefilter(), Prefilter::None);
    }

    #[test]
    fn json_round_trip_keeps_every_field() {
        let mut scene = small();
        scene.mode = RenderMode::Iso;
        scene.iso = Some(0.25);
        scene.lobe = LobeSpec {
            kind: LobeKind::Schlick.into(),
            n: Some(33.0),
            v: 3,
            geometry: Geometry::Blinn,
            hw: None,
        };
        scene.lights.push(Light {
            azimuth: -40.0,
            elevation: 20.0,
            intensity: 0.5,
        });
        scene.material.specular = Some(0.7);
        let json = scene.to_json().unwrap();
        assert!(json.contains("\"version\": 1"), "{json}");
        assert!(
            json.contains("\"schlick\"") && json.contains("\"blinn\""),
            "{json}"
        );
        assert_eq!(Scene::from_json(&json).unwrap(), scene);
    }

    #[test]
    fn missing_fields_take_defaults_and_unknown_ones_are_refused() {
        assert_eq!(Scene::from_json("{}").unwrap(), Scene::default());
        let err = Scene::from_json(r#"{"colour": 1}"#)
            .unwrap_err()
            .to_string();
        assert!(err.contains("colour"), "{err}");
        let err = Scene::from_json(r#"{"version": 7}"#)
            .unwrap_err()
            .to_string();
        assert!(err.contains("version 7"), "{err}");
        let err = Scene::from_json(r#"{"lobe": {"kind": "cosine"}}"#)
            .unwrap_err()
            .to_string();
        assert!(err.contains("cosine"), "{err}");
    }

    #[test]
    fn hw_lobes_parse_by_name_and_take_v_from_the_unit() {
        let parse = |lobe: &str| Scene::from_json(&format!(r#"{{"lobe": {lobe}}}"#));
        let plain = parse(r#"{"kind": "hw", "n": 40}"#).unwrap().lobe;
        assert_eq!(plain.kind, SceneLobe::Hw);
        assert_eq!((plain.v, plain.hw), (HwConfig::default().v, None));
        // v left out: the unit's; given: kept as written (resolution checks it).
        let v3 = r#""hw": {"v": 3, "square_frac": [14, 14, 12]}"#;
        let lobe = parse(&format!(r#"{{"kind": "HW", {v3}}}"#)).unwrap().lobe;
        assert_eq!(lobe.v, 3);
        assert_eq!(lobe.hw.as_ref().unwrap().square_frac, [14, 14, 12]);
        assert_eq!(
            lobe.hw.as_ref().unwrap().out_bits,
            HwConfig::default().out_bits
        );
        let lobe = parse(&format!(r#"{{"kind": "hw", "v": 5, {v3}}}"#))
            .unwrap()
            .lobe;
        assert_eq!(lobe.v, 5);
        // Float lobes keep the default v whatever the unit says.
        let lobe = parse(&format!(r#"{{"kind": "g", {v3}}}"#)).unwrap().lobe;
        assert_eq!((lobe.kind, lobe.v), (LobeKind::SlopeFit.into(), 4));
        // Unknown fields of the unit are refused, naming the path.
        let err = parse(r#"{"kind": "hw", "hw": {"out_bitz": 8}}"#).unwrap_err();
        assert!(err.to_string().contains("lobe.hw"), "{err}");
        let err = parse(r#"{"kind": "hardware"}"#).unwrap_err().to_string();
        assert!(err.contains("hardware") && err.contains("hw"), "{err}");
        for lobe in SceneLobe::ALL {
            assert_eq!(lobe.name().parse::<SceneLobe>().unwrap(), lobe);
        }
    }

    #[test]
    fn a_resolved_hw_scene_names_the_whole_unit_and_round_trips() {
        let field = Field::new(&small().input.open().unwrap()).unwrap();
        let scene = Scene::from_json(
            r#"{"input": {"phantom": {"name": "shepp-logan", "size": 24}},
            "size": [24, 20], "lobe": {"kind": "hw", "n": 40}}"#,
        )
        .unwrap();
        let resolved = scene.resolve_for(&field).unwrap();
        assert_eq!(resolved.scene.lobe.hw, Some(HwConfig::default()));
        let json = resolved.scene.to_json().unwrap();
        for field in ["\"hw\"", "out_bits", "square_frac", "coefficients"] {
            assert!(json.contains(field), "{field} missing: {json}");
        }
        let again = Scene::from_json(&json).unwrap();
        assert_eq!(again, resolved.scene);
        assert_eq!(again.resolve_for(&field).unwrap().scene, resolved.scene);
    }

    #[test]
    fn a_resolved_hw_lobe_is_the_units_output_per_cosine() {
        use glint_hw::{Input as HwInput, Unit};
        let field = Field::new(&small().input.open().unwrap()).unwrap();
        for (config, n) in [
            (HwConfig::default(), 40.4),
            (
                HwConfig {
                    out_bits: 12,
                    ..HwConfig::default()
                },
                100.0,
            ),
        ] {
            let scene = Scene {
                lobe: LobeSpec {
                    n: Some(n),
                    geometry: Geometry::Blinn,
                    ..LobeSpec::hw(config.clone())
                },
                ..small()
            };
            let resolved = scene.resolve_for(&field).unwrap();
            let specular = resolved.shader.specular();
            let unit = Unit::new(config).unwrap();
            let full = unit.full_scale();
            // n is rounded to the unit's integer input.
            let n_in = n.round() as u32;
            let mut distinct = std::collections::BTreeSet::new();
            for i in 0..=20_000 {
                let c = 0.9f32 + 0.1 * i as f32 / 20_000.0;
                let out = unit
                    .eval(&HwInput {
                        cos: unit.cos_code(f64::from(c)).unwrap(),
                        n: n_in,
                        ks: [full; 3],
                    })
                    .unwrap();
                let want = (out.rgb[0] as f64 / full as f64) as f32;
                assert_eq!(specular.eval(c).to_bits(), want.to_bits(), "n {n}, c {c}");
                distinct.insert(out.rgb[0]);
            }
            assert!(distinct.len() > 100, "{} output codes", distinct.len());
        }
    }

    #[test]
    fn contradictory_or_bad_hw_lobes_are_typed_errors() {
        let field = Field::new(&small().input.open().unwrap()).unwrap();
        let hw = |v: u32, config: Option<HwConfig>, n: f64| Scene {
            lobe: LobeSpec {
                kind: SceneLobe::Hw,
                v,
                n: Some(n),
                hw: config,
                ..LobeSpec::default()
            },
            ..small()
        };
        let err = hw(3, None, 40.0).resolve_for(&field).unwrap_err();
        assert!(
            matches!(err, RenderError::HwV { lobe: 3, unit: 4 }),
            "{err:?}"
        );
        let v3 = HwConfig {
            v: 3,
            square_frac: vec![14, 14, 12],
            ..HwConfig::default()
        };
        assert!(hw(3, Some(v3.clone()), 40.0).resolve_for(&field).is_ok());
        let err = hw(4, Some(v3), 40.0).resolve_for(&field).unwrap_err();
        assert!(
            matches!(err, RenderError::HwV { lobe: 4, unit: 3 }),
            "{err:?}"
        );
        let bad = HwConfig {
            out_bits: 0,
            ..HwConfig::default()
        };
        let err = hw(4, Some(bad), 40.0).resolve_for(&field).unwrap_err();
        assert!(matches!(err, RenderError::HwConfig(_)), "{err:?}");
        let err = hw(4, None, 1024.0).resolve_for(&field).unwrap_err();
        assert!(matches!(err, RenderError::HwN { .. }), "{err:?}");
        // A float lobe ignores the unit, even an invalid one.
        let mut k = hw(
            4,
            Some(HwConfig {
                v: 11,
                ..HwConfig::default()
            }),
            40.0,
        );
        k.lobe.kind = LobeKind::EnergyFit.into();
        assert!(k.resolve_for(&field).is_ok());
    }

    #[test]
    fn a_renderer_builds_a_units_table_once_per_configuration_and_n() {
        let scene = Scene {
            lobe: LobeSpec {
                n: Some(30.0),
                ..LobeSpec::hw(HwConfig::default())
            },
            ..small()
        };
        let mut r = Renderer::open(&scene.input).unwrap();
        let mut table = |s: &Scene| match r.resolve(s).unwrap().shader.specular() {
            Specular::Table(t) => t.clone(),
            Specular::Lobe(l) => panic!("a hw scene resolved to {l:?}"),
        };
        let first = table(&scene);
        // Another frame of the viewer: the camera moved.
        let mut moved = scene.clone();
        moved.camera.azimuth = 20.0;
        assert!(Arc::ptr_eq(&first, &table(&moved)));
        // Another n: another table.
        moved.lobe.n = Some(31.0);
        assert!(!Arc::ptr_eq(&first, &table(&moved)));
    }

    #[test]
    fn resolution_writes_its_choices_back_and_is_idempotent() {
        let field = Field::new(&small().input.open().unwrap()).unwrap();
        for mode in [RenderMode::Composite, RenderMode::Iso, RenderMode::Mip] {
            let scene = Scene { mode, ..small() };
            let first = scene.resolve_for(&field).unwrap();
            let s = &first.scene;
            assert!(s.lobe.n.is_some() && s.material.ambient.is_some());
            assert!(s.preset.is_some() || s.transfer_function.is_some());
            assert_eq!(s.iso.is_some(), mode == RenderMode::Iso);
            // Resolving the resolved scene chooses nothing new.
            let again = s.resolve_for(&field).unwrap();
            assert_eq!(&again.scene, s, "{mode:?}");
            let tf = |r: &Resolved| match &r.plan {
                Plan::Volume { tf, .. } => tf.clone(),
                Plan::Surface { .. } => panic!("a volume scene resolved to a surface plan"),
            };
            assert_eq!(tf(&again), tf(&first));
        }
    }

    #[test]
    fn bad_scenes_are_refused_with_the_reason() {
        let field = Field::new(&small().input.open().unwrap()).unwrap();
        let cases: Vec<(Scene, &str)> = vec![
            (
                Scene {
                    lights: vec![],
                    ..small()
                },
                "no light",
            ),
            (
                Scene {
                    iso: Some(1.0),
                    ..small()
                },
                "iso",
            ),
            (
                Scene {
                    preset: Some("ct-nonsense".into()),
                    ..small()
                },
                "ct-nonsense",
            ),
            (
                Scene {
                    step: 0.0,
                    ..small()
                },
                "step",
            ),
            (
                Scene {
                    size: [0, 4],
                    ..small()
                },
                "image size",
            ),
            (
                Scene {
                    gate: f64::NAN,
                    ..small()
                },
                "gate",
            ),
        ];
        for (scene, needle) in cases {
            let err = scene.resolve_for(&field).unwrap_err().to_string();
            assert!(err.contains(needle), "'{err}' lacks '{needle}'");
        }
    }

    #[test]
    fn a_renderer_reuses_its_classification_only_when_it_still_applies() {
        let scene = small();
        let mut r = Renderer::open(&scene.input).unwrap();
        let classified = |t: &Timings| t.stages().iter().any(|(s, _)| *s == "classify");
        let first = r.render(&scene, &|_| {}).unwrap();
        assert!(classified(&first.timings));
        // Another view and lobe: same classification.
        let moved = Scene {
            camera: CameraSpec {
                azimuth: 30.0,
                ..scene.camera
            },
            lobe: LobeSpec {
                kind: LobeKind::Exact.into(),
                ..scene.lobe.clone()
            },
            ..scene.clone()
        };
        let second = r.render(&moved, &|_| {}).unwrap();
        assert!(!classified(&second.timings));
        assert_ne!(second.image.rgb, first.image.rgb);
        // Another step: classified again, and the image equals a fresh renderer's.
        let finer = Scene {
            step: 0.25,
            ..scene.clone()
        };
        let third = r.render(&finer, &|_| {}).unwrap();
        assert!(classified(&third.timings));
        let fresh = Renderer::open(&scene.input)
            .unwrap()
            .render(&finer, &|_| {})
            .unwrap();
        assert_eq!(third.image, fresh.image);
    }

    /// A closed octahedron as OBJ in `dir`.
    fn octahedron(dir: &std::path::Path) -> PathBuf {
        let path = dir.join("octa.obj");
        std::fs::write(
            &path,
            "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n\
             f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n",
        )
        .unwrap();
        path
    }

    #[test]
    fn a_mesh_scene_resolves_once_and_reads_its_meshes_once() {
        let dir = tempfile::tempdir().unwrap();
        let json = format!(
            r#"{{"meshes": [{{"path": {:?}}}], "size": [32, 24]}}"#,
            octahedron(dir.path())
        );
        // Meshes without an input key: no volume.
        let scene = Scene::from_json(&json).unwrap();
        assert_eq!(scene.input, Input::None);
        let mut r = Renderer::open_scene(&scene).unwrap();
        assert!(r.field().is_none());
        let first = r.render(&scene, &|_| {}).unwrap();
        let s = &first.scene;
        assert_eq!(s.mode, RenderMode::Surface);
        assert_eq!(s.ssaa, Some(DEFAULT_SSAA));
        assert_eq!(s.lobe.n, Some(SURFACE_SHININESS));
        assert_eq!(s.meshes[0].color, Some(SURFACE_COLOR));
        assert!(first.colors.is_none());
        // The resolved scene chooses nothing new and renders the same image.
        let mut again = s.clone();
        again.derived = None;
        let second = r.render(&again, &|_| {}).unwrap();
        assert_eq!(second.scene, first.scene);
        assert_eq!(second.image, first.image);
        // Its JSON names the lack of a volume, and reads back to the same scene.
        let text = again.to_json().unwrap();
        assert!(text.contains(r#""input": "none""#), "{text}");
        assert_eq!(Scene::from_json(&text).unwrap(), again);
        // The octahedron covers the centre of the image.
        assert!(first.image.alpha[12 * 32 + 16] > 0.99);
        // A new camera reuses the meshes read (same Arc).
        let moved = Scene {
            camera: CameraSpec {
                azimuth: 40.0,
                ..again.camera
            },
            ..again.clone()
        };
        let before = r.meshes.as_ref().map(|(_, m)| Arc::as_ptr(m));
        r.render(&moved, &|_| {}).unwrap();
        assert_eq!(r.meshes.as_ref().map(|(_, m)| Arc::as_ptr(m)), before);
    }

    /// An octahedron of radius `r` about `c` (mm) as OBJ in `dir`.
    fn octahedron_at(dir: &std::path::Path, c: [f32; 3], r: f32) -> PathBuf {
        let path = dir.join("octa-at.obj");
        let mut text = String::new();
        for a in 0..3 {
            for sign in [1.0, -1.0] {
                let mut p = c;
                p[a] += sign * r;
                text += &format!("v {} {} {}\n", p[0], p[1], p[2]);
            }
        }
        text += "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";
        std::fs::write(&path, text).unwrap();
        path
    }

    /// A volume with meshes in a ray-cast mode: the meshes are drawn with the
    /// volume's camera and the volume composited over them. Pixels no mesh covers are
    /// the volume's alone; a mesh between the eye and the volume hides it, so there
    /// the image is the meshes' alone (the surface renderer with the same camera).
    #[test]
    fn a_volume_with_meshes_composites_the_volume_over_them() {
        let dir = tempfile::tempdir().unwrap();
        let base = Scene {
            size: [40, 40],
            ssaa: Some(1),
            ..small()
        };
        // In front of the phantom (it spans +-100 mm; anterior is +y).
        let scene = Scene {
            meshes: vec![MeshSpec::new(octahedron_at(
                dir.path(),
                [0.0, 160.0, 0.0],
                40.0,
            ))],
            ..base.clone()
        };
        let mut r = Renderer::open_scene(&scene).unwrap();
        let resolved = r.resolve(&scene).unwrap();
        let Plan::Volume {
            meshes: Some(layer),
            ..
        } = &resolved.plan
        else {
            panic!("a volume plan with meshes expected");
        };
        let layer = layer.clone();
        let shader = resolved.shader.clone();
        let both = r.render(&scene, &|_| {}).unwrap();
        let alone = r.render(&base, &|_| {}).unwrap();
        let camera = r.camera(&base).unwrap();
        let meshes = layer
            .surfaces
            .render(&camera, &shader, &layer.settings, None)
            .unwrap();
        let (mut covered, mut uncovered) = (0, 0);
        for i in 0..40 * 40 {
            if meshes.alpha[i] == 0.0 {
                assert_eq!(both.image.rgb[i], alone.image.rgb[i], "pixel {i}");
                assert_eq!(both.image.alpha[i], alone.image.alpha[i], "pixel {i}");
                uncovered += 1;
            } else if meshes.alpha[i] == 1.0 {
                for c in 0..3 {
                    let d = (both.image.rgb[i][c] - meshes.rgb[i][c]).abs();
                    assert!(
                        d < 1e-6,
                        "pixel {i}: {:?} vs {:?}",
                        both.image.rgb[i],
                        meshes.rgb[i]
                    );
                }
                assert_eq!(both.image.alpha[i], 1.0);
                covered += 1;
            }
        }
        // The mesh covers the middle of the image and the volume shows around it.
        assert!(
            meshes.alpha[20 * 40 + 20] == 1.0 && covered > 50,
            "{covered}"
        );
        assert!(
            (0..1600).any(|i| meshes.alpha[i] == 0.0 && alone.image.alpha[i] > 0.5),
            "{uncovered}"
        );
        // The dumped scene names the meshes and renders again bit for bit.
        let mut again = both.scene.clone();
        again.derived = None;
        assert_eq!(again.meshes.len(), 1);
        assert_eq!(again.mode, RenderMode::Composite);
        let text = again.to_json().unwrap();
        let reread = Scene::from_json(&text).unwrap();
        let fresh = Renderer::open_scene(&reread)
            .unwrap()
            .render(&reread, &|_| {})
            .unwrap();
        assert_eq!(fresh.image, both.image);
    }

    #[test]
    fn a_volume_with_meshes_in_surface_mode_joins_its_isosurface() {
        let dir = tempfile::tempdir().unwrap();
        let scene = Scene {
            meshes: vec![MeshSpec::new(octahedron(dir.path()))],
            mode: RenderMode::Surface,
            ..small()
        };
        let mut r = Renderer::open_scene(&scene).unwrap();
        // The phantom's isosurface joins the octahedron.
        let resolved = r.resolve(&scene).unwrap();
        assert!(resolved.scene.iso.is_some());
        let Plan::Surface { surfaces, .. } = &resolved.plan else {
            panic!("a surface plan expected");
        };
        assert_eq!(surfaces.mesh_count(), 2);
    }
}
