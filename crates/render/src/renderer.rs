//! The [`Renderer`]: scenes of one volume and one set of meshes turned into images,
//! keeping what frames share (the field, the meshes, the classification).

use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Instant;

use glint_core::camera::{Camera, Focus, Projection};
use glint_core::{Image, Legend, RenderError, RenderMode, ScalarColors, Shader, Timings};
use glint_io::{ReadOptions, Volume};
use glint_volume::Transport as VolumeTransport;
use glint_volume::{
    Classification, ClassifySettings, ColourVolume, Field, Filter, FrameSettings, Kernel,
    Occluders, PathFeatures, PathImage, Prefilter, ShadowField, ShadowSettings, Source,
    TransferFunction,
};

use crate::denoise::Denoise;
use crate::hwlobe::HwCache;
use crate::labels::LabelMeshes;
use crate::meshes::{MeshKey, MeshSet};
use crate::scene::{Derived, EnvCache, Input, MeshLayer, Plan, Resolved, Scene, Transport};

/// The `shadows` model's last light volumes, for the classification and settings they
/// were built with (reused while the lights point the same way).
#[derive(Clone)]
struct ShadowCache {
    class: Arc<Classification>,
    settings: ShadowSettings,
    /// The meshes' occupancy the light volumes were built with.
    occluders: Option<Arc<Occluders>>,
    /// The clip the light volumes were built with (clipped space casts no shadow).
    clip: glint_core::Clip,
    field: Arc<ShadowField>,
}

/// The meshes voxelised on a field's light-volume grid, for the meshes and field they
/// were built from (rebuilt when either changes).
#[derive(Clone)]
struct OccluderCache {
    surfaces: Arc<glint_raster::Surfaces>,
    field: Arc<Field>,
    occluders: Arc<Occluders>,
}

/// A path-traced image being accumulated, for the scene it renders (the resolved
/// scene's JSON without its sample count and time budget).
#[derive(Clone)]
struct PathAccumulation {
    key: String,
    image: PathImage,
    /// The frame's feature buffers, once a denoised frame asked for them.
    features: Option<Arc<PathFeatures>>,
}

/// Data in memory a renderer can be made of ([`Renderer::from_source`]); each is
/// shared, never copied.
#[derive(Clone)]
pub enum InMemory {
    /// A volume: the renderer builds its field, and its colours when it is a colour
    /// volume.
    Volume(Arc<Volume>),
    /// Any [`Source`] of samples (e.g. an OME-Zarr level streamed from disk,
    /// [`glint_volume::open_zarr`]): the renderer builds its field.
    Source(Arc<dyn Source>),
    /// A field already built (one per viewer, shared by its clients' renderers).
    Field(Arc<Field>),
}

impl From<Arc<Volume>> for InMemory {
    fn from(volume: Arc<Volume>) -> InMemory {
        InMemory::Volume(volume)
    }
}

impl From<Volume> for InMemory {
    /// The volume moved into an [`Arc`] (not copied).
    fn from(volume: Volume) -> InMemory {
        InMemory::Volume(Arc::new(volume))
    }
}

impl From<Arc<dyn Source>> for InMemory {
    fn from(source: Arc<dyn Source>) -> InMemory {
        InMemory::Source(source)
    }
}

impl From<Arc<Field>> for InMemory {
    fn from(field: Arc<Field>) -> InMemory {
        InMemory::Field(field)
    }
}

impl From<Field> for InMemory {
    fn from(field: Field) -> InMemory {
        InMemory::Field(Arc::new(field))
    }
}

/// What a renderer keeps to build its field (again, for another [`Prefilter`]).
#[derive(Clone)]
enum Kept {
    Volume(Arc<Volume>),
    Source(Arc<dyn Source>),
}

impl Kept {
    /// The field with `prefilter`.
    fn field(&self, prefilter: Prefilter) -> Result<Field, RenderError> {
        match self {
            Kept::Volume(volume) => Field::shared(volume.clone(), prefilter),
            Kept::Source(source) => Field::from_source(source.clone(), prefilter, &|_, _| {}),
        }
    }
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
    /// The names and colours of the labels shown, for a legend ([`Legend::draw`]);
    /// `None` without a label map (or with its legend turned off).
    pub legend: Option<Legend>,
}

impl Rendered {
    /// Maps the image's radiance to display light with the scene's exposure and tone
    /// curve ([`Scene::exposure`], [`Scene::tone`]; nothing changes at exposure 0
    /// with the `linear` curve): what [`Renderer::render`] does after rendering, and
    /// what a caller of [`Renderer::render_linear`] does after working on the
    /// radiance.
    pub fn tone_map(&mut self) {
        glint_core::tone_map(&mut self.image, self.scene.exposure, self.scene.tone);
    }

    /// Draws the colour bar ([`Rendered::colors`]) and the legend
    /// ([`Rendered::legend`]) into the image, as `glint render` writes it.
    pub fn draw_overlays(&mut self) {
        if let Some(colors) = &self.colors {
            colors.draw_bar(&mut self.image);
        }
        if let Some(legend) = &self.legend {
            legend.draw(&mut self.image);
        }
    }
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
    pub(crate) meshes: Option<(MeshKey, Arc<MeshSet>)>,
    /// The last `hw` lobe's unit and table.
    hw: HwCache,
    /// Which compositing loop frames use (the SIMD one by default).
    pub kernel: Kernel,
    opened: Timings,
    notes: Vec<String>,
    /// The source the field is built from (a volume, a streamed OME-Zarr level),
    /// kept to build the field when a scene asks for another [`Prefilter`] (or for
    /// the first time, when no prefilter was given); `None` for a renderer made from
    /// a field, or of meshes only.
    source: Option<Kept>,
    /// The last light volumes (`shadows` scenes).
    shadows: Option<ShadowCache>,
    /// The meshes as occluders of the volume's light (`shadows` and `path` scenes
    /// with meshes).
    occluders: Option<OccluderCache>,
    /// The path-traced image of the last `path` scene: rendering the same scene with
    /// more samples adds to it; any other change starts again.
    paths: Option<PathAccumulation>,
    /// The environment map of the last `path` scene with one.
    environment: EnvCache,
    /// Set by another thread to stop a volume render in flight ([`Renderer::set_cancel`]).
    cancel: Option<Arc<AtomicBool>>,
    /// A colour volume's colours ([`glint_io::Volume::colour`]), on the field's grid:
    /// its samples take their colour from them, their opacity from the transfer
    /// function of its grey samples. (A volume read with
    /// [`ReadOptions::colour`] off has none and renders grey.)
    colours: Option<Arc<ColourVolume>>,
    /// The GPU of `--device gpu` and `auto` frames (crate::device).
    gpu: crate::device::GpuSlot,
}

impl Renderer {
    /// Reads `scene`'s input with `options` and builds its field with the scene's
    /// prefilter (so rendering the scene builds no second field), then reads its
    /// meshes (with their overlays and label map, and the volume's isosurface in
    /// surface mode) when it has them. An OME-Zarr store is streamed: its chunks are
    /// decoded into the field's bricks as they are built, never read whole; any other
    /// input is read whole ([`Input::open_with`]). A scene without a volume
    /// ([`Input::None`]) reads only its meshes. The reader's notes are kept
    /// ([`Renderer::notes`]).
    pub fn open(scene: &Scene, options: &ReadOptions) -> Result<Renderer, RenderError> {
        let mut renderer = Renderer::read(&scene.input, options)?;
        renderer.use_prefilter(scene.prefilter)?;
        renderer.keep_colours()?;
        if scene.has_meshes() || scene.is_surface() {
            renderer.mesh_set(scene)?;
        }
        Ok(renderer)
    }

    /// A renderer of data already in memory, without reading anything: a volume or
    /// another [`Source`] (shared, not copied: the renderer keeps it to build the
    /// field, and to build it again when a scene asks for another [`Prefilter`]), or a
    /// field already built (several renderers can share one field, each with its own
    /// classification; such a renderer renders only scenes of the field's
    /// prefilter).
    ///
    /// The field of a volume or source is built now with `prefilter` when it is
    /// given, else with the prefilter of the first scene resolved (so that scene
    /// builds one field, not two; [`Renderer::field`] is `None` until then). A
    /// `prefilter` other than a given field's is refused.
    pub fn from_source(
        source: impl Into<InMemory>,
        prefilter: Option<Prefilter>,
    ) -> Result<Renderer, RenderError> {
        let mut renderer = Renderer::empty();
        match source.into() {
            InMemory::Volume(volume) => renderer.source = Some(Kept::Volume(volume)),
            InMemory::Source(source) => renderer.source = Some(Kept::Source(source)),
            InMemory::Field(field) => {
                renderer.opened = field.timings().clone();
                renderer.field = Some(field);
            }
        }
        if let Some(prefilter) = prefilter {
            renderer.use_prefilter(prefilter)?;
        }
        renderer.keep_colours()?;
        Ok(renderer)
    }

    /// The colours of a colour volume ([`ColourVolume`]), for its classifications.
    fn keep_colours(&mut self) -> Result<(), RenderError> {
        if let Some(Kept::Volume(volume)) = &self.source {
            self.colours = ColourVolume::from_volume(volume)?.map(Arc::new);
        }
        Ok(())
    }

    /// A renderer with nothing in it yet.
    fn empty() -> Renderer {
        Renderer {
            field: None,
            classification: None,
            meshes: None,
            hw: HwCache::default(),
            kernel: Kernel::Auto,
            opened: Timings::default(),
            notes: Vec::new(),
            source: None,
            shadows: None,
            occluders: None,
            paths: None,
            environment: EnvCache::default(),
            cancel: None,
            colours: None,
            gpu: Default::default(),
        }
    }

    /// A renderer of `input` read with `options`, its field not built yet (the
    /// reading's times and notes kept); an empty one for [`Input::None`].
    fn read(input: &Input, options: &ReadOptions) -> Result<Renderer, RenderError> {
        let mut renderer = Renderer::empty();
        if *input == Input::None {
            return Ok(renderer);
        }
        let start = Instant::now();
        if let Input::Path(path) = input {
            if options.raw.is_none() && glint_io::zarr::is_store(path) {
                // An OME-Zarr level is streamed: its chunks are decoded into the bricks
                // as they are built, through a bounded cache, never read whole.
                let stream = glint_volume::open_zarr(path, options)?;
                renderer.opened.record("read", start.elapsed());
                renderer.notes = stream.notes().to_vec();
                renderer.source = Some(Kept::Source(Arc::new(stream)));
                return Ok(renderer);
            }
        }
        let opened = input.open_with(options)?;
        // Inflating is reported apart from reading and parsing (issue 12).
        let inflate = opened.inflate.unwrap_or_default();
        let read = &mut renderer.opened;
        read.record("read", start.elapsed().saturating_sub(inflate));
        if let Some(inflate) = opened.inflate {
            read.record("read: inflate", inflate);
        }
        renderer.source = Some(Kept::Volume(Arc::new(opened.volume)));
        renderer.notes = opened.notes;
        Ok(renderer)
    }

    /// What the reader said about the input: where the affine came from, what it
    /// assumed (lines starting "geometry assumed:"), dropped dimensions.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The units of the volume's values when its file names them (e.g. `HU`);
    /// `None` for a renderer made from a field or a streamed source.
    pub(crate) fn units(&self) -> Option<String> {
        match &self.source {
            Some(Kept::Volume(v)) => v.units.clone(),
            _ => None,
        }
    }

    /// Builds the field with `prefilter` when it is not built yet or was built with
    /// another one (and forgets what depended on it); nothing without a volume.
    fn use_prefilter(&mut self, prefilter: Prefilter) -> Result<(), RenderError> {
        let filter = self
            .field
            .as_ref()
            .map_or(Filter::default(), |f| f.filter());
        self.use_field(prefilter, filter)
    }

    /// Makes the field one with `prefilter` and `filter`: built when there is none or
    /// its prefilter differs, reconstructed with `filter` when only that differs
    /// (the same bricks when no classification or frame holds the field, else built
    /// again), forgetting what depended on it; nothing without a volume. A field given
    /// to the renderer ([`InMemory::Field`]) is refused another prefilter or filter.
    fn use_field(&mut self, prefilter: Prefilter, filter: Filter) -> Result<(), RenderError> {
        if let Some(field) = &self.field {
            if field.prefilter() == prefilter && field.filter() == filter {
                return Ok(());
            }
        }
        let source = match (&self.source, &self.field) {
            (Some(source), _) => source,
            (None, None) => return Ok(()),
            (None, Some(field)) => {
                let (what, want, have) = if field.prefilter() != prefilter {
                    ("prefilter", prefilter.name(), field.prefilter().name())
                } else {
                    ("filter", filter.name(), field.filter().name())
                };
                return Err(RenderError::Parameter(format!(
                    "{what} {want}: this renderer was given a field built with {what} {have}"
                )));
            }
        };
        self.classification = None;
        self.meshes = None;
        self.shadows = None;
        self.paths = None;
        let same_prefilter = self.field.as_ref().map(|f| f.prefilter()) == Some(prefilter);
        let field = match self.field.take().map(Arc::try_unwrap) {
            Some(Ok(field)) if same_prefilter => field,
            _ => {
                let field = source.field(prefilter)?;
                self.opened.extend(field.timings());
                field
            }
        };
        self.field = Some(Arc::new(field.with_filter(filter)));
        Ok(())
    }

    /// The field every scene is rendered from; `None` for a renderer of meshes only, or
    /// one made from a volume or source ([`Renderer::from_source`]) before its first
    /// scene.
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
        let labels = scene.labels.clone().map(|mut l| {
            l.resolve_table();
            l
        });
        let key = MeshKey::new(&scene.meshes, iso, labels.as_ref());
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
        let label_meshes = match &labels {
            Some(spec) => {
                let image = match &scene.input {
                    Input::Path(p) => Some(p.as_path()),
                    _ => None,
                };
                let built = self
                    .opened
                    .time("labels", || LabelMeshes::build(spec, image))?;
                if let Some(f) = field {
                    built.check_overlap(spec, glint_labels::world_box(f.dims(), &f.affine()))?;
                }
                Some(built)
            }
            None => None,
        };
        let set = self.opened.time("meshes", || {
            MeshSet::load(&scene.meshes, extra, label_meshes)
        })?;
        let set = Arc::new(set);
        self.meshes = Some((key, set.clone()));
        Ok(set)
    }

    /// Resolves `scene` against this renderer's volume ([`Scene::resolve_for`]) or,
    /// for a surface scene, its meshes (read now if the scene names others); a `hw`
    /// lobe's table is built once per (configuration, n) and kept.
    pub fn resolve(&mut self, scene: &Scene) -> Result<Resolved, RenderError> {
        self.use_field(scene.prefilter, scene.filter)?;
        if scene.is_surface() || self.field.is_none() {
            let set = self.mesh_set(scene)?;
            return scene.resolve_surface(self.field.as_deref(), &set, &self.hw);
        }
        let mut resolved = if scene.has_meshes() {
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
    /// A colour volume's classification takes its colours from the data
    /// ([`Classification::with_colour`]).
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
        let mut c = Classification::new(field, tf, settings)?;
        if let Some(colours) = &self.colours {
            c = c.with_colour(colours.clone())?;
        }
        let c = Arc::new(c);
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

    /// Renders a scene resolved by [`Renderer::resolve`], its radiance mapped to
    /// display light by the scene's exposure and tone curve ([`Rendered::tone_map`]).
    pub fn render_resolved(
        &mut self,
        resolved: Resolved,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Rendered, RenderError> {
        let mut rendered = self.render_resolved_linear(resolved, progress)?;
        rendered.tone_map();
        Ok(rendered)
    }

    /// Renders `scene` as [`Renderer::render`] does, but leaves the image as linear
    /// radiance: no exposure, no tone curve (what `.exr` and `.pfm` output write, and
    /// what a denoiser works on before [`Rendered::tone_map`]).
    pub fn render_linear(
        &mut self,
        scene: &Scene,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Rendered, RenderError> {
        let resolved = self.resolve(scene)?;
        self.render_resolved_linear(resolved, progress)
    }

    /// [`Renderer::render_resolved`] without the exposure and tone curve: linear
    /// radiance ([`Renderer::render_linear`]).
    pub fn render_resolved_linear(
        &mut self,
        resolved: Resolved,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Rendered, RenderError> {
        let mut timings = self.opened.clone();
        let mut scene = resolved.scene;
        let (image, derived, colors, legend) = match resolved.plan {
            Plan::Volume {
                tf,
                classify,
                mut frame,
                meshes,
                transport,
            } => {
                let start = Instant::now();
                let (class, built) = self.classification(&tf, &classify)?;
                if built {
                    timings.record("classify", start.elapsed());
                }
                let focus = self.focus(&scene, &mut frame, transport)?;
                let camera = class.camera(&frame)?;
                let legend = meshes.as_ref().and_then(|m| m.legend.clone());
                let occluders = self.occluders(&class, meshes.as_ref(), transport, &mut timings);
                let volume = VolumeFrame {
                    occluders: occluders.as_ref(),
                    class: &class,
                    shader: &resolved.shader,
                    frame: &frame,
                    camera: &camera,
                    meshes: meshes.as_ref(),
                };
                let image = timings.time("frame", || {
                    self.render_volume(&volume, transport, &scene, progress)
                })?;
                let field = self.field.as_deref().expect("a volume plan has a field");
                let step_mm = scene.step * field.min_spacing();
                let mut d = derived(&camera);
                d.step_mm = Some(step_mm);
                d.min_spacing_mm = Some(field.min_spacing());
                d.transfer_function = Some(tf);
                d.focus_mm = focus;
                (image, d, None, legend)
            }
            Plan::Surface {
                surfaces,
                settings,
                colors,
                legend,
            } => {
                let camera = surfaces.camera(&settings)?;
                let image = timings.time("frame", || {
                    surfaces.render(&camera, &resolved.shader, &settings, colors.as_ref())
                })?;
                progress(u64::from(settings.width) * u64::from(settings.height));
                (image, derived(&camera), colors, legend)
            }
        };
        scene.derived = Some(derived);
        Ok(Rendered {
            image,
            scene,
            timings,
            colors,
            legend,
        })
    }
}

/// What a volume frame is rendered from.
struct VolumeFrame<'a> {
    class: &'a Arc<Classification>,
    shader: &'a Shader,
    frame: &'a FrameSettings,
    camera: &'a Camera,
    meshes: Option<&'a MeshLayer>,
    /// The meshes as occluders of the volume's light (`shadows` and `path`).
    occluders: Option<&'a Arc<Occluders>>,
}

impl Renderer {
    /// The volume frame of `v` under `transport`, drawn over its meshes when it has
    /// any (rays stop at them).
    fn render_volume(
        &mut self,
        v: &VolumeFrame,
        transport: Transport,
        scene: &Scene,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Image, RenderError> {
        let (class, shader, frame) = (v.class, v.shader, v.frame);
        let on = (&**class, shader, frame, v.meshes.is_some());
        if let Some(image) = self.gpu.frame(scene.device, on, transport)? {
            return Ok(image);
        }
        let env = self.environment.get(&scene.lighting)?;
        // Every model stops when the flag is set ([`Renderer::set_cancel`]).
        let stop = self.cancel.clone();
        let stop = stop.as_deref();
        let mut volume = |far: Option<&[f32]>| -> Result<Image, RenderError> {
            match transport {
                Transport::Local => class.frame_cancellable(
                    shader,
                    frame,
                    far,
                    VolumeTransport::Local,
                    progress,
                    stop,
                ),
                Transport::Shadows(settings) => {
                    let lights = self.shadow_field(class, v, settings)?;
                    class.frame_cancellable(
                        shader,
                        frame,
                        far,
                        VolumeTransport::Shadows(&lights),
                        progress,
                        stop,
                    )
                }
                Transport::Path {
                    spp,
                    settings,
                    denoise,
                } => {
                    let mut key = scene.clone();
                    key.lighting.spp = None;
                    key.lighting.time_budget = None;
                    // Denoising is applied to the accumulated samples: turning it on
                    // or off keeps them.
                    key.lighting.denoise = None;
                    key.derived = None;
                    // The display transform does not change the radiance traced.
                    key.exposure = 0.0;
                    key.tone = glint_core::Tone::Linear;
                    let key = key.to_json()?;
                    let size = [frame.width, frame.height];
                    let acc = match self.paths.take() {
                        Some(a) if a.key == key && a.image.samples() <= spp => a,
                        _ => PathAccumulation {
                            key,
                            image: PathImage::new(size[0], size[1]),
                            features: None,
                        },
                    };
                    let cancel = self.cancel.clone();
                    let acc = self.paths.insert(acc);
                    let light = VolumeTransport::Path {
                        image: &mut acc.image,
                        spp,
                        settings,
                        occluders: v.occluders.map(|o| &**o),
                        environment: env.as_deref(),
                        cancel: cancel.as_deref(),
                    };
                    let traced = match class.frame(shader, frame, far, light, progress) {
                        Ok(image) => image,
                        Err(e) => {
                            // A cancelled batch left some rows with more samples than
                            // others: the image cannot be continued.
                            self.paths = None;
                            return Err(e);
                        }
                    };
                    if denoise == Denoise::None {
                        return Ok(traced);
                    }
                    // The features depend on the camera and the classification only
                    // (the key): built once, kept while samples are added.
                    let features = match &acc.features {
                        Some(f) => f.clone(),
                        None => {
                            let f = Arc::new(class.path_features(shader, frame, far)?);
                            acc.features.insert(f).clone()
                        }
                    };
                    let variance = acc.image.variance_of_mean();
                    crate::denoise::denoise(&traced, &features, &variance, denoise)
                }
            }
        };
        match v.meshes {
            None => volume(None),
            Some(layer) => layer.render(v.camera, shader, |far| volume(Some(far))),
        }
    }

    /// The distance in focus of a thin-lens camera in `path` lighting, written into
    /// `frame`'s camera: its own, or for `auto` (or none given) the depth of the
    /// first opaque point under the image's centre ([`Renderer::pick`]); an error
    /// when nothing is there. `None` for a pinhole or another lighting model (which
    /// renders a pinhole).
    fn focus(
        &mut self,
        scene: &Scene,
        frame: &mut FrameSettings,
        transport: Transport,
    ) -> Result<Option<f64>, RenderError> {
        let lens = frame.camera.aperture > 0.0;
        if !lens || !matches!(transport, Transport::Path { .. }) {
            return Ok(None);
        }
        let d = match frame.camera.focus {
            Some(Focus::Distance(d)) => d,
            _ => {
                let (x, y) = (f64::from(frame.width) / 2.0, f64::from(frame.height) / 2.0);
                match self.pick(scene, x, y)? {
                    Some(hit) if hit.depth_mm > 0.0 => hit.depth_mm,
                    _ => {
                        return Err(RenderError::Parameter(
                            "autofocus: nothing opaque under the image centre; give the focus distance in mm (--focus MM)".into(),
                        ))
                    }
                }
            }
        };
        frame.camera.focus = Some(Focus::Distance(d));
        Ok(Some(d))
    }

    /// The light volumes of the frame's lights for its camera, its meshes opaque: the
    /// last ones when they were built for the same classification, settings, meshes
    /// and light directions.
    fn shadow_field(
        &mut self,
        class: &Arc<Classification>,
        v: &VolumeFrame,
        settings: ShadowSettings,
    ) -> Result<Arc<ShadowField>, RenderError> {
        let same_occluders = |c: &ShadowCache| match (&c.occluders, v.occluders) {
            (None, None) => true,
            (Some(a), Some(b)) => Arc::ptr_eq(a, b),
            _ => false,
        };
        if let Some(c) = &self.shadows {
            if Arc::ptr_eq(&c.class, class)
                && c.settings == settings
                && same_occluders(c)
                && c.clip == v.frame.clip
                && c.field.is_for(v.shader, v.camera)
            {
                return Ok(c.field.clone());
            }
        }
        let occluders = v.occluders.map(|o| &**o);
        let field = Arc::new(class.shadow_field(v.shader, v.frame, &settings, occluders)?);
        self.shadows = Some(ShadowCache {
            class: class.clone(),
            settings,
            occluders: v.occluders.cloned(),
            clip: v.frame.clip.clone(),
            field: field.clone(),
        });
        Ok(field)
    }

    /// The meshes of `layer` voxelised on `class`'s field, for the `shadows` and
    /// `path` models (`None` in `local` or without meshes): the last ones when the
    /// meshes and the field are the same; the time of a build is recorded as
    /// `occluders`.
    fn occluders(
        &mut self,
        class: &Classification,
        layer: Option<&MeshLayer>,
        transport: Transport,
        timings: &mut Timings,
    ) -> Option<Arc<Occluders>> {
        if matches!(transport, Transport::Local) {
            return None;
        }
        let surfaces = layer?.surfaces.as_ref()?;
        let field = class.field();
        if let Some(c) = &self.occluders {
            if Arc::ptr_eq(&c.surfaces, surfaces) && Arc::ptr_eq(&c.field, field) {
                return Some(c.occluders.clone());
            }
        }
        let occluders = Arc::new(timings.time("occluders", || {
            Occluders::new(field, surfaces.triangle_corners())
        }));
        self.occluders = Some(OccluderCache {
            surfaces: surfaces.clone(),
            field: field.clone(),
            occluders: occluders.clone(),
        });
        Some(occluders)
    }

    /// Gives the renderer a flag that stops a volume render in flight, under every
    /// lighting model, when another thread sets it: the ray caster leaves the tiles
    /// not begun, the path tracer the rows; that render returns
    /// [`RenderError::Cancelled`] and the path samples it held are dropped. The flag is the caller's to clear before the next render.
    /// A clone keeps the flag; give each clone its own (one per viewer client).
    pub fn set_cancel(&mut self, flag: Option<Arc<AtomicBool>>) {
        self.cancel = flag;
    }

    /// Forgets the path-traced image it holds: the next `path` render starts from no
    /// samples (benchmarks repeating one frame).
    pub fn forget_paths(&mut self) {
        self.paths = None;
    }

    /// Notes, each once, on `--device auto` frames rendered on the CPU instead.
    pub fn device_notes(&mut self) -> Vec<String> {
        self.gpu.take_notes()
    }

    /// Samples per pixel of the path-traced image the renderer holds (0 when it holds
    /// none): a `path` scene rendered again with more samples continues from it.
    pub fn path_samples(&self) -> u32 {
        self.paths.as_ref().map_or(0, |p| p.image.samples())
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
        focus_mm: None,
        step_mm: None,
        min_spacing_mm: None,
        transfer_function: None,
    }
}

/// The one-shot resolve, here rather than beside the scene's other rules so that the
/// scene does not depend on the renderer (no module cycle).
impl Scene {
    /// Reads the input and the meshes and resolves the scene against them (one-shot;
    /// a [`Renderer`] keeps the volume, the meshes and the classification across
    /// scenes).
    pub fn resolve(&self) -> Result<Resolved, RenderError> {
        Renderer::open(self, &ReadOptions::default())?.resolve(self)
    }
}
