//! One client's state: its scene (camera, lobe, ...), split mode, and the renderer that
//! keeps its classification; turning messages into state changes and states into
//! encoded frames.

use std::time::{Duration, Instant};

use glint_render::{
    luminance_f32, srgb_to_linear, Denoise, Depth, Image, Lighting, LightingModel, RenderError,
    RenderStats, Renderer, Scene, DEFAULT_SPP, MAX_IMAGE_SIDE,
};
use serde_json::{Map, Value};

use crate::drag::{half_size, DragCost, DragFrame};
use crate::labels::{merge_labels, LabelList};
use crate::protocol::{Format, FrameHeader, Purpose, Split};
use crate::schedule::Schedule;
use crate::ViewError;

/// Largest image side a client may ask for (the viewer renders every frame at this
/// size at most; `glint render` takes up to [`MAX_IMAGE_SIDE`]).
pub const MAX_VIEW_SIDE: u32 = 2048;

/// Scene fields a client may not change: the server renders only the volume (and
/// meshes and label map) it was started with; a client naming another file would have
/// the server read it. Of the label map, only [`crate::labels::LABEL_FIELDS`] change.
const FIXED_FIELDS: [&str; 4] = ["input", "meshes", "version", "derived"];

/// JPEG quality of frames sent while the user drags (small and quick).
const INTERACTIVE_QUALITY: u8 = 70;

/// JPEG quality of the full-resolution frame when the input stops.
const FULL_QUALITY: u8 = 92;

/// Difference in luminance (linear, 0..1) shown at full heat in the diff view: 5%.
const DIFF_FULL_SCALE: f32 = 0.05;

/// `scene` with the fields of `patch` applied ([`Scene::patch`]: the rule every front
/// end shares), checked against `renderer`'s volume; the fields naming the data are
/// the server's and cannot be changed. A `labels` patch is merged into the scene's
/// label map field by field ([`crate::labels::LABEL_FIELDS`]: which labels are shown)
/// and checked against `labels`, the labels present.
pub fn apply_patch(
    renderer: &Renderer,
    scene: &Scene,
    patch: &Map<String, Value>,
    labels: Option<&LabelList>,
) -> Result<Scene, ViewError> {
    if let Some(key) = patch.keys().find(|k| FIXED_FIELDS.contains(&k.as_str())) {
        return Err(ViewError::Message(format!(
            "the viewer does not change '{key}'"
        )));
    }
    let next = match patch.get("labels") {
        Some(l) => {
            let mut patch = patch.clone();
            patch.insert("labels".into(), merge_labels(scene.labels.as_ref(), l)?);
            scene.patch(&patch)?
        }
        None => scene.patch(patch)?,
    };
    let mut check = next.clone();
    if let (Some(list), Some(spec)) = (labels, &next.labels) {
        if next.labels != scene.labels {
            list.check(spec)?;
            // Checked without building the new label meshes, which the next frame
            // does (once): the rest of the scene against the meshes built last.
            check.labels = scene.labels.clone();
        }
        check = list.visible(&check);
    }
    if next.size.iter().any(|&s| s > MAX_VIEW_SIDE) {
        return Err(ViewError::Message(format!(
            "image size {}x{}: the viewer renders at most {MAX_VIEW_SIDE} per side",
            next.size[0], next.size[1]
        )));
    }
    // A clone shares the volume and meshes (resolving may read meshes it lacks).
    let resolved = renderer.clone().resolve(&check)?.scene;
    check_cost(renderer, &resolved)?;
    Ok(next)
}

/// Most ray samples a viewer frame may take: its pixels times the samples of a ray
/// along the volume's world diagonal at the scene's step (the most one ray can take;
/// empty space skipped and early termination make the real count smaller). 2^34: on
/// the head CT of `scripts/fetch-samples` (256x256x108 voxels), 512x512 frames at
/// any step (down to the floor, 0.01) and 2048x2048 frames from step 0.1 render;
/// issue 41's request (2048x2048 at step 0.01: 1.7e11) is refused.
pub const MAX_FRAME_RAY_SAMPLES: f64 = (1u64 << 34) as f64;

/// The ray samples a frame of the resolved `scene` on `renderer`'s volume may take
/// ([`MAX_FRAME_RAY_SAMPLES`]); `None` for a scene without a volume.
pub fn frame_ray_samples(renderer: &Renderer, scene: &Scene) -> Option<f64> {
    let field = renderer.field()?;
    let d = field.dims().map(|n| n.saturating_sub(1) as f64);
    // The longest diagonal of the (possibly sheared) grid box.
    let diagonal = (0..4)
        .map(|n| {
            let a = [0, 1, 2].map(|i| if n & (1 << i) != 0 { d[i] } else { 0.0 });
            let b = [0, 1, 2].map(|i| d[i] - a[i]);
            let (p, q) = (field.index_to_world(a), field.index_to_world(b));
            (0..3).map(|i| (p[i] - q[i]).powi(2)).sum::<f64>().sqrt()
        })
        .fold(0.0f64, f64::max);
    let dt = scene.step * field.min_spacing();
    let pixels = f64::from(scene.size[0]) * f64::from(scene.size[1]);
    Some(pixels * (diagonal / dt).ceil().max(1.0))
}

/// Refuses a frame of the resolved `scene` that could take more than
/// [`MAX_FRAME_RAY_SAMPLES`], saying how to bring it within.
fn check_cost(renderer: &Renderer, scene: &Scene) -> Result<(), ViewError> {
    match frame_ray_samples(renderer, scene) {
        Some(n) if n > MAX_FRAME_RAY_SAMPLES => Err(ViewError::Message(format!(
            "a {}x{} frame at step {} takes up to {n:.2e} ray samples: the viewer renders \
             at most {MAX_FRAME_RAY_SAMPLES:.2e} per frame (raise the step or lower the size)",
            scene.size[0], scene.size[1], scene.step
        ))),
        _ => Ok(()),
    }
}

/// A rendered frame, ready to send.
pub struct Frame {
    /// Header and image bytes.
    pub message: Vec<u8>,
    /// The resolved scene of the (main) render.
    pub scene: Scene,
    /// The last update the frame reflects.
    pub seq: u32,
    /// Path-traced samples per pixel in the image (0 for the other lighting models).
    pub samples: u32,
}

/// A rendered frame before encoding ([`render_image`]).
pub struct FrameImage {
    /// The image (with `split`, both halves or the difference).
    pub image: Image,
    /// The resolved scene of the (main) render.
    pub scene: Scene,
    /// Path-traced samples per pixel in the image (0 for the other lighting models).
    pub samples: u32,
    /// Milliseconds spent rendering.
    pub render_ms: f32,
}

/// Renders `scene` for `purpose` (interactive frames at half size, a `path` scene's
/// path-traced and denoised at the smallest drag size: [`crate::drag`]; a `path`
/// scene's full frames to the scene's sample count, continuing the samples `renderer`
/// holds for it) with `split`, encoded with its header.
pub fn render_frame(
    renderer: &mut Renderer,
    scene: &Scene,
    split: Split,
    purpose: Purpose,
    seq: u32,
) -> Result<Frame, RenderError> {
    render_frame_counted(
        renderer,
        scene,
        split,
        purpose,
        seq,
        &|_| {},
        &mut DragCost::default(),
    )
}

/// [`render_frame`] calling `progress` (from worker threads) with the pixels each
/// tile or row of its renders finished: the work a frame did, stopped or not; a
/// `path` scene's drag frame sized by the client's `drag` estimate, which the frame's
/// time updates ([`DragCost`]).
pub fn render_frame_counted(
    renderer: &mut Renderer,
    scene: &Scene,
    split: Split,
    purpose: Purpose,
    seq: u32,
    progress: &(dyn Fn(u64) + Sync),
    drag: &mut DragCost,
) -> Result<Frame, RenderError> {
    let FrameImage {
        image,
        scene,
        samples,
        render_ms,
    } = render_image_counted(renderer, scene, split, purpose, progress, drag)?;
    let (format, bytes) = match purpose {
        Purpose::Save => (
            Format::Png,
            image
                .encode_png(Depth::Eight)
                .map_err(RenderError::Encode)?,
        ),
        Purpose::Interactive => (Format::Jpeg, jpeg(&image, INTERACTIVE_QUALITY)?),
        Purpose::Full => (Format::Jpeg, jpeg(&image, FULL_QUALITY)?),
    };
    let header = FrameHeader {
        seq,
        width: image.width,
        height: image.height,
        render_ms,
        format,
        purpose,
        samples: u16::try_from(samples).unwrap_or(u16::MAX),
    };
    Ok(Frame {
        message: header.encode(&bytes),
        scene,
        seq,
        samples,
    })
}

/// [`render_frame`]'s image, not encoded: the frame `purpose` asks for of `scene`
/// with `split`.
pub fn render_image(
    renderer: &mut Renderer,
    scene: &Scene,
    split: Split,
    purpose: Purpose,
) -> Result<FrameImage, RenderError> {
    render_image_counted(
        renderer,
        scene,
        split,
        purpose,
        &|_| {},
        &mut DragCost::default(),
    )
}

/// The lighting of a `path` scene's drag frame: one sample per pixel (no time
/// budget: the image is the same for the same scene and size) denoised by the
/// à-trous filter, whatever the scene's own denoiser (Intel Open Image Denoise
/// takes hundreds of milliseconds; no filter at one sample shows the noise).
pub fn drag_lighting(lighting: &Lighting) -> Lighting {
    Lighting {
        spp: Some(1),
        time_budget: None,
        denoise: Some(Denoise::Atrous),
        ..lighting.clone()
    }
}

/// [`render_image`] calling `progress` as [`render_frame_counted`] does, a `path`
/// scene's drag frame sized by `drag`.
fn render_image_counted(
    renderer: &mut Renderer,
    scene: &Scene,
    split: Split,
    purpose: Purpose,
    progress: &(dyn Fn(u64) + Sync),
    drag: &mut DragCost,
) -> Result<FrameImage, RenderError> {
    let mut s = scene.clone();
    // A path drag frame's size (`Some(Some(size))`) or a local one (`Some(None)`),
    // measured when it is done.
    let mut measure = None;
    if purpose == Purpose::Interactive {
        if s.lighting.model == LightingModel::Path {
            match drag.choose(s.size) {
                DragFrame::Path(size) => {
                    s.size = size;
                    s.lighting = drag_lighting(&s.lighting);
                    measure = Some(Some(size));
                }
                DragFrame::Local(size) => {
                    // Even the smallest path frame would be too slow (one path
                    // sample of a 512x512 MNI152 frame at half size takes about
                    // 0.4 s here, docs/performance.md): the cheap model, as before.
                    s.size = size;
                    s.lighting = s.lighting.for_model(LightingModel::Local);
                    measure = Some(None);
                }
            }
        } else {
            s.size = half_size(s.size);
        }
    }
    let start = Instant::now();
    let main = renderer.render(&s, progress)?;
    let image = match split {
        Split::Off => main.image,
        Split::Side | Split::Diff => {
            let reference = renderer
                .render(&main.scene.with_exact_lobe(), progress)?
                .image;
            if split == Split::Side {
                side_by_side(&reference, &main.image)
            } else {
                difference(&reference, &main.image)
            }
        }
    };
    let render_ms = start.elapsed().as_secs_f32() * 1e3;
    match measure {
        Some(Some(size)) => drag.measured(size, f64::from(render_ms)),
        Some(None) => drag.measured_local(f64::from(render_ms)),
        None => {}
    }
    let samples = if main.scene.lighting.model == LightingModel::Path {
        renderer.path_samples()
    } else {
        0
    };
    Ok(FrameImage {
        image,
        scene: main.scene,
        samples,
        render_ms,
    })
}

/// One viewer without a transport: a renderer, the live scene, the labels present
/// and the [`Schedule`] of frames owed, for a front end that renders on its own
/// thread (the notebook's `glint.Viewer`). It follows `glint view`'s rules: patches
/// through [`apply_patch`], reduced frames while dragging, a full frame once the
/// input settles, a `path` scene refined while it holds still.
pub struct Session {
    renderer: Renderer,
    scene: Scene,
    labels: Option<LabelList>,
    schedule: Schedule,
    settle: Duration,
    /// What this session's `path` drag frames cost ([`crate::drag`]).
    drag: DragCost,
}

impl Session {
    /// A session of `scene` on `renderer` (its volume, meshes and label map read):
    /// the scene is resolved and its label map's labels listed; a full frame is owed.
    /// `settle`: the quiet time after a drag's last input before the full frame
    /// ([`crate::ViewerConfig::settle`]).
    pub fn new(
        mut renderer: Renderer,
        scene: &Scene,
        settle: Duration,
    ) -> Result<Session, RenderError> {
        let scene = renderer.resolve(scene)?.scene;
        // An RT structure set is rasterised onto the scene's image (its path).
        let image = match &scene.input {
            glint_render::Input::Path(p) => Some(p.as_path()),
            _ => None,
        };
        let labels = scene
            .labels
            .as_ref()
            .map(|l| LabelList::read(l, image))
            .transpose()?;
        Ok(Session {
            renderer,
            scene,
            labels,
            schedule: Schedule::default(),
            settle,
            drag: DragCost::default(),
        })
    }

    /// The live scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The labels of the scene's label map (`None` without one).
    pub fn labels(&self) -> Option<&LabelList> {
        self.labels.as_ref()
    }

    /// Applies `patch` ([`apply_patch`]) at `now`: a drag's reduced frame when
    /// `interactive`, else a full frame. A refused patch changes nothing.
    pub fn update(
        &mut self,
        patch: &Map<String, Value>,
        interactive: bool,
        now: Instant,
    ) -> Result<(), ViewError> {
        self.scene = apply_patch(&self.renderer, &self.scene, patch, self.labels.as_ref())?;
        self.schedule.input(interactive, now, self.settle);
        Ok(())
    }

    /// When a drag's full frame is due (`None`: no drag under way).
    pub fn settle_at(&self) -> Option<Instant> {
        self.schedule.settle_at()
    }

    /// The frame owed at `now`, if any, taken off the list.
    pub fn next(&mut self, now: Instant) -> Option<Purpose> {
        self.schedule.settled(now);
        self.schedule.take()
    }

    /// Whether a frame is owed now (a `path` scene refining, a full frame after a
    /// change); a drag's full frame that is not due yet is not ([`Session::settle_at`]).
    pub fn owes(&self) -> bool {
        self.schedule.owes()
    }

    /// A full-resolution frame is wanted ([`Purpose::Save`]), next.
    pub fn save(&mut self) {
        self.schedule.save();
    }

    /// The sample count the live scene refines to (`None`: not a `path` scene).
    fn progressive(&self) -> Option<u32> {
        let lighting = &self.scene.lighting;
        (lighting.model == LightingModel::Path).then(|| lighting.spp.unwrap_or(DEFAULT_SPP))
    }

    /// Renders the live scene for `purpose` (hidden labels hidden; a full frame of a
    /// `path` scene to the next sample count) and notes it in the schedule: a `path`
    /// scene short of its samples owes the next refinement.
    pub fn render(&mut self, purpose: Purpose) -> Result<FrameImage, RenderError> {
        let mut s = match &self.labels {
            Some(list) => list.visible(&self.scene),
            None => self.scene.clone(),
        };
        let goal = self.progressive();
        if purpose == Purpose::Full {
            if let Some(spp) = self.schedule.samples_for(goal) {
                s.lighting.spp = Some(spp);
            }
        }
        let done = render_image_counted(
            &mut self.renderer,
            &s,
            Split::Off,
            purpose,
            &|_| {},
            &mut self.drag,
        );
        match done {
            Ok(frame) => {
                if purpose == Purpose::Full {
                    self.schedule.full_done(frame.samples, goal);
                }
                Ok(frame)
            }
            Err(RenderError::Cancelled) => {
                self.schedule.cancelled();
                Err(RenderError::Cancelled)
            }
            Err(e) => Err(e),
        }
    }
}

fn jpeg(image: &Image, quality: u8) -> Result<Vec<u8>, RenderError> {
    let rgb = image.encode_srgb(Depth::Eight);
    let mut out = Vec::new();
    let too_big = || {
        RenderError::Parameter(format!(
            "{}x{} is too large for JPEG",
            image.width, image.height
        ))
    };
    let (w, h) = (
        u16::try_from(image.width).map_err(|_| too_big())?,
        u16::try_from(image.height).map_err(|_| too_big())?,
    );
    jpeg_encoder::Encoder::new(&mut out, quality)
        .encode(&rgb, w, h, jpeg_encoder::ColorType::Rgb)
        .map_err(|e| RenderError::Parameter(format!("JPEG encoding failed: {e}")))?;
    Ok(out)
}

/// `left` and `right` (same size) side by side.
fn side_by_side(left: &Image, right: &Image) -> Image {
    let (w, h) = (left.width as usize, left.height as usize);
    let mut rgb = Vec::with_capacity(2 * w * h);
    let mut alpha = Vec::with_capacity(2 * w * h);
    for y in 0..h {
        for img in [left, right] {
            rgb.extend_from_slice(&img.rgb[y * w..(y + 1) * w]);
            alpha.extend_from_slice(&img.alpha[y * w..(y + 1) * w]);
        }
    }
    debug_assert!(2 * left.width <= 2 * MAX_IMAGE_SIDE);
    Image {
        width: 2 * left.width,
        height: left.height,
        rgb,
        alpha,
        stats: RenderStats::default(),
    }
}

/// The absolute difference of CIE luminance (Rec. 709 weights on linear RGB) as a
/// black-red-yellow-white heat map, full heat at [`DIFF_FULL_SCALE`].
fn difference(a: &Image, b: &Image) -> Image {
    let lum = |c: &[f32; 3]| luminance_f32(*c);
    let rgb = a
        .rgb
        .iter()
        .zip(&b.rgb)
        .map(|(p, q)| {
            let t = ((lum(p) - lum(q)).abs() / DIFF_FULL_SCALE).min(1.0) * 3.0;
            // sRGB ramps: red, then green, then blue.
            [t, t - 1.0, t - 2.0].map(|x| srgb_to_linear(x.clamp(0.0, 1.0) as f64) as f32)
        })
        .collect();
    Image {
        width: a.width,
        height: a.height,
        rgb,
        alpha: vec![1.0; a.alpha.len()],
        stats: RenderStats::default(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::schedule::next_samples;
    use glint_lobe::LobeKind;
    use glint_render::{Phantom, ReadOptions};

    fn scene() -> Scene {
        Scene::phantom(Phantom::SheppLogan, 24, [24, 24])
    }

    #[test]
    fn patches_merge_nested_fields_and_refuse_bad_ones() {
        let r = Renderer::open(&scene(), &ReadOptions::default()).unwrap();
        let patch = |j: &str| serde_json::from_str::<Map<String, Value>>(j).unwrap();
        let s = apply_patch(&r, &scene(), &patch(r#"{"camera": {"azimuth": 30}}"#), None).unwrap();
        assert_eq!(s.camera.azimuth, 30.0);
        assert_eq!(s.camera.view, scene().camera.view);
        for (bad, needle) in [
            (r#"{"input": {"path": "/etc/passwd"}}"#, "input"),
            (r#"{"labels": {"path": "/etc/passwd"}}"#, "labels"),
            (r#"{"camera": {"zoom": -3}}"#, "zoom"),
            (r#"{"camera": {"tilt": 3}}"#, "tilt"),
            (r#"{"step": "fast"}"#, "step"),
            (r#"{"size": [99999, 2]}"#, "99999"),
            (r#"{"lobe": {"n": 1e9}}"#, "1000000000"),
        ] {
            let err = apply_patch(&r, &scene(), &patch(bad), None)
                .unwrap_err()
                .to_string();
            assert!(err.contains(needle), "{bad}: '{err}'");
        }
    }

    #[test]
    fn a_patch_can_make_the_lobe_the_hardware_unit() {
        let mut r = Renderer::open(&scene(), &ReadOptions::default()).unwrap();
        let patch = |j: &str| serde_json::from_str::<Map<String, Value>>(j).unwrap();
        let hw = r#"{"lobe": {"kind": "hw", "n": 30, "hw": {"out_bits": 10}}}"#;
        let s = apply_patch(&r, &scene(), &patch(hw), None).unwrap();
        assert_eq!(s.lobe.kind, glint_render::SceneLobe::Hw);
        assert_eq!(s.lobe.hw.as_ref().map(|c| c.out_bits), Some(10));
        // The frame's scene names the whole unit, and the image is not float K_4's.
        let f = render_frame(&mut r, &s, Split::Off, Purpose::Full, 1).unwrap();
        assert_eq!(
            f.scene.lobe.hw.as_ref().map(|c| c.square_frac.len()),
            Some(4)
        );
        let k = Scene {
            lobe: glint_render::LobeSpec {
                kind: LobeKind::EnergyFit.into(),
                ..s.lobe.clone()
            },
            ..s.clone()
        };
        assert_ne!(
            r.render(&s, &|_| {}).unwrap().image.rgb,
            r.render(&k, &|_| {}).unwrap().image.rgb
        );
        // The scene's v (4) contradicts a v = 3 unit: refused, saying why.
        let v3 = r#"{"lobe": {"kind": "hw", "hw": {"v": 3, "square_frac": [14, 14, 12]}}}"#;
        let err = apply_patch(&r, &scene(), &patch(v3), None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("contradicts"), "{err}");
    }

    #[test]
    fn split_frames_have_the_right_shape() {
        let mut r = Renderer::open(&scene(), &ReadOptions::default()).unwrap();
        for (split, width) in [(Split::Off, 24), (Split::Side, 48), (Split::Diff, 24)] {
            let f = render_frame(&mut r, &scene(), split, Purpose::Full, 5).unwrap();
            let (h, jpeg) = FrameHeader::decode(&f.message).unwrap();
            assert_eq!((h.width, h.height, h.seq), (width, 24, 5));
            assert_eq!(&jpeg[..2], &[0xFF, 0xD8], "JPEG SOI marker");
        }
        let f = render_frame(&mut r, &scene(), Split::Off, Purpose::Interactive, 1).unwrap();
        assert_eq!(FrameHeader::decode(&f.message).unwrap().0.width, 12);
        let f = render_frame(&mut r, &scene(), Split::Off, Purpose::Save, 1).unwrap();
        assert_eq!(&FrameHeader::decode(&f.message).unwrap().1[1..4], b"PNG");
    }

    #[test]
    fn path_frames_continue_their_samples_and_interaction_restarts_them() {
        let mut s = scene();
        s.lighting = glint_render::Lighting {
            model: LightingModel::Path,
            spp: Some(2),
            bounces: Some(3),
            ..Default::default()
        };
        let mut r = Renderer::open(&s, &ReadOptions::default()).unwrap();
        let f = render_frame(&mut r, &s, Split::Off, Purpose::Full, 1).unwrap();
        assert_eq!(
            (
                f.samples,
                FrameHeader::decode(&f.message).unwrap().0.samples
            ),
            (2, 2)
        );
        s.lighting.spp = Some(5);
        let f = render_frame(&mut r, &s, Split::Off, Purpose::Full, 1).unwrap();
        assert_eq!(f.samples, 5, "the same scene with more samples continues");
        let f = render_frame(&mut r, &s, Split::Off, Purpose::Interactive, 2).unwrap();
        assert_eq!(f.samples, 1, "interactive path frames take one sample");
        // The drag frame's samples replaced the full frame's: the next full frame of
        // the same scene starts again (a drag moves the camera, which would anyway).
        let f = render_frame(&mut r, &s, Split::Off, Purpose::Full, 2).unwrap();
        assert_eq!(f.samples, 5);
        let f = render_frame(&mut r, &scene(), Split::Off, Purpose::Full, 3).unwrap();
        assert_eq!(f.samples, 0, "local frames are not path traced");
        let steps: Vec<u32> =
            std::iter::successors(Some(0), |&d| (d < 40).then(|| next_samples(d, 40))).collect();
        assert_eq!(steps, [0, 1, 2, 4, 8, 16, 24, 32, 40]);
        assert_eq!(next_samples(0, 0), 1);
    }

    #[test]
    fn a_session_follows_the_schedule_and_refuses_bad_patches() {
        let mut s = scene();
        s.lighting = glint_render::Lighting {
            model: LightingModel::Path,
            spp: Some(4),
            ..Default::default()
        };
        let r = Renderer::open(&s, &ReadOptions::default()).unwrap();
        let settle = Duration::from_millis(150);
        let mut session = Session::new(r, &s, settle).unwrap();
        let t0 = Instant::now();
        let mut samples = Vec::new();
        while let Some(p) = session.next(t0) {
            let f = session.render(p).unwrap();
            samples.push((p, f.samples, f.image.width));
        }
        let full = |n| (Purpose::Full, n, 24);
        assert_eq!(samples, [full(1), full(2), full(4)]);
        let patch = |j: &str| serde_json::from_str::<Map<String, Value>>(j).unwrap();
        session
            .update(&patch(r#"{"camera": {"azimuth": 40}}"#), true, t0)
            .unwrap();
        assert_eq!(session.scene().camera.azimuth, 40.0);
        assert_eq!(session.next(t0), Some(Purpose::Interactive));
        let f = session.render(Purpose::Interactive).unwrap();
        assert_eq!((f.samples, f.image.width), (1, 12));
        assert!(session.next(t0).is_none() && session.settle_at() == Some(t0 + settle));
        assert_eq!(session.next(t0 + settle), Some(Purpose::Full));
        let before = session.scene().clone();
        let err = session
            .update(&patch(r#"{"colour": 1}"#), false, t0)
            .unwrap_err()
            .to_string();
        assert!(err.contains("colour"), "{err}");
        assert!(session.scene() == &before && !session.owes());
    }

    /// Issue 41: the ray caster's frames (`local`, `shadows`, MIP) stop at the next
    /// tile once the cancel flag is set (here when the first tile is done): most
    /// pixels are never rendered, and the frame is an error, not a partial image.
    #[test]
    fn a_cancelled_ray_cast_frame_stops_early() {
        use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
        use std::sync::Arc;
        let mut s = Scene::phantom(Phantom::SheppLogan, 24, [128, 128]);
        let mut r = Renderer::open(&s, &ReadOptions::default()).unwrap();
        let flag = Arc::new(AtomicBool::new(false));
        r.set_cancel(Some(flag.clone()));
        let total = 128 * 128;
        for model in [LightingModel::Local, LightingModel::Shadows] {
            s.lighting = s.lighting.for_model(model);
            let pixels = AtomicU64::new(0);
            let stop = |n| {
                pixels.fetch_add(n, Ordering::SeqCst);
                flag.store(true, Ordering::SeqCst);
            };
            flag.store(false, Ordering::SeqCst);
            let f = render_frame_counted(
                &mut r,
                &s,
                Split::Off,
                Purpose::Full,
                1,
                &stop,
                &mut DragCost::default(),
            );
            assert!(matches!(f, Err(RenderError::Cancelled)), "{model:?}");
            let done = pixels.load(Ordering::SeqCst);
            // The tiles begun before the flag was seen finish: a few of 64.
            assert!(done < total / 4, "{model:?}: {done} of {total} pixels");
            // The flag cleared, the same renderer renders the whole frame.
            flag.store(false, Ordering::SeqCst);
            let whole = AtomicU64::new(0);
            let count = |n| {
                whole.fetch_add(n, Ordering::SeqCst);
            };
            render_frame_counted(
                &mut r,
                &s,
                Split::Off,
                Purpose::Full,
                2,
                &count,
                &mut DragCost::default(),
            )
            .unwrap();
            assert_eq!(whole.load(Ordering::SeqCst), total, "{model:?}");
        }
    }

    /// Issue 41: the issue's request (2048x2048 at step 0.01, here of a 32^3
    /// phantom) is over the bound of ray samples: refused with one line saying what to
    /// change, the scene unchanged; one within the bound is taken.
    #[test]
    fn a_frame_over_the_ray_sample_bound_is_refused() {
        let small = Scene::phantom(Phantom::SheppLogan, 32, [24, 24]);
        let r = Renderer::open(&small, &ReadOptions::default()).unwrap();
        let patch = |j: &str| serde_json::from_str::<Map<String, Value>>(j).unwrap();
        let big = patch(r#"{"size": [2048, 2048], "step": 0.01}"#);
        let err = apply_patch(&r, &small, &big, None).unwrap_err().to_string();
        assert!(
            err.contains("a 2048x2048 frame at step 0.01 takes up to")
                && err.contains("raise the step or lower the size")
                && !err.contains('\n'),
            "{err}"
        );
        let fine = patch(r#"{"size": [2048, 2048], "step": 0.5}"#);
        let s = apply_patch(&r, &small, &fine, None).unwrap();
        assert!(frame_ray_samples(&r, &s).unwrap() <= MAX_FRAME_RAY_SAMPLES);
        // 2048^2 pixels, the phantom's diagonal (31 sqrt(3) voxels) over 0.5.
        let n = frame_ray_samples(&r, &s).unwrap() / (2048.0 * 2048.0);
        assert!((100.0..115.0).contains(&n), "{n} samples per ray");
    }

    fn path_scene(size: u32) -> Scene {
        let mut s = Scene::phantom(Phantom::SheppLogan, 32, [size, size]);
        s.lighting = glint_render::Lighting {
            model: LightingModel::Path,
            spp: Some(16),
            ..Default::default()
        };
        s
    }

    /// Issue 41, item 3: while the budget allows, a `path` scene's drag frame is
    /// path-traced at one sample and denoised by the à-trous filter, not `local`:
    /// the same image as that render, bit for bit, again for the same scene and
    /// size, and not the `local` image of that size.
    #[test]
    fn a_path_scene_drags_in_denoised_path_frames_while_the_budget_allows() {
        let s = path_scene(64);
        let mut session = Session::new(
            Renderer::open(&s, &ReadOptions::default()).unwrap(),
            &s,
            Duration::from_millis(150),
        )
        .unwrap();
        let patch = serde_json::from_str(r#"{"camera": {"azimuth": 25}}"#).unwrap();
        session.update(&patch, true, Instant::now()).unwrap();
        let drag = session.render(Purpose::Interactive).unwrap();
        // Half size (32 px) is under the smallest drag size: half size, path.
        assert_eq!(
            (drag.samples, drag.image.width, drag.image.height),
            (1, 32, 32)
        );
        assert_eq!(drag.scene.lighting.model, LightingModel::Path);
        assert_eq!(
            drag.scene.lighting.denoise,
            Some(glint_render::Denoise::Atrous)
        );
        // The same render made by hand.
        let mut r = Renderer::open(&s, &ReadOptions::default()).unwrap();
        let mut by_hand = session.scene().clone();
        by_hand.size = [32, 32];
        by_hand.lighting = drag_lighting(&by_hand.lighting);
        let expected = r.render(&by_hand, &|_| {}).unwrap().image;
        assert_eq!(drag.image.rgb, expected.rgb);
        // The filter did something: the undenoised one-sample image differs.
        let mut raw = by_hand.clone();
        raw.lighting.denoise = None;
        let noisy = Renderer::open(&s, &ReadOptions::default())
            .unwrap()
            .render(&raw, &|_| {})
            .unwrap()
            .image;
        assert_ne!(drag.image.rgb, noisy.rgb);
        // Not the local image of that size.
        let mut local = by_hand.clone();
        local.lighting = local.lighting.for_model(LightingModel::Local);
        assert_ne!(drag.image.rgb, r.render(&local, &|_| {}).unwrap().image.rgb);
        // Deterministic: a drag frame of the same scene on another renderer.
        let mut other = Renderer::open(&s, &ReadOptions::default()).unwrap();
        let again = render_image(
            &mut other,
            session.scene(),
            Split::Off,
            Purpose::Interactive,
        );
        assert_eq!(again.unwrap().image.rgb, drag.image.rgb);
    }

    /// The drag frame's size follows the client's estimate: a cheap one gives half
    /// size, a dear one the smallest, one too dear even for that today's half-size
    /// `local` frame; the path frame's time moves the estimate.
    #[test]
    fn the_drag_frame_size_follows_the_estimate_and_falls_back_to_local() {
        let s = path_scene(256);
        let mut r = Renderer::open(&s, &ReadOptions::default()).unwrap();
        let mut frame = |cost: f64| {
            let mut d = DragCost::default();
            // An estimate of `cost` ms per pixel (one frame measured).
            d.measured([1, 1], cost);
            let f = render_image_counted(
                &mut r,
                &s,
                Split::Off,
                Purpose::Interactive,
                &|_| {},
                &mut d,
            )
            .unwrap();
            let moved = d.ms_per_pixel() != Some(cost);
            assert_eq!(
                d.local_ms().is_some(),
                f.samples == 0,
                "local frames measured"
            );
            (f.image.width, f.samples, f.scene.lighting.model, moved)
        };
        let path = LightingModel::Path;
        // 128x128 within the target; at 4e-3 ms per pixel 65 ms, over it, and the
        // smallest (96x96) 37 ms; at 1 ms per pixel even the smallest is too dear.
        assert_eq!(frame(0.0), (128, 1, path, true));
        assert_eq!(frame(4e-3), (96, 1, path, true));
        let local = (128, 0, LightingModel::Local, false);
        assert_eq!(
            frame(1.0),
            local,
            "the estimate is not moved by local frames"
        );
    }

    #[test]
    fn the_diff_of_an_image_with_itself_is_black() {
        let mut r = Renderer::open(&scene(), &ReadOptions::default()).unwrap();
        let img = r.render(&scene(), &|_| {}).unwrap().image;
        let d = difference(&img, &img);
        assert!(d.rgb.iter().flatten().all(|&c| c == 0.0));
    }
}
