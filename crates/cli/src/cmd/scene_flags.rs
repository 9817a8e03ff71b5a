//! The scene options shared by `glint render`, `glint compare` and `glint view`: one
//! `#[derive(clap::Args)]` struct flattened into each command, and the one function
//! that applies it to a [`Scene`], so the commands cannot drift apart.

use std::path::PathBuf;

use anyhow::bail;
use clap::builder::TypedValueParser;
use glint_io::zarr::Level;
use glint_io::{Format, Grey, ReadOptions};
use glint_lobe::Geometry;
use glint_render::{
    AreaLightSpec, AreaShapeSpec, Clip, ClipPlane, ColorMap, CropBox, Denoise, Device, Filter,
    Focus, Input, Light, LightFrame, LightingModel, MeshSpec, Overlay, Phantom, Prefilter,
    Projection, RenderMode, Sampler, Sampling, Scene, SceneLobe, Tone, TransferFunctionFile, View,
    WindowLevel,
};

use super::choice::choice;
use super::label_flags::LabelFlags;

/// Scene options. Every one is optional: unset, it keeps the scene file's value or the
/// scene default (which `Scene::resolve_for` chooses and `--dump-scene` shows).
#[derive(clap::Args, Default)]
pub struct SceneFlags {
    /// A volume (any format glint's io reads) and/or surface meshes (.gii with
    /// pointset and triangle arrays, .stl, .obj, .ply: told apart by extension);
    /// without any (and without --scene), the built-in phantom.
    #[arg(value_name = "INPUT")]
    pub input: Vec<PathBuf>,
    /// Per-vertex values for the meshes, one per mesh in order: a GIFTI shape or label
    /// array (the file's first per-vertex array unless --overlay-array says) or a PLY
    /// file's vertex scalar; repeatable.
    #[arg(long, value_name = "FILE")]
    pub overlay: Vec<PathBuf>,
    /// Which per-vertex array of each --overlay file (0-based, `glint info FILE` lists
    /// them), one per --overlay in order [default: 0]; repeatable.
    #[arg(long, value_name = "INDEX")]
    pub overlay_array: Vec<usize>,
    /// Colour map of the scalar overlays [default: viridis].
    #[arg(long, value_parser = choice::<ColorMap>(ColorMap::NAMES.iter().copied()))]
    pub colormap: Option<ColorMap>,
    /// Overlay values at the colour map's ends [default: the overlays' 2nd and 98th
    /// percentiles].
    #[arg(long, value_name = "LO,HI", allow_hyphen_values = true, value_parser = parse_range)]
    pub overlay_range: Option<[f32; 2]>,
    /// Surfaces: samples per pixel along each axis (anti-aliasing) [default: 2].
    #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(["1", "2", "4"]).map(|s| s.parse::<u32>().expect("one of the listed numbers")))]
    pub ssaa: Option<u32>,
    /// Start from this scene file; the flags below override its fields.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Built-in phantom when no input is given [default: head].
    #[arg(long, conflicts_with = "input", value_parser = choice::<Phantom>(Phantom::NAMES.iter().copied()))]
    pub phantom: Option<Phantom>,
    /// Grid edge of the built-in phantom [default: 128].
    #[arg(long, conflicts_with = "input")]
    pub phantom_size: Option<usize>,
    /// Transfer-function and material preset [default: the phantom's own for a phantom,
    /// ct-bone for CT-like volumes (robust minimum below -500), mr-t2-brain otherwise].
    #[arg(long, conflicts_with = "tf")]
    pub preset: Option<String>,
    /// Custom transfer function from a file: glint's JSON (see `glint render --help`),
    /// a ParaView colour map (.json) or a 3D Slicer volume property file (.vp), told
    /// apart by extension and contents.
    #[arg(long, visible_alias = "transfer-function", value_name = "FILE")]
    pub tf: Option<PathBuf>,
    /// Window width, in the volume's units (HU for CT): the transfer function (the
    /// preset's or --tf's) is stretched so that its opacity ramp spans this width,
    /// centred on --window-level [default: the function's own].
    #[arg(long, value_name = "WIDTH", requires = "window_level")]
    pub window: Option<f64>,
    /// Window level (centre), in the volume's units; with --window. (--level is the
    /// OME-Zarr pyramid level.)
    #[arg(
        long,
        value_name = "LEVEL",
        visible_alias = "window-center",
        requires = "window",
        allow_negative_numbers = true
    )]
    pub window_level: Option<f64>,
    /// How a volume becomes a picture; surface: its isosurface at --iso, rasterised with
    /// the meshes [default: composite; surface for meshes].
    #[arg(long, value_parser = choice::<RenderMode>(RenderMode::NAMES.iter().copied()))]
    pub mode: Option<RenderMode>,
    /// Iso value for --mode iso and --mode surface [default: the middle of the volume's
    /// robust range].
    #[arg(long, allow_negative_numbers = true)]
    pub iso: Option<f32>,
    /// Named view in the volume's world frame (RAS+) [default: anterior].
    #[arg(long, value_parser = choice::<View>(View::NAMES.iter().copied()))]
    pub view: Option<View>,
    /// Orbit the camera this many degrees about the view's up axis (towards the image's
    /// right) [default: 0].
    #[arg(long, allow_negative_numbers = true)]
    pub azimuth: Option<f64>,
    /// Orbit the camera this many degrees upwards [default: 0].
    #[arg(long, allow_negative_numbers = true)]
    pub elevation: Option<f64>,
    /// Magnification; 1 frames what the transfer function makes visible [default: 1].
    #[arg(long, allow_negative_numbers = true)]
    pub zoom: Option<f64>,
    /// Projection (perspective: 30° field of view) [default: perspective].
    #[arg(long, value_parser = choice::<Projection>(["perspective", "orthographic"]))]
    pub projection: Option<Projection>,
    /// Path lighting: thin-lens depth of field, the lens's radius in mm (0: a pinhole;
    /// local and shadows lighting always render a pinhole, with a note) [default: 0].
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    pub aperture: Option<f64>,
    /// Path lighting with --aperture: the distance in focus, mm from the eye along the
    /// view axis, or auto (the first opaque point under the image centre)
    /// [default: auto].
    #[arg(long, value_name = "MM|auto", allow_negative_numbers = true, value_parser = |s: &str| s.parse::<Focus>().map_err(|e| e.to_string()))]
    pub focus: Option<Focus>,
    /// Exposure in stops: the radiance is scaled by 2^EV before the tone curve (not
    /// in .exr/.pfm output, which is the radiance) [default: 0].
    #[arg(long, value_name = "EV", allow_negative_numbers = true)]
    pub exposure: Option<f64>,
    /// Tone curve from radiance to display light, before the sRGB encoding: linear
    /// (clips at 1), aces (Narkowicz's fit), agx (Blender 4's view transform)
    /// [default: linear].
    #[arg(long, value_parser = choice::<Tone>(Tone::NAMES.iter().copied()))]
    pub tone: Option<Tone>,
    /// Sample distance along rays, in voxels of the smallest spacing [default: 0.5].
    #[arg(long, allow_negative_numbers = true)]
    pub step: Option<f64>,
    /// Shininess n [default: the preset's specular power].
    #[arg(long, allow_negative_numbers = true)]
    pub n: Option<f64>,
    /// The power fits raise their base to 2^v [default: 4].
    #[arg(long)]
    pub v: Option<u32>,
    /// The hardware unit of `--lobe hw`: a `glint hw` configuration file (JSON; missing
    /// fields take the default's, see `glint hw eval --print-config`) [default: the
    /// scene's unit, else the default unit]. The unit's v is the lobe's: --v must agree.
    #[arg(long, value_name = "FILE")]
    pub hw_config: Option<PathBuf>,
    /// Highlight geometry: phong (R·V) or blinn (N·H) [default: phong].
    #[arg(long, value_parser = choice::<Geometry>(["phong", "blinn"]))]
    pub geometry: Option<Geometry>,
    /// Override the preset's ambient coefficient.
    #[arg(long, allow_negative_numbers = true)]
    pub ambient: Option<f32>,
    /// Override the preset's diffuse coefficient.
    #[arg(long, allow_negative_numbers = true)]
    pub diffuse: Option<f32>,
    /// Override the preset's specular coefficient.
    #[arg(long, allow_negative_numbers = true)]
    pub specular: Option<f32>,
    /// Extra directional light at AZ,EL degrees from the view direction (towards the
    /// image's right and top), optionally with an intensity; repeatable.
    #[arg(long = "light", value_name = "AZ,EL[,I]", allow_hyphen_values = true, value_parser = parse_light)]
    pub lights: Vec<Light>,
    /// Area light (every lighting model; path samples it with soft shadows, local and
    /// shadows take it as the directional light of its irradiance at the volume's
    /// centre), repeatable: KIND:SIZE:X,Y,Z:RADIANCE, then optionally :FRAME. KIND sphere (SIZE its
    /// radius, mm) or rect (SIZE WxH mm, facing the volume's centre); X,Y,Z its centre
    /// in mm from the volume's centre, along the camera's right, up and towards the
    /// viewer (FRAME camera, the default: it orbits with the camera) or the world's
    /// RAS+ axes (FRAME volume); RADIANCE one number or R,G,B. E.g. sphere:20:150,150,250:10
    #[arg(long = "area-light", value_name = "KIND:SIZE:X,Y,Z:RADIANCE[:FRAME]", allow_hyphen_values = true, value_parser = parse_area_light)]
    pub area_lights: Vec<AreaLightSpec>,
    /// Turn the headlight off (then give at least one --light).
    #[arg(long)]
    pub no_headlight: bool,
    /// Gradient-magnitude gate, a fraction of the value range per voxel: weaker
    /// gradients get no directional shading (no random highlights in flat regions)
    /// [default: 0.01].
    #[arg(long, allow_negative_numbers = true)]
    pub gate: Option<f64>,
    /// Image size WxH [default: 512x512].
    #[arg(long, value_parser = parse_size)]
    pub size: Option<[u32; 2]>,
    /// Clip plane through the point X,Y,Z with normal NX,NY,NZ (world mm, RAS+):
    /// keeps the side the normal points to, in every mode and lighting model; cut
    /// faces are lit with the plane's normal. Repeatable (all planes cut), added to a
    /// --scene file's planes. E.g. `--clip 0,0,0,1,0,0` keeps x >= 0.
    #[arg(long = "clip", value_name = "X,Y,Z,NX,NY,NZ", allow_hyphen_values = true, value_parser = parse_clip)]
    pub clip: Vec<ClipPlane>,
    /// Crop box XMIN,XMAX,YMIN,YMAX,ZMIN,ZMAX (world mm, axis-aligned): keeps its
    /// inside, as --clip cuts; replaces a --scene file's box.
    #[arg(long, value_name = "XMIN,XMAX,YMIN,YMAX,ZMIN,ZMAX", allow_hyphen_values = true, value_parser = parse_crop)]
    pub crop: Option<CropBox>,
    /// Where --clip or --crop cuts a closed mesh or label surface, close the cut with
    /// the plane (lit with its normal, in the surface's colour) instead of showing the
    /// inside.
    #[arg(long)]
    pub clip_caps: bool,
    /// Refuse what lenient readers accept with a note (DICOM without preamble or meta
    /// group, multi-frame DICOM without frame positions).
    #[arg(long)]
    pub strict: bool,
    /// A colour volume (DICOM RGB or YBR) rendered grey: its luminance (ITU-R BT.601
    /// luma) or one channel, through the transfer function's colours [default: the
    /// volume's own colours, with opacity from its luminance].
    #[arg(long, value_parser = choice::<Grey>(CHANNEL_NAMES))]
    pub channel: Option<Grey>,
    /// Level of an OME-Zarr pyramid to render: 0 (the finest), 1, ..., or auto (the
    /// coarsest with at least as many voxels along its longest edge as the image has
    /// pixels along its larger side) [default: 0].
    #[arg(long, value_parser = parse_level)]
    pub level: Option<LevelArg>,
    /// Filter applied to the volume before trilinear reconstruction: binomial (a
    /// [1 2 1]/4 low-pass per axis; no "wood grain" rings on surfaces) or none (the
    /// samples as stored) [default: binomial].
    #[arg(long, value_parser = choice::<Prefilter>(Prefilter::NAMES.iter().copied()))]
    pub prefilter: Option<Prefilter>,
    /// Reconstruction between voxels, of the values and their gradients, in every
    /// lighting model: trilinear, or tricubic (the cubic B-spline, Sigg and Hadwiger
    /// 2005: no stair steps of the voxel grid at a close zoom; it smooths slightly, and
    /// costs several times the frame time: docs/lighting.md) [default: trilinear].
    #[arg(long, value_parser = choice::<Filter>(Filter::NAMES.iter().copied()))]
    pub filter: Option<Filter>,
    /// Composite mode: point (the transfer function at each sample) or pre-integrated
    /// (integrated between samples, Engel et al. 2001: shells of opacity thinner than
    /// the step show without slicing rings, for about a third more frame time on the
    /// MNI152 scene) [default: point].
    #[arg(long, value_parser = choice::<Sampling>(Sampling::NAMES.iter().copied()))]
    pub sampling: Option<Sampling>,
    /// Where frames render: cpu; gpu (any adapter, lavapipe included; an error for
    /// what it does not render yet: docs/gpu.md); auto (a hardware GPU, else the CPU
    /// with a note) [default: cpu].
    #[arg(long, value_parser = choice::<Device>(Device::NAMES.iter().copied()))]
    pub device: Option<Device>,
    /// The length of matter, in mm, whose opacity the transfer function gives (VTK's
    /// scalar opacity unit distance) [default: one voxel of the smallest spacing].
    #[arg(long, value_name = "MM")]
    pub opacity_unit: Option<f64>,
    /// Light transport: local (every light reaches every sample), shadows (each
    /// light's transmittance through the volume scales it; a scattering medium where
    /// the gradient is weak; --occlusion adds local ambient occlusion) or path
    /// (progressive Monte Carlo path tracing with the lights, a uniform environment
    /// and the lobe importance-sampled: --spp, --bounces, --seed, --environment)
    /// [default: local].
    #[arg(long, value_parser = choice::<LightingModel>(LightingModel::ALL.map(|m| m.name())))]
    pub lighting: Option<LightingModel>,
    /// Path lighting: samples per pixel [default: 64].
    #[arg(long)]
    pub spp: Option<u32>,
    /// Path lighting: most scattering events of a path [default: 4].
    #[arg(long)]
    pub bounces: Option<u32>,
    /// Path lighting: seed of the random numbers (the same seed and --spp give the
    /// same image bit for bit) [default: 0].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Path lighting: the environment: a number, the radiance of a uniform white one
    /// [default: 0.5]; or an environment map replacing it: an equirectangular .hdr
    /// or .exr file, or a name: studio (built in), or a Poly Haven probe that
    /// scripts/fetch-samples fetches (apartment, bridge, city, dawn, esplanade, forest,
    /// hall, lab, lobby, night, park, sky, sunrise, sunset, venice, warehouse,
    /// workshop); importance-sampled with MIS. Shadows lighting takes a map (not a
    /// number) as up to 8 directional lights fitted to it by median cut.
    #[arg(long, allow_negative_numbers = true, value_name = "RADIANCE|FILE|NAME")]
    pub environment: Option<Environment>,
    /// Path and shadows lighting: degrees the environment map is turned about the vertical
    /// (superior) axis [default: 0].
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub environment_rotation: Option<f64>,
    /// Path and shadows lighting: the environment map's radiance scale [default: 1].
    #[arg(long, value_name = "X")]
    pub environment_intensity: Option<f32>,
    /// Path lighting: camera rays that meet no matter see the environment and the
    /// area lights (opaque) instead of the background.
    #[arg(long)]
    pub show_environment: bool,
    /// Path lighting: where the random numbers come from: sobol (Owen-scrambled Sobol
    /// points for the first dimensions of each path: less noise for the same --spp)
    /// or independent (PCG32 numbers throughout) [default: sobol].
    #[arg(long, value_parser = choice::<Sampler>(Sampler::ALL.map(|m| m.name())))]
    pub sampler: Option<Sampler>,
    /// Path lighting: a time budget per frame in milliseconds: passes of samples,
    /// spent where the noise is once every pixel holds a few, until the budget is
    /// spent; --spp is then the most a pixel takes (more than 0, at most one hour)
    /// [default: none: every pixel takes --spp].
    #[arg(long, value_name = "MS", allow_negative_numbers = true)]
    pub time_budget: Option<f64>,
    /// Shadows and path lighting: anisotropy g of the medium's Henyey-Greenstein phase
    /// function, -0.95..=0.95 (> 0 scatters forwards) [default: 0].
    #[arg(long, allow_negative_numbers = true)]
    pub anisotropy: Option<f32>,
    /// Shadows and path lighting: scale of the surface part of the hybrid, 0..=1 (0: a
    /// pure medium of extinction, albedo and phase function, as Mitsuba 3's volpath
    /// renders one: docs/lighting.md) [default: 1, the gradient gate's weight].
    #[arg(long, value_name = "W", allow_negative_numbers = true)]
    pub surface_weight: Option<f32>,
    /// Shadows lighting: local ambient occlusion on the ambient term.
    #[arg(long)]
    pub occlusion: bool,
    /// Path lighting: denoise the image, guided by the albedo, normal and depth of
    /// each pixel's first hit: none, atrous (the built-in edge-avoiding wavelet
    /// filter), oidn (Intel Open Image Denoise, loaded at run time: scripts/fetch-oidn
    /// fetches it) or auto (oidn where it loads, else atrous) [default: none].
    #[arg(long, value_parser = choice::<Denoise>(Denoise::ALL.map(|d| d.name())))]
    pub denoise: Option<Denoise>,
    /// Testing: turn empty-space skipping off.
    #[arg(long, hide = true)]
    pub no_skip: bool,
    #[command(flatten)]
    pub labels: LabelFlags,
}

/// `--channel`'s values: [`Grey::name`]s and their short forms (`Grey`'s `FromStr`).
const CHANNEL_NAMES: [&str; 8] = ["luminance", "luma", "red", "r", "green", "g", "blue", "b"];

impl SceneFlags {
    /// Makes `scene`'s lobe `kind`; a `hw` lobe takes its unit's v unless --v was
    /// given (a --v that contradicts the unit is refused when the scene is resolved).
    pub fn set_lobe(&self, scene: &mut Scene, kind: SceneLobe) {
        scene.lobe.set_kind(kind, self.v);
    }

    /// The scene file (or the default scene) with every given flag applied. Checks what
    /// can be checked before the volume is read (preset name, transfer-function file,
    /// n and v, lights).
    pub fn scene(&self) -> anyhow::Result<Scene> {
        let mut scene = match &self.scene {
            Some(path) => Scene::load(path)?,
            None => Scene::default(),
        };
        self.apply(&mut scene)?;
        Ok(scene)
    }

    /// How to read the input volume.
    pub fn read_options(&self) -> ReadOptions {
        let pixels = self.size.map_or(512, |[w, h]| w.max(h) as usize);
        ReadOptions {
            strict: self.strict,
            grey: self.channel.unwrap_or_default(),
            colour: self.channel.is_none(),
            level: match self.level {
                None => Level::Finest,
                Some(LevelArg::Index(i)) => Level::Index(i),
                Some(LevelArg::Auto) => Level::Auto(pixels),
            },
            ..ReadOptions::default()
        }
    }

    /// Applies every given flag to `scene`.
    pub fn apply(&self, scene: &mut Scene) -> anyhow::Result<()> {
        self.apply_input(scene)?;
        let alone = self.input.is_empty()
            && self.scene.is_none()
            && self.phantom.is_none()
            && self.phantom_size.is_none();
        self.labels.apply(scene, alone)?;
        self.apply_classification(scene)?;
        self.apply_lighting(scene)?;
        let camera = &mut scene.camera;
        set(&mut camera.view, self.view);
        set(&mut camera.azimuth, self.azimuth);
        set(&mut camera.elevation, self.elevation);
        set(&mut camera.zoom, self.zoom);
        set(&mut camera.projection, self.projection);
        set(&mut camera.aperture, self.aperture);
        if self.focus.is_some() {
            camera.focus = self.focus;
        }
        if camera.aperture > 0.0 && scene.lighting.model != LightingModel::Path {
            eprintln!(
                "glint: note: --aperture (depth of field) applies to path lighting; {} lighting renders a pinhole",
                scene.lighting.model.name()
            );
        }
        set(&mut scene.exposure, self.exposure);
        set(&mut scene.tone, self.tone);
        set(&mut scene.size, self.size);
        scene.clip.extend(self.clip.iter().copied());
        if self.crop.is_some() {
            scene.crop = self.crop;
        }
        scene.clip_caps |= self.clip_caps;
        set(&mut scene.step, self.step);
        set(&mut scene.prefilter, self.prefilter);
        set(&mut scene.filter, self.filter);
        set(&mut scene.sampling, self.sampling);
        set(&mut scene.device, self.device);
        if self.opacity_unit.is_some() {
            scene.opacity_unit = self.opacity_unit;
        }
        if self.no_skip {
            scene.skip_empty = false;
        }
        Ok(())
    }

    fn apply_input(&self, scene: &mut Scene) -> anyhow::Result<()> {
        let (meshes, volumes): (Vec<&PathBuf>, Vec<&PathBuf>) = self
            .input
            .iter()
            .partition(|p| Format::guess(p).is_some_and(Format::is_mesh));
        if volumes.len() > 1 {
            bail!(
                "{} volumes given ({}, {}): a scene holds one volume (and any number of meshes)",
                volumes.len(),
                volumes[0].display(),
                volumes[1].display()
            );
        }
        if !self.input.is_empty() {
            scene.input = volumes
                .first()
                .map_or(Input::None, |p| Input::Path(p.to_path_buf()));
            scene.meshes = meshes.into_iter().map(MeshSpec::new).collect();
        } else if self.phantom.is_some() || self.phantom_size.is_some() {
            let (name, size) = match scene.input {
                Input::Phantom { name, size } => (name, size),
                Input::Path(_) | Input::None => (Phantom::default(), Phantom::DEFAULT_SIZE),
            };
            scene.input = Input::Phantom {
                name: self.phantom.unwrap_or(name),
                size: self.phantom_size.unwrap_or(size),
            };
        }
        self.apply_overlays(scene)
    }

    /// `--overlay` (one per mesh, in order), `--colormap`, `--overlay-range`, `--ssaa`.
    fn apply_overlays(&self, scene: &mut Scene) -> anyhow::Result<()> {
        if self.overlay.len() > scene.meshes.len() {
            bail!(
                "{} overlays for {} meshes: give at most one --overlay per mesh, in the meshes' order",
                self.overlay.len(),
                scene.meshes.len()
            );
        }
        if self.overlay_array.len() > self.overlay.len() {
            bail!(
                "{} --overlay-array for {} overlays: give at most one per --overlay, in order",
                self.overlay_array.len(),
                self.overlay.len()
            );
        }
        for (k, (mesh, path)) in scene.meshes.iter_mut().zip(&self.overlay).enumerate() {
            mesh.overlay = Some(Overlay {
                array: self.overlay_array.get(k).copied(),
                ..Overlay::new(path)
            });
        }
        if self.colormap.is_some() || self.overlay_range.is_some() {
            let mut any = false;
            for o in scene.meshes.iter_mut().filter_map(|m| m.overlay.as_mut()) {
                set(&mut o.colormap, self.colormap.map(Some));
                set(&mut o.range, self.overlay_range.map(Some));
                any = true;
            }
            if !any {
                bail!("--colormap and --overlay-range need a mesh with an --overlay");
            }
        }
        set(&mut scene.ssaa, self.ssaa.map(Some));
        Ok(())
    }

    fn apply_classification(&self, scene: &mut Scene) -> anyhow::Result<()> {
        if let Some(p) = &self.preset {
            glint_render::preset(p)?; // fail before reading the volume
            scene.set_preset(p.clone());
        }
        if let Some(path) = &self.tf {
            let file = TransferFunctionFile::read(path)?;
            for note in &file.notes {
                eprintln!("glint: note: {}: {note}", path.display());
            }
            scene.set_transfer_function(file.tf);
            let m = &mut scene.material;
            set(&mut m.ambient, file.material.ambient.map(Some));
            set(&mut m.diffuse, file.material.diffuse.map(Some));
            set(&mut m.specular, file.material.specular.map(Some));
            set(&mut m.shade, file.material.shade.map(Some));
            if file.power.is_some() {
                scene.lobe.n = file.power;
            }
        }
        if let (Some(window), Some(level)) = (self.window, self.window_level) {
            scene.set_window_level(Some(WindowLevel { window, level }))?;
        }
        if let Some(mode) = self.mode {
            scene.set_mode(mode);
        }
        if self.iso.is_some() {
            scene.iso = self.iso;
        }
        let m = &mut scene.material;
        set(&mut m.ambient, self.ambient.map(Some));
        set(&mut m.diffuse, self.diffuse.map(Some));
        set(&mut m.specular, self.specular.map(Some));
        Ok(())
    }

    fn apply_lighting(&self, scene: &mut Scene) -> anyhow::Result<()> {
        if let Some(n) = self.n {
            glint_analysis::check_n(n)?;
        }
        if let Some(v) = self.v {
            glint_analysis::check_v(v)?;
        }
        let lobe = &mut scene.lobe;
        if let Some(path) = &self.hw_config {
            lobe.hw = Some(super::hw::load_config(Some(path))?);
        }
        set(&mut lobe.n, self.n.map(Some));
        set(&mut lobe.v, self.v);
        set(&mut lobe.geometry, self.geometry);
        set(&mut scene.gate, self.gate);
        self.apply_transport(scene);
        if self.no_headlight {
            scene
                .lights
                .retain(|l| (l.azimuth, l.elevation) != (0.0, 0.0));
            let path = scene.lighting.model == LightingModel::Path;
            let area = !self.area_lights.is_empty() || !scene.lighting.area_lights.is_empty();
            let map = scene.lighting.environment_map.is_some();
            if self.lights.is_empty() && scene.lights.is_empty() && !path && !area && !map {
                bail!(
                    "--no-headlight leaves no light: add at least one --light AZ,EL \
                     (path lighting may be lit by its --environment alone, shadows by a map)"
                );
            }
        }
        scene.lights.extend(self.lights.iter().copied());
        (scene.lighting.area_lights).extend(self.area_lights.iter().copied());
        Ok(())
    }
}

impl SceneFlags {
    /// `--lighting` (keeping only the settings the model uses) and its settings.
    fn apply_transport(&self, scene: &mut Scene) {
        let l = &mut scene.lighting;
        if let Some(model) = self.lighting {
            if model != l.model {
                *l = l.for_model(model);
            }
        }
        set(&mut l.spp, self.spp.map(Some));
        set(&mut l.bounces, self.bounces.map(Some));
        set(&mut l.seed, self.seed.map(Some));
        match &self.environment {
            Some(Environment::Uniform(r)) => {
                (l.environment, l.environment_map) = (Some(*r), None);
            }
            Some(Environment::Map(m)) => {
                (l.environment, l.environment_map) = (None, Some(m.clone()));
            }
            None => {}
        }
        set(
            &mut l.environment_rotation,
            self.environment_rotation.map(Some),
        );
        set(
            &mut l.environment_intensity,
            self.environment_intensity.map(Some),
        );
        set(&mut l.anisotropy, self.anisotropy.map(Some));
        set(&mut l.sampler, self.sampler.map(Some));
        set(&mut l.time_budget, self.time_budget.map(Some));
        set(&mut l.denoise, self.denoise.map(Some));
        set(&mut l.surface_weight, self.surface_weight.map(Some));
        if self.occlusion {
            l.occlusion = Some(true);
        }
        if self.show_environment {
            l.show_environment = Some(true);
        }
    }
}

/// `--environment`: a uniform radiance (a number) or a map (a file or built-in name).
#[derive(Clone, Debug, PartialEq)]
pub enum Environment {
    /// The uniform white environment's radiance.
    Uniform(f32),
    /// An environment map's file or built-in name.
    Map(String),
}

impl std::str::FromStr for Environment {
    type Err = std::convert::Infallible;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(s.parse::<f32>()
            .map_or_else(|_| Environment::Map(s.to_string()), Environment::Uniform))
    }
}

/// `*field = value` when the flag was given.
pub fn set<T>(field: &mut T, value: Option<T>) {
    if let Some(v) = value {
        *field = v;
    }
}

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<[u32; 2], String> {
    let bad = || format!("'{s}': expected WxH, e.g. 512x512");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    Ok([
        w.trim().parse().map_err(|_| bad())?,
        h.trim().parse().map_err(|_| bad())?,
    ])
}

/// Parses `LO,HI` (an overlay range).
pub fn parse_range(s: &str) -> Result<[f32; 2], String> {
    let bad = || format!("'{s}': expected LO,HI with LO < HI, e.g. -1,1");
    let (lo, hi) = s.split_once(',').ok_or_else(bad)?;
    let lo: f32 = lo.trim().parse().map_err(|_| bad())?;
    let hi: f32 = hi.trim().parse().map_err(|_| bad())?;
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(bad());
    }
    Ok([lo, hi])
}

/// Six comma-separated finite numbers, or `None`.
fn six(s: &str) -> Option<[f64; 6]> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()?;
    v.try_into().ok()
}

/// Parses `X,Y,Z,NX,NY,NZ` (a point and a non-zero normal, world mm) into a clip
/// plane.
pub fn parse_clip(s: &str) -> Result<ClipPlane, String> {
    let [x, y, z, nx, ny, nz] = six(s).ok_or_else(|| {
        format!("'{s}': expected X,Y,Z,NX,NY,NZ (a point and a normal in mm), e.g. 0,0,0,1,0,0")
    })?;
    let plane = ClipPlane {
        point: [x, y, z],
        normal: [nx, ny, nz],
    };
    Clip {
        planes: vec![plane],
        crop: None,
    }
    .validate()
    .map_err(|e| format!("'{s}': {}", reason(e).trim_start_matches("clip plane 1: ")))?;
    Ok(plane)
}

/// Parses `XMIN,XMAX,YMIN,YMAX,ZMIN,ZMAX` (world mm) into a crop box.
pub fn parse_crop(s: &str) -> Result<CropBox, String> {
    let [x0, x1, y0, y1, z0, z1] = six(s).ok_or_else(|| {
        format!("'{s}': expected XMIN,XMAX,YMIN,YMAX,ZMIN,ZMAX in mm, e.g. -50,0,-80,80,-60,60")
    })?;
    let crop = CropBox {
        min: [x0, y0, z0],
        max: [x1, y1, z1],
    };
    Clip {
        planes: vec![],
        crop: Some(crop),
    }
    .validate()
    .map_err(|e| format!("'{s}': {}", reason(e)))?;
    Ok(crop)
}

/// What a parameter error says, without its kind's prefix (clap adds its own).
fn reason(e: glint_render::RenderError) -> String {
    match e {
        glint_render::RenderError::Parameter(m) => m,
        e => e.to_string(),
    }
}

/// Parses `AZ,EL` or `AZ,EL,INTENSITY` (degrees) into a camera-relative light.
pub fn parse_light(s: &str) -> Result<Light, String> {
    let bad = || format!("'{s}': expected AZ,EL or AZ,EL,INTENSITY in degrees, e.g. 45,30");
    let parts: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    let (azimuth, elevation, intensity) = match parts[..] {
        [a, e] => (a, e, 1.0),
        [a, e, i] => (a, e, i as f32),
        _ => return Err(bad()),
    };
    let light = Light {
        azimuth,
        elevation,
        intensity,
    };
    light.validate().map_err(|e| e.to_string())?;
    Ok(light)
}

/// Parses `--area-light KIND:SIZE:X,Y,Z:RADIANCE[:FRAME]` (see the flag's help).
pub fn parse_area_light(s: &str) -> Result<AreaLightSpec, String> {
    let bad = |why: &str| {
        format!("'{s}': {why}; expected KIND:SIZE:X,Y,Z:RADIANCE[:FRAME], e.g. sphere:20:150,150,250:10 or rect:80x40:0,0,300:5,5,4:volume")
    };
    let nums = |t: &str| -> Result<Vec<f64>, String> {
        (t.split(',').map(|p| p.trim().parse::<f64>()))
            .collect::<Result<_, _>>()
            .map_err(|_| bad(&format!("'{t}' is not a number list")))
    };
    let parts: Vec<&str> = s.split(':').collect();
    let (kind, size, pos, rad, frame) = match parts[..] {
        [k, s, p, r] => (k, s, p, r, "camera"),
        [k, s, p, r, f] => (k, s, p, r, f),
        _ => return Err(bad("four or five fields")),
    };
    let shape = match kind {
        "sphere" => match nums(size)?[..] {
            [radius] => AreaShapeSpec::Sphere { radius },
            _ => return Err(bad("a sphere's SIZE is its radius")),
        },
        "rect" => match (size.split_once('x')).map(|(w, h)| (nums(w), nums(h))) {
            Some((Ok(w), Ok(h))) if w.len() == 1 && h.len() == 1 => {
                AreaShapeSpec::Rect { size: [w[0], h[0]] }
            }
            _ => return Err(bad("a rectangle's SIZE is WxH")),
        },
        _ => return Err(bad("KIND is sphere or rect")),
    };
    let position = match nums(pos)?[..] {
        [x, y, z] => [x, y, z],
        _ => return Err(bad("the position is X,Y,Z")),
    };
    let radiance = match nums(rad)?[..] {
        [l] => [l as f32; 3],
        [r, g, b] => [r as f32, g as f32, b as f32],
        _ => return Err(bad("RADIANCE is one number or R,G,B")),
    };
    let frame = match frame {
        "camera" => LightFrame::Camera,
        "volume" => LightFrame::Volume,
        _ => return Err(bad("FRAME is camera or volume")),
    };
    let light = AreaLightSpec {
        shape,
        frame,
        position,
        radiance,
    };
    light.validate().map_err(|e| format!("'{s}': {e}"))?;
    Ok(light)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        flags: SceneFlags,
    }

    fn scene(argv: &[&str]) -> anyhow::Result<Scene> {
        let mut full = vec!["glint"];
        full.extend_from_slice(argv);
        Cli::try_parse_from(full)?.flags.scene()
    }

    #[test]
    fn no_flags_give_the_default_scene() {
        let s = scene(&[]).unwrap();
        assert_eq!(s.to_json().unwrap(), Scene::default().to_json().unwrap());
    }

    #[test]
    fn flags_set_their_fields() {
        let s = scene(&[
            "--phantom",
            "shepp-logan",
            "--view",
            "left",
            "--azimuth",
            "-30",
            "--n",
            "40",
            "--v",
            "3",
            "--light",
            "45,-20,0.5",
            "--size",
            "64x32",
            "--step",
            "0.25",
            "--specular",
            "0.7",
        ])
        .unwrap();
        assert!(matches!(
            s.input,
            Input::Phantom {
                name: Phantom::SheppLogan,
                size: Phantom::DEFAULT_SIZE
            }
        ));
        assert_eq!(s.camera.view, View::Left);
        assert_eq!(s.camera.azimuth, -30.0);
        assert_eq!((s.lobe.n, s.lobe.v), (Some(40.0), 3));
        assert_eq!(s.size, [64, 32]);
        assert_eq!(s.step, 0.25);
        assert_eq!(s.material.specular, Some(0.7));
        let extra = s.lights.last().unwrap();
        assert_eq!(
            (extra.azimuth, extra.elevation, extra.intensity),
            (45.0, -20.0, 0.5)
        );
    }

    #[test]
    fn bad_values_are_refused_before_any_work() {
        for argv in [
            &["--preset", "no-such-preset"][..],
            &["--n", "-3"],
            &["--v", "99"],
            &["--no-headlight"],
            &["--size", "64"],
            &["--light", "1,2,3,4"],
        ] {
            assert!(scene(argv).is_err(), "{argv:?} was accepted");
        }
    }

    #[test]
    fn lighting_flags_set_the_model_and_its_settings() {
        let s = scene(&[
            "--lighting",
            "path",
            "--spp",
            "16",
            "--bounces",
            "3",
            "--seed",
            "7",
            "--environment",
            "0.3",
            "--anisotropy",
            "-0.2",
            "--sampler",
            "independent",
            "--time-budget",
            "250",
            "--show-environment",
            "--surface-weight",
            "0",
        ])
        .unwrap();
        let l = &s.lighting;
        assert_eq!(l.model, LightingModel::Path);
        assert_eq!((l.spp, l.bounces, l.seed), (Some(16), Some(3), Some(7)));
        assert_eq!((l.environment, l.anisotropy), (Some(0.3), Some(-0.2)));
        assert_eq!(l.sampler, Some(Sampler::Independent));
        assert_eq!(l.time_budget, Some(250.0));
        assert_eq!(l.show_environment, Some(true));
        assert_eq!(l.surface_weight, Some(0.0));
        // Switching a path scene to shadows keeps what shadows uses.
        let mut next = s.clone();
        let flags = SceneFlags {
            lighting: Some(LightingModel::Shadows),
            occlusion: true,
            ..SceneFlags::default()
        };
        flags.apply(&mut next).unwrap();
        let l = &next.lighting;
        assert_eq!(
            (l.model, l.spp, l.seed),
            (LightingModel::Shadows, None, None)
        );
        assert_eq!((l.anisotropy, l.occlusion), (Some(-0.2), Some(true)));
        assert!(scene(&["--lighting", "global"]).is_err());
    }

    #[test]
    fn a_mode_other_than_iso_drops_the_iso_value() {
        let mut s = Scene {
            iso: Some(3.0),
            ..Scene::default()
        };
        let flags = SceneFlags {
            mode: Some(RenderMode::Mip),
            ..SceneFlags::default()
        };
        flags.apply(&mut s).unwrap();
        assert_eq!((s.mode, s.iso), (RenderMode::Mip, None));
    }

    #[test]
    fn clip_and_crop_flags_set_the_scenes_planes_and_box() {
        let s = scene(&[
            "--clip",
            "1,-2,3,0,0,-1",
            "--clip",
            "0,0,0,2,0,0",
            "--crop",
            "-50,0,-80,80,-60,60.5",
        ])
        .unwrap();
        assert_eq!(s.clip.len(), 2);
        assert_eq!(
            (s.clip[0].point, s.clip[0].normal),
            ([1.0, -2.0, 3.0], [0.0, 0.0, -1.0])
        );
        let b = s.crop.unwrap();
        assert_eq!((b.min, b.max), ([-50.0, -80.0, -60.0], [0.0, 80.0, 60.5]));
        assert!(!s.clip_caps, "caps are off by default");
        assert!(
            scene(&["--clip", "0,0,0,1,0,0", "--clip-caps"])
                .unwrap()
                .clip_caps
        );
        for (argv, says) in [
            (["--clip", "0,0,0,0,0,0"], "the normal is zero"),
            (["--clip", "0,0,0,1,0"], "expected X,Y,Z,NX,NY,NZ"),
            (["--clip", "0,0,nan,1,0,0"], "expected X,Y,Z,NX,NY,NZ"),
            (
                ["--crop", "0,-1,0,1,0,1"],
                "x from 0 to -1 is empty or inverted",
            ),
            (["--crop", "0,1,0,1,0"], "expected XMIN,XMAX"),
        ] {
            let e = scene(&argv).unwrap_err().to_string();
            assert!(e.contains(says), "{argv:?}: {e}");
        }
    }

    #[test]
    fn size_and_light_parsing() {
        assert_eq!(parse_size("640x480").unwrap(), [640, 480]);
        assert_eq!(parse_size("64X48").unwrap(), [64, 48]);
        assert!(parse_size("64").is_err());
        let l = parse_light("-30,15").unwrap();
        assert_eq!((l.azimuth, l.elevation, l.intensity), (-30.0, 15.0, 1.0));
        assert_eq!(parse_light("10,20,0.5").unwrap().intensity, 0.5);
        assert!(parse_light("1,2,3,4").is_err());
    }

    #[test]
    fn area_light_parsing() {
        let l = parse_area_light("sphere:20:150,-150,250:10").unwrap();
        assert_eq!(l.shape, AreaShapeSpec::Sphere { radius: 20.0 });
        assert_eq!(
            (l.frame, l.position, l.radiance),
            (LightFrame::Camera, [150.0, -150.0, 250.0], [10.0; 3])
        );
        let r = parse_area_light("rect:80x40:0,-300,100:5,4,3:volume").unwrap();
        assert_eq!(r.shape, AreaShapeSpec::Rect { size: [80.0, 40.0] });
        assert_eq!((r.frame, r.radiance), (LightFrame::Volume, [5.0, 4.0, 3.0]));
        // Zero, negative or NaN sizes, bad fields: one line each.
        for bad in [
            "sphere:0:0,0,300:1",
            "sphere:-5:0,0,300:1",
            "sphere:nan:0,0,300:1",
            "rect:0x40:0,0,300:1",
            "rect:80:0,0,300:1",
            "sphere:20:0,0:1",
            "sphere:20:0,0,300:-1",
            "sphere:20:0,0,300:1:world",
            "cone:20:0,0,300:1",
            "rect:10x10:0,0,0:1",
        ] {
            let e = parse_area_light(bad).unwrap_err();
            assert!(!e.contains('\n') && e.contains(bad), "{bad}: {e}");
        }
        let s = scene(&["--area-light", "sphere:20:150,150,250:10", "--no-headlight"]).unwrap();
        assert_eq!(s.lighting.area_lights.len(), 1);
        assert!(s.lights.is_empty());
    }
}

/// `--level`: a pyramid level by number, or `auto`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LevelArg {
    /// Level n (0 the finest).
    Index(usize),
    /// The coarsest level with at least one voxel per pixel.
    Auto,
}

/// Parses `--level`: a number or `auto`.
fn parse_level(s: &str) -> Result<LevelArg, String> {
    match s.trim() {
        "auto" => Ok(LevelArg::Auto),
        n => n
            .parse()
            .map(LevelArg::Index)
            .map_err(|_| format!("'{s}' is not a level (0, 1, ... or auto)")),
    }
}
