//! Turntables: a scene rendered from `N` cameras stepping `360/N` degrees of azimuth
//! (about the view's up axis) from the scene's own camera, with one [`Renderer`], so
//! the volume is read, its field built and classified once, and every frame after the
//! first changes only the camera; the frames go to an [`AnimationWriter`]. With
//! camera keys ([`CameraPath`]) the `N` frames follow the keys instead.

use std::path::Path;
use std::time::{Duration, Instant};

use glint_core::Depth;

use crate::animation::{
    AnimationFormat, AnimationWriter, TurntableError, DEFAULT_TURNTABLE_FPS, MAX_TURNTABLE_FPS,
    MAX_TURNTABLE_FRAMES,
};
use crate::camera_path::CameraPath;
use crate::renderer::{Rendered, Renderer};
use crate::scene::Scene;

/// A turntable: how many frames, how fast they play, and the PNG depth of frames
/// written to a directory.
///
/// ```
/// use glint_render::{Input, Phantom, ReadOptions, Renderer, Scene, Turntable};
///
/// let scene = Scene {
///     input: Input::Phantom { name: Phantom::SheppLogan, size: 24 },
///     size: [24, 24],
///     ..Scene::default()
/// };
/// let dir = tempfile::tempdir().unwrap();
/// let gif = dir.path().join("spin.gif");
/// let mut renderer = Renderer::open(&scene, &ReadOptions::default()).unwrap();
/// let done = Turntable::new(4).write(&mut renderer, &scene, &gif, &|_| {}).unwrap();
/// assert_eq!((done.frames, done.width, done.height), (4, 24, 24));
/// assert!(std::fs::read(&gif).unwrap().starts_with(b"GIF89a"));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Turntable {
    /// Frames in one turn (2..=[`MAX_TURNTABLE_FRAMES`]).
    pub frames: u32,
    /// Frames per second (1..=[`MAX_TURNTABLE_FPS`]).
    pub fps: u32,
    /// Bits per channel of PNG frames written to a directory (GIF, WebP and MP4 are
    /// 8-bit).
    pub depth: Depth,
    /// Camera keys the frames follow instead of turning round (`None`: a turn).
    pub keys: Option<CameraPath>,
}

/// What a turntable wrote.
#[derive(Clone, Debug)]
pub struct TurntableWritten {
    /// The format written.
    pub format: AnimationFormat,
    /// Frames written.
    pub frames: u32,
    /// Frame width in pixels.
    pub width: u32,
    /// Frame height in pixels.
    pub height: u32,
    /// The first frame's resolved scene (the scene's own camera; `--dump-scene`).
    pub first: Scene,
    /// Time spent rendering the frames (the first one's classification included).
    pub render: Duration,
    /// Time spent encoding and writing the frames.
    pub encode: Duration,
}

impl Turntable {
    /// `frames` frames at [`DEFAULT_TURNTABLE_FPS`], 8-bit.
    pub fn new(frames: u32) -> Turntable {
        Turntable {
            frames,
            fps: DEFAULT_TURNTABLE_FPS,
            depth: Depth::Eight,
            keys: None,
        }
    }

    /// `frames` frames along camera `keys` ([`CameraPath::frame_camera`]).
    pub fn along(keys: CameraPath, frames: u32) -> Turntable {
        Turntable {
            keys: Some(keys),
            ..Turntable::new(frames)
        }
    }

    /// Checks the frame count and rate.
    pub fn validate(&self) -> Result<(), TurntableError> {
        if !(2..=MAX_TURNTABLE_FRAMES).contains(&self.frames) {
            return Err(TurntableError::Frames(self.frames));
        }
        if !(1..=MAX_TURNTABLE_FPS).contains(&self.fps) {
            return Err(TurntableError::Fps(self.fps));
        }
        Ok(())
    }

    /// Frame `k`'s scene: `scene` with its camera's azimuth turned by `360 k / N`
    /// degrees (frame 0 is `scene` itself, so it renders the still of the scene bit
    /// for bit; the others' azimuths are brought into -180..180); with camera keys,
    /// `scene` with the camera of [`CameraPath::frame_camera`].
    pub fn frame_scene(&self, scene: &Scene, k: u32) -> Scene {
        let mut s = scene.clone();
        if let Some(keys) = &self.keys {
            s.camera = keys.frame_camera(&scene.camera, k, self.frames);
        } else if k > 0 {
            let turned =
                scene.camera.azimuth + 360.0 * f64::from(k) / f64::from(self.frames.max(1));
            s.camera.azimuth = (turned + 180.0).rem_euclid(360.0) - 180.0;
        }
        s
    }

    /// The writer of `path` for this turntable ([`AnimationWriter::create`]): checks
    /// the frame count and rate, the format and (MP4) ffmpeg before any frame is
    /// rendered.
    pub fn writer(&self, path: &Path) -> Result<AnimationWriter, TurntableError> {
        self.validate()?;
        AnimationWriter::create(path, self.fps, self.depth)
    }

    /// Renders the turntable of `scene` with `renderer` into `writer` and finishes
    /// it. `progress` is called with the pixels finished, as by [`Renderer::render`]
    /// (the whole turntable is `N` times the image's pixels). On an error nothing is
    /// left at the output (the writer removes what it wrote).
    pub fn render(
        &self,
        renderer: &mut Renderer,
        scene: &Scene,
        mut writer: AnimationWriter,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<TurntableWritten, TurntableError> {
        self.validate()?;
        let (mut render, mut encode) = (Duration::ZERO, Duration::ZERO);
        let mut first = None;
        for k in 0..self.frames {
            let start = Instant::now();
            let mut rendered = renderer.render(&self.frame_scene(scene, k), progress)?;
            rendered.draw_overlays();
            render += start.elapsed();
            let start = Instant::now();
            writer.frame(&rendered.image)?;
            encode += start.elapsed();
            if k == 0 {
                first = Some(rendered);
            }
        }
        let format = writer.format();
        let start = Instant::now();
        let frames = writer.finish()?;
        encode += start.elapsed();
        let first: Rendered = first.expect("at least two frames");
        Ok(TurntableWritten {
            format,
            frames,
            width: first.image.width,
            height: first.image.height,
            first: first.scene,
            render,
            encode,
        })
    }

    /// [`Turntable::writer`] then [`Turntable::render`]: the turntable of `scene`
    /// written to `path`.
    pub fn write(
        &self,
        renderer: &mut Renderer,
        scene: &Scene,
        path: &Path,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<TurntableWritten, TurntableError> {
        let writer = self.writer(path)?;
        self.render(renderer, scene, writer, progress)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glint_core::{Image, RenderStats};

    #[test]
    fn frames_step_the_azimuth_round_from_the_scenes_own() {
        let mut scene = Scene::default();
        scene.camera.azimuth = 170.0;
        let t = Turntable::new(4);
        assert_eq!(t.frame_scene(&scene, 0), scene);
        let azimuths: Vec<f64> = (0..4)
            .map(|k| t.frame_scene(&scene, k).camera.azimuth)
            .collect();
        assert_eq!(azimuths, [170.0, -100.0, -10.0, 80.0]);
        // Far from zero, the turned angles stay within the camera's range.
        scene.camera.azimuth = 3590.0;
        for k in 1..4 {
            t.frame_scene(&scene, k).camera.validate().unwrap();
        }
    }

    #[test]
    fn counts_and_rates_out_of_range_are_refused() {
        for frames in [0, 1, MAX_TURNTABLE_FRAMES + 1] {
            let err = Turntable::new(frames).validate().unwrap_err();
            assert!(matches!(err, TurntableError::Frames(f) if f == frames));
        }
        for fps in [0, MAX_TURNTABLE_FPS + 1] {
            let t = Turntable {
                fps,
                ..Turntable::new(4)
            };
            assert!(matches!(t.validate(), Err(TurntableError::Fps(_))));
        }
        Turntable::new(2).validate().unwrap();
    }

    fn grey(width: u32, height: u32, v: f32) -> Image {
        let n = (width * height) as usize;
        Image {
            width,
            height,
            rgb: vec![[v; 3]; n],
            alpha: vec![1.0; n],
            stats: RenderStats::default(),
        }
    }

    /// A writer dropped before it is finished (a render that failed half way) leaves
    /// nothing: no GIF, no temporary file, no frames, no directory it made.
    #[test]
    fn an_unfinished_animation_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let frames = dir.path().join("frames");
        let gif = dir.path().join("a.gif");
        for path in [
            std::path::PathBuf::from(format!("{}/", frames.display())),
            gif.clone(),
        ] {
            let mut w = AnimationWriter::create(&path, 10, Depth::Eight).unwrap();
            w.frame(&grey(8, 6, 0.5)).unwrap();
            // Another size is refused.
            let err = w.frame(&grey(6, 8, 0.5)).unwrap_err();
            assert!(matches!(err, TurntableError::FrameSize { .. }), "{err}");
            drop(w);
            assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        }
        // Finished, the GIF is in place with its frames, and nothing else.
        let mut w = AnimationWriter::create(&gif, 10, Depth::Eight).unwrap();
        for v in [0.2, 0.8] {
            w.frame(&grey(8, 6, v)).unwrap();
        }
        assert_eq!(w.finish().unwrap(), 2);
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["a.gif"]);
        // No frame: an error, and nothing left.
        let w = AnimationWriter::create(&dir.path().join("b.gif"), 10, Depth::Eight).unwrap();
        assert!(matches!(w.finish(), Err(TurntableError::NoFrames { .. })));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
