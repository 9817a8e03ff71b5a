//! The one description of a render: [`Scene`], a serialisable value (versioned JSON) that
//! every front end builds (the command line, compare mode, the viewer, the Python
//! module, benches and tests), and [`Renderer`], which turns scenes into images.
//!
//! [`Scene::resolve`] is the only place where defaults are chosen (the preset guessed
//! from the data, the shininess from the preset, the iso value from the range, ...);
//! each choice is written back into the resolved scene, so a dumped scene renders the
//! same image again.

use std::path::PathBuf;

use glint_core::{
    CameraSpec, Clip, ClipPlane, CropBox, Light, MaterialOverrides, RenderError, RenderMode, Tone,
};
use glint_io::{open_volume, ReadOptions, Volume};
use glint_volume::{Field, Filter, Phantom, Prefilter, Sampling, TransferFunction, WindowLevel};
use serde::{Deserialize, Serialize};

use crate::labels::LabelSpec;
use crate::meshes::MeshSpec;

mod device;
mod envmap;
mod file;
mod lighting;
mod lobe;
mod patch;
mod resolve;
#[cfg(test)]
mod tests;

pub use device::Device;
pub(crate) use envmap::EnvCache;
pub use envmap::{
    available_environments, fetched_environment, load_environment, ENVIRONMENT_NAMES,
    FETCHED_ENVIRONMENTS,
};
pub use lighting::{Lighting, Transport, DEFAULT_BOUNCES, DEFAULT_ENVIRONMENT, DEFAULT_SPP};
pub use lobe::{LobeSpec, SceneLobe};
pub use patch::MERGED_FIELDS;
pub use resolve::{MeshLayer, Plan, Resolved};

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
/// use glint_render::{Input, Phantom, ReadOptions, Renderer, Scene};
///
/// let scene = Scene {
///     input: Input::Phantom { name: Phantom::SheppLogan, size: 32 },
///     size: [32, 32],
///     ..Scene::default()
/// };
/// let json = scene.to_json().unwrap();
/// assert_eq!(Scene::from_json(&json).unwrap(), scene);
/// let mut renderer = Renderer::open(&scene, &ReadOptions::default()).unwrap();
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
    /// A label map drawn as one surface per label, like [`meshes`](Self::meshes)
    /// (with a volume, in its ray-cast frame; without one, rasterised).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub labels: Option<LabelSpec>,
    /// Surface renders: samples per pixel along each axis, 1, 2 or 4 (default
    /// [`DEFAULT_SSAA`](crate::DEFAULT_SSAA)).
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
    /// Window and level (radiology's width and centre, in the volume's units): the
    /// transfer function (the preset's or the scene's own) remapped linearly along
    /// the value axis so that its own window ([`TransferFunction::window_level`], its
    /// opacity ramp) becomes this one; absent: the function as it is. Setting the
    /// preset or the transfer function clears it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub window_level: Option<WindowLevel>,
    /// Material coefficients that replace the preset's.
    pub material: MaterialOverrides,
    /// The specular lobe.
    pub lobe: LobeSpec,
    /// Directional lights relative to the camera (the headlight is `(0, 0)`).
    pub lights: Vec<Light>,
    /// The light-transport model (`local`, `shadows`, `path`) and its settings
    /// ([`Lighting`]); left out of the JSON while it is the default, `local`.
    #[serde(skip_serializing_if = "Lighting::is_default")]
    pub lighting: Lighting,
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
    /// How the field is reconstructed between voxels, its values and gradients, in
    /// every lighting model ([`Filter`]: `trilinear` by default; `tricubic`, the cubic
    /// B-spline, smooths away the voxel grid at a close zoom). Left out of the JSON
    /// while it is the default.
    #[serde(skip_serializing_if = "Filter::is_trilinear")]
    pub filter: Filter,
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
    /// Exposure in stops: the rendered radiance is scaled by `2^exposure` before the
    /// tone curve ([`Scene::tone`]) and the sRGB encoding; linear float output
    /// (`.exr`, `.pfm`) is the radiance before it. Left out of the JSON while 0.
    #[serde(skip_serializing_if = "is_zero")]
    pub exposure: f64,
    /// The tone curve from radiance to display light ([`Tone`]: `linear`, the
    /// default, clips at 1 as glint always did; `aces`; `agx`). Left out of the JSON
    /// while `linear`.
    #[serde(skip_serializing_if = "is_linear")]
    pub tone: Tone,
    /// Clip planes (world mm), each keeping the side its normal points to: the
    /// volume, its light, a label map (as a volume or as surfaces) and the meshes are
    /// cut in every mode and lighting model; cut faces of the volume are lit with the
    /// plane's normal where the data's gradient is weak. Left out of the JSON when
    /// there are none.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub clip: Vec<ClipPlane>,
    /// A crop box (axis-aligned, world mm) keeping its inside, cutting as
    /// [`clip`](Self::clip) does. Left out of the JSON when absent.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub crop: Option<CropBox>,
    /// Close the cut of closed meshes and label surfaces with the cut plane (lit with
    /// the plane's normal, in the mesh's colour) rather than showing their inside
    /// [default: false]. Left out of the JSON while false.
    #[serde(skip_serializing_if = "is_false")]
    pub clip_caps: bool,
    /// Where frames are rendered ([`Device`]: `cpu`, the default, `gpu` or `auto`).
    /// Left out of the JSON while `cpu`.
    #[serde(skip_serializing_if = "Device::is_cpu")]
    pub device: Device,
    /// Written by a render for other tools (e.g. scripts/bench/bench-vtk.py): the camera
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
            labels: None,
            ssaa: None,
            mode: RenderMode::Composite,
            iso: None,
            preset: None,
            transfer_function: None,
            window_level: None,
            material: MaterialOverrides::default(),
            lobe: LobeSpec::default(),
            lights: vec![Light::HEADLIGHT],
            lighting: Lighting::default(),
            camera: CameraSpec::default(),
            size: [512, 512],
            step: 0.5,
            gate: 0.01,
            skip_empty: true,
            prefilter: Prefilter::default(),
            filter: Filter::default(),
            sampling: Sampling::default(),
            opacity_unit: None,
            background: [0.0; 3],
            exposure: 0.0,
            tone: Tone::Linear,
            clip: Vec::new(),
            crop: None,
            clip_caps: false,
            device: Device::Cpu,
            derived: None,
        }
    }
}

/// Whether `b` is false (serde's `skip_serializing_if` for flags off by default).
fn is_false(b: &bool) -> bool {
    !*b
}

/// Whether `x` is zero (serde's `skip_serializing_if` for the exposure).
fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// Whether `t` is the default curve (serde's `skip_serializing_if`).
fn is_linear(t: &Tone) -> bool {
    *t == Tone::Linear
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

/// What a render used, in world units, for tools that rebuild the scene elsewhere
/// (VTK in scripts/bench/bench-vtk.py). Written by [`Renderer::render`](crate::Renderer::render); ignored on input.
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
    /// The distance in focus, mm from the eye along the view axis, of a thin-lens
    /// camera in `path` lighting (an `auto` focus as found under the image centre).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focus_mm: Option<f64>,
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

impl Scene {
    /// The default scene of the built-in phantom `name` sampled on a `size`³ grid,
    /// rendered at `image` (width, height) pixels: the scene tests, examples and
    /// notebooks start from.
    ///
    /// ```
    /// use glint_render::{Input, Phantom, Scene};
    /// let s = Scene::phantom(Phantom::SheppLogan, 24, [32, 28]);
    /// assert_eq!(s.input, Input::Phantom { name: Phantom::SheppLogan, size: 24 });
    /// assert_eq!((s.size, s.step), ([32, 28], Scene::default().step));
    /// ```
    pub fn phantom(name: Phantom, size: usize, image: [u32; 2]) -> Scene {
        Scene {
            input: Input::Phantom { name, size },
            size: image,
            ..Scene::default()
        }
    }

    /// Whether the scene is rasterised (meshes without a volume, or the volume's
    /// isosurface asked for) rather than ray cast (a volume, with or without meshes
    /// drawn into its frame).
    pub fn is_surface(&self) -> bool {
        self.mode == RenderMode::Surface || (self.has_meshes() && self.input == Input::None)
    }

    /// The clip planes and crop box as one [`Clip`].
    pub fn clip(&self) -> Clip {
        Clip {
            planes: self.clip.clone(),
            crop: self.crop,
        }
    }

    /// Whether the scene has surfaces besides the volume's: meshes or a label map.
    pub fn has_meshes(&self) -> bool {
        !self.meshes.is_empty() || self.labels.is_some()
    }

    /// The iso value of the volume's isosurface in a surface scene (the scene's, else
    /// the middle of the robust range), `None` when the scene has no volume.
    pub(crate) fn surface_iso(&self, field: Option<&Field>) -> Option<f32> {
        let field = field?;
        let (lo, hi) = field.robust_range();
        Some(self.iso.unwrap_or((lo + hi) / 2.0))
    }
}
