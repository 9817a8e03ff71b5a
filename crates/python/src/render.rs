//! `glint.Renderer`, `glint.render` and `glint.Image`: glint_render's Renderer over
//! `glint.Volume`s and `glint.Scene`s, images out as numpy arrays and PNG.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use numpy::{PyArray1, PyArrayMethods as _};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use glint_render::{
    Depth, Input, ReadOptions, RenderError, Rendered, Renderer as RRenderer, SceneLobe,
};

use crate::errors::{self, render_error};
use crate::scene::{with_fields, Scene};
use crate::volume::Volume;

/// What a renderer draws: a volume in memory, or a file to read.
enum Source {
    Volume(Arc<glint_io::Volume>, Option<PathBuf>),
    Path(PathBuf),
}

/// A `glint.Volume` or a path.
fn source_of(obj: &Bound<'_, PyAny>) -> PyResult<Source> {
    if let Ok(v) = obj.cast::<Volume>() {
        let v = v.get();
        let path = v.source.as_ref().map(|(p, _)| p.clone());
        return Ok(Source::Volume(Arc::clone(&v.inner), path));
    }
    Ok(Source::Path(obj.extract::<PathBuf>().map_err(|_| {
        pyo3::exceptions::PyTypeError::new_err(format!(
            "expected a glint.Volume or a path, got {}",
            obj.get_type()
                .name()
                .map(|n| n.to_string())
                .unwrap_or_default()
        ))
    })?))
}

/// Renders scenes of one volume, keeping its gradients and the last classification
/// (transfer function, step, mode) across calls: views that change only the camera,
/// lights, lobe or size render without classifying again.
#[pyclass(module = "glint", frozen)]
pub struct Renderer {
    inner: Mutex<RRenderer>,
    /// The file the volume came from, written into rendered scenes' `input`.
    path: Option<PathBuf>,
}

impl Renderer {
    /// Opens `source` with the GIL released. A volume is shared, not copied, and its
    /// field is built at the first scene's prefilter; a file is read now, its field
    /// built with `scene`'s prefilter and its meshes read (the file replaces the
    /// scene's input).
    fn open(py: Python<'_>, source: Source, scene: &glint_render::Scene) -> PyResult<Renderer> {
        let (result, path) = match source {
            Source::Volume(v, path) => (
                crate::pool::detach(py, move || RRenderer::from_source(v, None))?,
                path,
            ),
            Source::Path(p) => {
                let scene = glint_render::Scene {
                    input: Input::Path(p.clone()),
                    ..scene.clone()
                };
                (
                    crate::pool::detach(py, move || {
                        RRenderer::open(&scene, &ReadOptions::default())
                    })?,
                    Some(p),
                )
            }
        };
        let inner = result.map_err(|e| render_error(py, e))?;
        Ok(Renderer {
            inner: Mutex::new(inner),
            path,
        })
    }

    /// The renderer of `scene`, of `volume` (a `glint.Volume` or a path) when it is
    /// given, else of the scene's own input: its field built once, with the scene's
    /// prefilter, and its meshes read once.
    fn for_scene(
        py: Python<'_>,
        volume: Option<&Bound<'_, PyAny>>,
        scene: &glint_render::Scene,
    ) -> PyResult<Renderer> {
        match volume {
            Some(v) => Renderer::open(py, source_of(v)?, scene),
            None => {
                let scene = scene.clone();
                let inner = crate::pool::detach(py, move || {
                    RRenderer::open(&scene, &ReadOptions::default())
                })?
                .map_err(|e| render_error(py, e))?;
                Ok(Renderer {
                    inner: Mutex::new(inner),
                    path: None,
                })
            }
        }
    }

    /// Renders with the GIL released (other threads wait for this renderer's lock
    /// without holding the GIL).
    fn render_scene(&self, py: Python<'_>, mut scene: glint_render::Scene) -> PyResult<Image> {
        if let Some(p) = &self.path {
            scene.input = Input::Path(p.clone());
        }
        let rendered = crate::pool::detach(py, || {
            let mut r = self
                .inner
                .lock()
                .unwrap_or_else(|poisoned| poisoned.into_inner());
            r.render_linear(&scene, &|_| {})
        })?
        .map_err(|e| render_error(py, e))?;
        Ok(Image::from_radiance(rendered))
    }
}

#[pymethods]
impl Renderer {
    /// A renderer of a `glint.Volume` (shared, not copied; its field is built for
    /// the first scene rendered) or of the volume file at a path (read now).
    #[new]
    fn new(py: Python<'_>, volume: &Bound<'_, PyAny>) -> PyResult<Renderer> {
        let source = source_of(volume)?;
        Renderer::open(py, source, &glint_render::Scene::default())
    }

    /// Renders `scene` (default: `glint.Scene()`), with keyword arguments replacing
    /// its fields; the scene's `input` is ignored (this renderer's volume is used).
    #[pyo3(signature = (scene=None, **fields))]
    fn render(
        &self,
        py: Python<'_>,
        scene: Option<&Bound<'_, Scene>>,
        fields: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Image> {
        let base = scene.map(|s| s.get().inner.clone()).unwrap_or_default();
        let scene = with_fields(&base, fields)?;
        self.render_scene(py, scene)
    }

    /// The 3D point image point `(x, y)` of `scene`'s image shows (pixels from the
    /// image's top-left corner; the centre of pixel (i, j) is (i + 0.5, j + 0.5)),
    /// traced as the frame traces that pixel's ray: a dict as `glint pick` prints it
    /// (`object`, `world_mm`, `depth_mm`, `voxel`, `voxel_nearest`, `value` in the
    /// volume's units, `interpolated`, `units`, `label`, `opacity`), or None where
    /// the pixel shows nothing. `opacity` is the composite mode's accumulated opacity
    /// threshold. A point off the image raises ValueError.
    #[pyo3(signature = (x, y, scene=None, opacity=glint_render::PICK_OPACITY, **fields))]
    fn pick<'py>(
        &self,
        py: Python<'py>,
        x: f64,
        y: f64,
        scene: Option<&Bound<'py, Scene>>,
        opacity: f32,
        fields: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let base = scene.map(|s| s.get().inner.clone()).unwrap_or_default();
        let mut scene = with_fields(&base, fields)?;
        if let Some(p) = &self.path {
            scene.input = Input::Path(p.clone());
        }
        let pick = crate::pool::detach(py, || {
            let mut r = self
                .inner
                .lock()
                .unwrap_or_else(|poisoned| poisoned.into_inner());
            r.pick_with(&scene, x, y, opacity)
        })?
        .map_err(|e| render_error(py, e))?;
        let json = serde_json::to_value(&pick).map_err(|e| errors::value_error(&e))?;
        crate::json::to_py(py, &json)
    }
}

/// Renders a volume (a `glint.Volume` or a path; None: the scene's own input) with a
/// scene: an sRGB uint8 array of shape (height, width, 3), as `glint render` writes
/// it to PNG; with `linear=True` the linear radiance instead, float32 (height, width,
/// 3), before the scene's exposure and tone curve (what `glint render -o x.exr`
/// writes). Keyword arguments replace scene fields. The GIL is released throughout.
#[pyfunction]
#[pyo3(signature = (volume=None, scene=None, linear=false, **fields))]
pub fn render<'py>(
    py: Python<'py>,
    volume: Option<&Bound<'py, PyAny>>,
    scene: Option<&Bound<'py, Scene>>,
    linear: bool,
    fields: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let base = scene.map(|s| s.get().inner.clone()).unwrap_or_default();
    let scene = with_fields(&base, fields)?;
    let renderer = Renderer::for_scene(py, volume, &scene)?;
    let image = renderer.render_scene(py, scene)?;
    if linear {
        image.linear(py)
    } else {
        image.array(py)
    }
}

/// Renders a turntable of a scene: `frames` views whose camera azimuth steps
/// 360/frames degrees from the scene's own (frame 0 is `glint.render`'s image), or with
/// `keys` `frames` views along camera keys (a list of cameras as the scene's `camera`
/// writes them, dicts with `azimuth`, `elevation` and `zoom`, or the path of a JSON
/// file of them: `glint render --camera-path`), with one renderer (the volume read and
/// classified once), written to `path` as `glint render --turntable` writes it: an
/// animated GIF (`.gif`), an animated WebP (`.webp`), an MP4 (`.mp4`, through ffmpeg)
/// or PNG frames in a directory (a path ending in `/`, or an existing directory). The
/// volume and scene are taken as by `glint.render`; nothing is left at `path` when it
/// fails. The GIL is released throughout.
#[pyfunction]
#[pyo3(signature = (scene, frames, path, fps=glint_render::DEFAULT_TURNTABLE_FPS, volume=None, keys=None, **fields))]
#[allow(clippy::too_many_arguments)]
pub fn turntable<'py>(
    py: Python<'py>,
    scene: Option<&Bound<'py, Scene>>,
    frames: u32,
    path: PathBuf,
    fps: u32,
    volume: Option<&Bound<'py, PyAny>>,
    keys: Option<&Bound<'py, PyAny>>,
    fields: Option<&Bound<'py, PyDict>>,
) -> PyResult<()> {
    let base = scene.map(|s| s.get().inner.clone()).unwrap_or_default();
    let mut scene = with_fields(&base, fields)?;
    let keys = keys.map(camera_keys).transpose()?;
    let turntable = glint_render::Turntable {
        fps,
        keys,
        ..glint_render::Turntable::new(frames)
    };
    // The keys, count, rate, format and ffmpeg are checked before the volume is read.
    let writer = turntable
        .writer(&path)
        .map_err(|e| errors::turntable_error(py, e))?;
    let renderer = Renderer::for_scene(py, volume, &scene)?;
    if let Some(p) = &renderer.path {
        scene.input = Input::Path(p.clone());
    }
    let mut inner = renderer
        .inner
        .into_inner()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    crate::pool::detach(py, || turntable.render(&mut inner, &scene, writer, &|_| {}))?
        .map_err(|e| errors::turntable_error(py, e))?;
    Ok(())
}

/// `glint.turntable`'s `keys`: a path of a JSON file (read as `--camera-path` reads
/// it) or a list of camera dicts; bad keys raise `ValueError` (an unreadable file
/// `OSError`) with `glint render`'s line.
fn camera_keys(keys: &Bound<'_, PyAny>) -> PyResult<glint_render::CameraPath> {
    let parsed = if let Ok(file) = keys.extract::<PathBuf>() {
        glint_render::CameraPath::load(&file)
    } else {
        let value = crate::json::to_json(keys)?;
        glint_render::CameraPath::from_json(&value.to_string())
    };
    parsed.map_err(|e| {
        let message = errors::one_line(&e);
        match e {
            glint_render::CameraPathError::Read { source, .. } => {
                errors::os_error(keys.py(), message, source)
            }
            other => errors::value_error(&other),
        }
    })
}

/// Compares a volume's rendering with the exact `cos^n` lobe and with each of `lobes`
/// (names as `glint compare --lobe` takes them), as `glint compare --json` does: a dict
/// with the same keys and the same numbers (the resolved scene, the highlight, per
/// lobe PSNR, SSIM, CIEDE2000 ΔE and ꟻLIP over the image and the highlight). The volume
/// and scene are taken as by `glint.render`; the GIL is released throughout.
///
/// A `path` scene gets the command's defaults (16 samples per pixel unless it sets
/// them; 128x128 unless a scene or a `size` is given) and, as there, each image's
/// distance to the exact lobe traced with `reference_spp` samples per pixel (16 times
/// the images' by default, 0 for none).
#[pyfunction]
#[pyo3(signature = (volume=None, scene=None, lobes=vec!["k".to_string()], reference_spp=None, **fields))]
pub fn compare<'py>(
    py: Python<'py>,
    volume: Option<&Bound<'py, PyAny>>,
    scene: Option<&Bound<'py, Scene>>,
    lobes: Vec<String>,
    reference_spp: Option<u32>,
    fields: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let base = scene.map(|s| s.get().inner.clone()).unwrap_or_default();
    let mut own = with_fields(&base, fields)?;
    let size_given = scene.is_some() || fields.is_some_and(|f| f.contains("size").unwrap_or(false));
    glint_compare::path_defaults(&mut own, size_given);
    let reference =
        glint_compare::reference_spp(&own, reference_spp).map_err(|e| errors::value_error(&e))?;
    let mut scene = own.with_exact_lobe();
    let lobes = lobes
        .iter()
        .map(|l| l.parse::<SceneLobe>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| render_error(py, e))?;
    let renderer = Renderer::for_scene(py, volume, &scene)?;
    if let Some(p) = &renderer.path {
        scene.input = Input::Path(p.clone());
    }
    let inner = renderer
        .inner
        .into_inner()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    let report = crate::pool::detach(py, || {
        glint_compare::run_against(inner, &scene, &lobes, None, reference)?.to_json()
    })?
    .map_err(|e| match e {
        glint_compare::CompareError::Render(e) => render_error(py, e),
        other => errors::value_error(&other),
    })?;
    crate::json::to_py(py, &report)
}

/// A rendered image: `array` (sRGB uint8, (height, width, 3)), the resolved `scene`,
/// PNG bytes; shows inline in Jupyter.
#[pyclass(module = "glint", frozen)]
pub struct Image {
    /// The image as shown: the radiance through the scene's exposure and tone curve.
    rendered: Rendered,
    /// The linear radiance, when the exposure and tone curve changed it (else it is
    /// `rendered`'s image).
    radiance: Option<glint_render::Image>,
}

impl Image {
    /// The image of a render's linear radiance ([`glint_render::Renderer::render_linear`]):
    /// tone mapped for display, the radiance kept for `linear` and float files.
    fn from_radiance(mut rendered: Rendered) -> Image {
        let s = &rendered.scene;
        let same = s.exposure == 0.0 && s.tone == glint_render::Tone::Linear;
        let radiance = (!same).then(|| rendered.image.clone());
        rendered.tone_map();
        Image { rendered, radiance }
    }

    /// The linear radiance.
    fn radiance(&self) -> &glint_render::Image {
        self.radiance.as_ref().unwrap_or(&self.rendered.image)
    }
}

#[pymethods]
impl Image {
    /// sRGB uint8 samples, shape (height, width, 3): the pixels of the PNG
    /// `glint render` writes.
    #[getter]
    fn array<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let img = &self.rendered.image;
        let shape = [img.height as usize, img.width as usize, 3];
        let bytes = crate::pool::detach(py, || img.encode_srgb(Depth::Eight))?;
        Ok(PyArray1::from_vec(py, bytes).reshape(shape)?.into_any())
    }

    /// Linear radiance, float32 (height, width, 3): the rendered light before the
    /// scene's exposure, tone curve and sRGB encoding (what `.exr` and `.pfm` files
    /// hold).
    #[getter]
    fn linear<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let img = self.radiance();
        let shape = [img.height as usize, img.width as usize, 3];
        let flat: Vec<f32> = img.rgb.iter().flatten().copied().collect();
        Ok(PyArray1::from_vec(py, flat).reshape(shape)?.into_any())
    }

    /// Accumulated opacity per pixel, float32 (height, width).
    #[getter]
    fn alpha<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let img = &self.rendered.image;
        let shape = [img.height as usize, img.width as usize];
        Ok(PyArray1::from_vec(py, img.alpha.clone())
            .reshape(shape)?
            .into_any())
    }

    /// Width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.rendered.image.width
    }

    /// Height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.rendered.image.height
    }

    /// The scene with every default chosen (`glint render --dump-scene` writes the
    /// same): render it again to get the same image.
    #[getter]
    fn scene(&self) -> Scene {
        Scene {
            inner: self.rendered.scene.clone(),
        }
    }

    /// Seconds spent reading, building the field, classifying (0 when the renderer
    /// reused its classification) and rendering the frame.
    #[getter]
    fn timings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        // The renderer's stages ("read", "field: ..." parts, "classify", "frame"),
        // with the field's parts summed and a stage that did not run as 0.
        let stages = self.rendered.timings.stages();
        let secs = |pick: &dyn Fn(&str) -> bool| -> f64 {
            stages
                .iter()
                .filter(|(s, _)| pick(s))
                .map(|(_, d)| d.as_secs_f64())
                .sum()
        };
        let d = PyDict::new(py);
        d.set_item("read", secs(&|s| s == "read"))?;
        d.set_item("field", secs(&|s| s.starts_with("field")))?;
        d.set_item("classify", secs(&|s| s == "classify"))?;
        d.set_item("frame", secs(&|s| s == "frame"))?;
        Ok(d)
    }

    /// The names of the stages that ran for this image, in order ("read", "field: ...",
    /// "classify", "frame"): "classify" is absent when the renderer reused its
    /// classification. What ran, without the times (tests check this, not wall time).
    #[getter]
    fn stages(&self) -> Vec<&'static str> {
        self.rendered
            .timings
            .stages()
            .iter()
            .map(|(s, _)| *s)
            .collect()
    }

    /// The image as an 8-bit sRGB PNG file's bytes.
    fn png<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let img = &self.rendered.image;
        let bytes = crate::pool::detach(py, || img.encode_png(Depth::Eight))?
            .map_err(|e| render_error(py, RenderError::Encode(e)))?;
        Ok(PyBytes::new(py, &bytes))
    }

    /// Jupyter's inline display.
    fn _repr_png_<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        self.png(py)
    }

    /// Writes an sRGB PNG atomically (no partial file on failure); `sixteen_bit` for
    /// 16 bits per channel. A path ending in `.exr` or `.pfm` gets the linear
    /// radiance ([`Image::linear`]) as OpenEXR (RGBA f32) or a Portable Float Map.
    #[pyo3(signature = (path, sixteen_bit=false))]
    fn save(&self, py: Python<'_>, path: PathBuf, sixteen_bit: bool) -> PyResult<()> {
        if let Some(format) = glint_render::FloatFormat::of_path(&path) {
            let img = self.radiance();
            return crate::pool::detach(py, || img.write_float(&path, format))?
                .map_err(|e| render_error(py, e));
        }
        let depth = if sixteen_bit {
            Depth::Sixteen
        } else {
            Depth::Eight
        };
        let img = &self.rendered.image;
        crate::pool::detach(py, || img.write_png(&path, depth))?.map_err(|e| render_error(py, e))
    }

    /// `numpy.asarray(image)` gives `image.array`.
    #[pyo3(signature = (dtype=None, copy=None))]
    fn __array__<'py>(
        &self,
        py: Python<'py>,
        dtype: Option<&Bound<'py, PyAny>>,
        copy: Option<bool>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let _ = copy; // always a new array
        let arr = self.array(py)?;
        match dtype {
            Some(d) => arr.call_method1("astype", (d,)),
            None => Ok(arr),
        }
    }

    fn __repr__(&self) -> String {
        let s = &self.rendered.scene;
        format!(
            "glint.Image({}x{}, lobe={} n={:?} v={})",
            self.rendered.image.width, self.rendered.image.height, s.lobe.kind, s.lobe.n, s.lobe.v
        )
    }
}
