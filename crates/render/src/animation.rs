//! Writing a sequence of frames: an animated GIF, an animated WebP, an MP4 through
//! `ffmpeg`, or a directory of PNG frames, chosen by the output path
//! ([`AnimationFormat::of`]). Every writer leaves nothing behind when it fails or is
//! dropped unfinished: a GIF, WebP or MP4 is
//! written to a temporary file beside the target and renamed at the end; PNG frames
//! written into a directory are removed again (and the directory, when the writer made
//! it).

use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::thread::JoinHandle;

use glint_core::{Depth, Image, RenderError};
use tempfile::NamedTempFile;

use crate::webp::{WebPSink, MAX_WEBP_SIDE};

/// The most frames a turntable may have (a tenth of a degree apart).
pub const MAX_TURNTABLE_FRAMES: u32 = 3600;

/// The highest frame rate an animation may ask for.
pub const MAX_TURNTABLE_FPS: u32 = 120;

/// The frame rate of an animation when none is given.
pub const DEFAULT_TURNTABLE_FPS: u32 = 24;

/// The formats an animation can be written in, as an error message lists them.
pub const ANIMATION_FORMATS: &str = "an animated GIF (.gif), an animated WebP (.webp), an MP4 \
(.mp4, through ffmpeg) or a directory of PNG frames (a path ending in '/' or an existing \
directory)";

/// The file format of an animation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnimationFormat {
    /// An animated GIF, looping forever: each frame quantised to its own 256-colour
    /// palette (NeuQuant), its delay `fps` rounded to hundredths of a second.
    Gif,
    /// An animated WebP, looping forever: each frame lossless (VP8L, the frame's 8-bit
    /// sRGB pixels exactly), its duration `1000 / fps` ms rounded.
    WebP,
    /// An H.264 MP4 (yuv420p) written by `ffmpeg` from the frames' sRGB pixels (MPEG-4
    /// part 2 when that ffmpeg has no libx264); an odd width or height is padded by a
    /// black pixel, as yuv420p needs even sides.
    Mp4,
    /// A directory of PNG files `frame-0000.png`, `frame-0001.png`, ..., each written
    /// as `glint render` writes a still.
    Frames,
}

impl AnimationFormat {
    /// The format `path` asks for: a directory (a path ending in `/`, or an existing
    /// directory), `.gif`, `.webp` or `.mp4` (any case).
    pub fn of(path: &Path) -> Result<AnimationFormat, TurntableError> {
        if path.as_os_str().to_string_lossy().ends_with('/') || path.is_dir() {
            return Ok(AnimationFormat::Frames);
        }
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("gif") => Ok(AnimationFormat::Gif),
            Some("mp4") => Ok(AnimationFormat::Mp4),
            Some("webp") => Ok(AnimationFormat::WebP),
            _ => Err(TurntableError::Format { path: path.into() }),
        }
    }
}

/// Why a turntable or another animation could not be rendered or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TurntableError {
    /// The frame count is out of range.
    #[error("turntable frame count {0}: expected 2..={max}", max = MAX_TURNTABLE_FRAMES)]
    Frames(u32),
    /// The frame rate is out of range.
    #[error("frame rate {0} per second: expected 1..={max}", max = MAX_TURNTABLE_FPS)]
    Fps(u32),
    /// The output path names no format an animation can be written in.
    #[error("cannot write an animation to {}: expected {formats}", path.display(), formats = ANIMATION_FORMATS)]
    Format {
        /// The output path.
        path: PathBuf,
    },
    /// Encoding or writing the animated WebP failed.
    #[error("cannot write the WebP {}: {why}", path.display())]
    WebP {
        /// The output path.
        path: PathBuf,
        /// What went wrong.
        why: String,
    },
    /// An MP4 was asked for and `ffmpeg` is not on `PATH`.
    #[error("cannot write {}: ffmpeg is not on PATH (install ffmpeg, or write .gif or a directory of PNG frames)", path.display())]
    NoFfmpeg {
        /// The output path.
        path: PathBuf,
    },
    /// `ffmpeg` failed (or has no encoder to use); `why` is its last line of errors.
    #[error("ffmpeg failed writing {}: {why}", path.display())]
    Ffmpeg {
        /// The output path.
        path: PathBuf,
        /// What ffmpeg said, or what was missing.
        why: String,
    },
    /// An animation was finished without a frame.
    #[error("cannot write {}: no frames", path.display())]
    NoFrames {
        /// The output path.
        path: PathBuf,
    },
    /// A frame is larger than a GIF can hold, or not the size of the first frame.
    #[error("cannot write {}: frame of {width}x{height} pixels: {why}", path.display())]
    FrameSize {
        /// The output path.
        path: PathBuf,
        /// The frame's width.
        width: u32,
        /// The frame's height.
        height: u32,
        /// What was wrong.
        why: &'static str,
    },
    /// Encoding the GIF failed.
    #[error("cannot encode the GIF {}", path.display())]
    Gif {
        /// The output path.
        path: PathBuf,
        /// The encoder's error.
        #[source]
        source: gif::EncodingError,
    },
    /// The operating system refused to write a file.
    #[error("cannot write {}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        #[source]
        source: std::io::Error,
    },
    /// A frame could not be rendered or encoded.
    #[error(transparent)]
    Render(#[from] RenderError),
}

/// What a writer holds once it has seen its first frame.
enum Sink {
    /// Nothing written yet (the size is not known).
    Waiting,
    Gif(Box<gif::Encoder<BufWriter<std::fs::File>>>),
    WebP(WebPSink),
    Ffmpeg(Ffmpeg),
    Frames,
}

/// Writes the frames of an animation to a path, in the format the path asks for
/// ([`AnimationFormat::of`]); [`AnimationWriter::finish`] puts the file in place.
/// Dropped unfinished (an error, a cancelled render), it removes what it wrote.
pub struct AnimationWriter {
    path: PathBuf,
    format: AnimationFormat,
    fps: u32,
    depth: Depth,
    /// The GIF's, WebP's or MP4's temporary file beside the target.
    tmp: Option<NamedTempFile>,
    /// The MP4's video encoder (`libx264` or `mpeg4`).
    encoder: &'static str,
    /// The directory of PNG frames, and whether this writer created it.
    dir_created: bool,
    /// The PNG frames written so far.
    written: Vec<PathBuf>,
    sink: Sink,
    size: Option<(u32, u32)>,
    frames: u32,
    finished: bool,
}

impl AnimationWriter {
    /// A writer of `path` at `fps` frames per second (PNG frames at `depth` bits per
    /// channel; GIF, WebP and MP4 are 8-bit). Checks what it can before any frame is
    /// rendered: the format, the output's directory, that `ffmpeg` is on `PATH` and
    /// has an encoder (MP4); creates the temporary file or the frames' directory.
    pub fn create(path: &Path, fps: u32, depth: Depth) -> Result<AnimationWriter, TurntableError> {
        if !(1..=MAX_TURNTABLE_FPS).contains(&fps) {
            return Err(TurntableError::Fps(fps));
        }
        let format = AnimationFormat::of(path)?;
        let io = |source| TurntableError::Io {
            path: path.into(),
            source,
        };
        let mut w = AnimationWriter {
            path: path.into(),
            format,
            fps,
            depth,
            tmp: None,
            encoder: "",
            dir_created: false,
            written: Vec::new(),
            sink: Sink::Waiting,
            size: None,
            frames: 0,
            finished: false,
        };
        match format {
            AnimationFormat::Frames => {
                if !path.is_dir() {
                    std::fs::create_dir(path).map_err(io)?;
                    w.dir_created = true;
                }
            }
            AnimationFormat::Gif | AnimationFormat::WebP | AnimationFormat::Mp4 => {
                if format == AnimationFormat::Mp4 {
                    w.encoder = ffmpeg_encoder(path)?;
                }
                let dir = match path.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d,
                    _ => Path::new("."),
                };
                let suffix = match format {
                    AnimationFormat::Gif => ".gif",
                    AnimationFormat::WebP => ".webp",
                    _ => ".mp4",
                };
                let mut builder = tempfile::Builder::new();
                builder.prefix(".glint-").suffix(suffix);
                // An output is an ordinary file (0666 less the umask), not a private one.
                #[cfg(unix)]
                {
                    use std::os::unix::fs::PermissionsExt;
                    builder.permissions(std::fs::Permissions::from_mode(0o666));
                }
                w.tmp = Some(builder.tempfile_in(dir).map_err(io)?);
            }
        }
        Ok(w)
    }

    /// The format being written.
    pub fn format(&self) -> AnimationFormat {
        self.format
    }

    /// The video encoder an MP4 is written with (`libx264` or `mpeg4`); empty for
    /// other formats.
    pub fn encoder(&self) -> &'static str {
        self.encoder
    }

    /// Adds a frame (every frame has the first one's size).
    pub fn frame(&mut self, image: &Image) -> Result<(), TurntableError> {
        let (width, height) = (image.width, image.height);
        let size_error = |why| TurntableError::FrameSize {
            path: self.path.clone(),
            width,
            height,
            why,
        };
        match self.size {
            None => self.size = Some((width, height)),
            Some(s) if s != (width, height) => {
                return Err(size_error("not the size of the first frame"))
            }
            Some(_) => {}
        }
        if matches!(self.sink, Sink::Waiting) {
            self.sink = self.start(width, height)?;
        }
        let index = self.frames;
        match &mut self.sink {
            Sink::Waiting => unreachable!("started above"),
            Sink::Gif(encoder) => {
                let rgb = image.encode_srgb(Depth::Eight);
                // Speed 10 of 1..=30: NeuQuant's default sampling, a second for ~50
                // 512x512 frames; 1 is several times slower for no visible gain.
                let mut f = gif::Frame::from_rgb_speed(width as u16, height as u16, &rgb, 10);
                f.delay = gif_delay(self.fps);
                encoder
                    .write_frame(&f)
                    .map_err(|source| TurntableError::Gif {
                        path: self.path.clone(),
                        source,
                    })?;
            }
            Sink::WebP(webp) => webp
                .frame(&image.encode_srgb(Depth::Eight))
                .map_err(|e| webp_error(&self.path, e))?,
            Sink::Ffmpeg(ff) => ff.write(&image.encode_srgb(Depth::Eight), &self.path)?,
            Sink::Frames => {
                let file = self.path.join(format!("frame-{index:04}.png"));
                image.write_png(&file, self.depth)?;
                self.written.push(file);
            }
        }
        self.frames += 1;
        Ok(())
    }

    /// The sink for frames of `width` x `height`: the GIF's encoder or a running
    /// ffmpeg.
    fn start(&self, width: u32, height: u32) -> Result<Sink, TurntableError> {
        let tmp = self.tmp.as_ref();
        let io = |source| TurntableError::Io {
            path: self.path.clone(),
            source,
        };
        Ok(match self.format {
            AnimationFormat::Frames => Sink::Frames,
            AnimationFormat::Gif => {
                let (Ok(w), Ok(h)) = (u16::try_from(width), u16::try_from(height)) else {
                    return Err(TurntableError::FrameSize {
                        path: self.path.clone(),
                        width,
                        height,
                        why: "a GIF is at most 65535 pixels wide and high",
                    });
                };
                let file = tmp.expect("a GIF has a temporary file");
                let file = BufWriter::new(file.as_file().try_clone().map_err(io)?);
                let gif_error = |source| TurntableError::Gif {
                    path: self.path.clone(),
                    source,
                };
                let mut encoder = gif::Encoder::new(file, w, h, &[]).map_err(gif_error)?;
                encoder
                    .set_repeat(gif::Repeat::Infinite)
                    .map_err(gif_error)?;
                Sink::Gif(Box::new(encoder))
            }
            AnimationFormat::WebP => {
                if width > MAX_WEBP_SIDE || height > MAX_WEBP_SIDE {
                    return Err(TurntableError::FrameSize {
                        path: self.path.clone(),
                        width,
                        height,
                        why: "a WebP frame is at most 16384 pixels wide and high",
                    });
                }
                let file = tmp.expect("a WebP has a temporary file");
                let file = file.as_file().try_clone().map_err(io)?;
                Sink::WebP(
                    WebPSink::start(file, width, height, self.fps)
                        .map_err(|e| webp_error(&self.path, e))?,
                )
            }
            AnimationFormat::Mp4 => {
                let out = tmp.expect("an MP4 has a temporary file").path();
                Sink::Ffmpeg(Ffmpeg::spawn(
                    &self.path,
                    out,
                    self.encoder,
                    (width, height),
                    self.fps,
                )?)
            }
        })
    }

    /// Ends the animation and puts it in place: the GIF's trailer written, ffmpeg's
    /// file finished, the temporary file renamed to the target. Returns the number of
    /// frames written.
    pub fn finish(mut self) -> Result<u32, TurntableError> {
        let io = |source| TurntableError::Io {
            path: self.path.clone(),
            source,
        };
        match std::mem::replace(&mut self.sink, Sink::Waiting) {
            Sink::Waiting => {
                return Err(TurntableError::NoFrames {
                    path: self.path.clone(),
                })
            }
            Sink::Frames => {}
            Sink::Gif(encoder) => {
                let file = encoder.into_inner().map_err(|source| TurntableError::Gif {
                    path: self.path.clone(),
                    source,
                })?;
                file.into_inner().map_err(|e| io(e.into_error()))?;
            }
            Sink::WebP(webp) => webp.finish().map_err(|e| webp_error(&self.path, e))?,
            Sink::Ffmpeg(ff) => ff.finish(&self.path)?,
        }
        if let Some(tmp) = self.tmp.take() {
            tmp.persist(&self.path).map_err(|e| io(e.error))?;
        }
        self.finished = true;
        Ok(self.frames)
    }
}

impl Drop for AnimationWriter {
    /// Unfinished: removes the PNG frames written (and the directory this writer
    /// made); the temporary file removes itself, and ffmpeg is stopped.
    fn drop(&mut self) {
        if self.finished {
            return;
        }
        if let Sink::Ffmpeg(ff) = &mut self.sink {
            ff.kill();
        }
        for file in &self.written {
            let _ = std::fs::remove_file(file);
        }
        if self.dir_created {
            let _ = std::fs::remove_dir(&self.path);
        }
    }
}

/// The error of a failed WebP write of `path`: the operating system's refusal as
/// [`TurntableError::Io`], the rest as [`TurntableError::WebP`].
fn webp_error(path: &Path, e: crate::webp::WebPError) -> TurntableError {
    match e {
        crate::webp::WebPError::Io(source) => TurntableError::Io {
            path: path.into(),
            source,
        },
        other => TurntableError::WebP {
            path: path.into(),
            why: other.to_string(),
        },
    }
}

/// A GIF frame's delay in hundredths of a second for `fps` (at least 2: browsers
/// show shorter delays as 10).
fn gif_delay(fps: u32) -> u16 {
    ((100.0 / f64::from(fps)).round() as u16).max(2)
}

/// The video encoder the `ffmpeg` on `PATH` has: `libx264`, else `mpeg4`.
fn ffmpeg_encoder(path: &Path) -> Result<&'static str, TurntableError> {
    let out = match Command::new("ffmpeg")
        .args(["-hide_banner", "-encoders"])
        .stdin(Stdio::null())
        .stderr(Stdio::null())
        .output()
    {
        Ok(out) => out,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(TurntableError::NoFfmpeg { path: path.into() })
        }
        Err(source) => {
            return Err(TurntableError::Ffmpeg {
                path: path.into(),
                why: format!("cannot run ffmpeg: {source}"),
            })
        }
    };
    let list = String::from_utf8_lossy(&out.stdout);
    let has = |name: &str| {
        list.lines()
            .any(|l| l.split_whitespace().nth(1) == Some(name))
    };
    ["libx264", "mpeg4"]
        .into_iter()
        .find(|e| has(e))
        .ok_or_else(|| TurntableError::Ffmpeg {
            path: path.into(),
            why: "this ffmpeg has neither the libx264 nor the mpeg4 encoder".into(),
        })
}

/// A running `ffmpeg` reading raw sRGB frames on its standard input.
struct Ffmpeg {
    child: Child,
    stdin: Option<ChildStdin>,
    /// Reads ffmpeg's standard error (so it never blocks on a full pipe).
    errors: Option<JoinHandle<String>>,
}

impl Ffmpeg {
    /// ffmpeg encoding `width` x `height` rgb24 frames at `fps` with `encoder` into
    /// the MP4 `out`.
    fn spawn(
        path: &Path,
        out: &Path,
        encoder: &str,
        (width, height): (u32, u32),
        fps: u32,
    ) -> Result<Ffmpeg, TurntableError> {
        let mut cmd = Command::new("ffmpeg");
        cmd.args(["-hide_banner", "-loglevel", "error", "-nostdin", "-y"])
            .args(["-f", "rawvideo", "-pix_fmt", "rgb24"])
            .arg("-s")
            .arg(format!("{width}x{height}"))
            .arg("-r")
            .arg(fps.to_string())
            .args(["-i", "-"])
            // yuv420p halves the chroma: odd sides are padded to even ones.
            .args(["-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"])
            .args(["-pix_fmt", "yuv420p", "-c:v", encoder]);
        if encoder == "libx264" {
            cmd.args(["-crf", "18"]);
        } else {
            cmd.args(["-q:v", "2"]);
        }
        cmd.args(["-movflags", "+faststart", "-f", "mp4"])
            .arg(out)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        let mut child = cmd.spawn().map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => TurntableError::NoFfmpeg { path: path.into() },
            _ => TurntableError::Ffmpeg {
                path: path.into(),
                why: format!("cannot run ffmpeg: {e}"),
            },
        })?;
        let stdin = child.stdin.take();
        let errors = child.stderr.take().map(|mut e| {
            std::thread::spawn(move || {
                let mut s = String::new();
                let _ = e.read_to_string(&mut s);
                s
            })
        });
        Ok(Ffmpeg {
            child,
            stdin,
            errors,
        })
    }

    /// Sends one frame's rgb24 bytes; when ffmpeg has stopped, its error.
    fn write(&mut self, rgb: &[u8], path: &Path) -> Result<(), TurntableError> {
        let stdin = self.stdin.as_mut().expect("open until finish");
        if stdin.write_all(rgb).is_err() {
            // ffmpeg exited (a broken pipe): its own message says why.
            self.stdin = None;
            let _ = self.child.wait();
            return Err(self.failure(path, "ffmpeg stopped reading frames"));
        }
        Ok(())
    }

    /// Closes ffmpeg's input and waits for it to finish the file.
    fn finish(mut self, path: &Path) -> Result<(), TurntableError> {
        drop(self.stdin.take());
        let status = self.child.wait().map_err(|source| TurntableError::Io {
            path: path.into(),
            source,
        })?;
        if !status.success() {
            return Err(self.failure(path, &format!("ffmpeg exited with {status}")));
        }
        Ok(())
    }

    /// The error of a failed ffmpeg: the last line it wrote to standard error, else
    /// `fallback`.
    fn failure(&mut self, path: &Path, fallback: &str) -> TurntableError {
        let said = self
            .errors
            .take()
            .and_then(|t| t.join().ok())
            .unwrap_or_default();
        let why = said
            .lines()
            .rev()
            .map(str::trim)
            .find(|l| !l.is_empty())
            .unwrap_or(fallback)
            .to_string();
        TurntableError::Ffmpeg {
            path: path.into(),
            why,
        }
    }

    /// Stops ffmpeg (an unfinished animation).
    fn kill(&mut self) {
        drop(self.stdin.take());
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
