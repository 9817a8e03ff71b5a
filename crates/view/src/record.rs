//! The page's "record" button: a turntable of the client's current scene, rendered on
//! the server by [`glint_render::Turntable`] (the code of `glint render --turntable`)
//! with a clone of the client's renderer (the field and classification shared, so
//! nothing is read again), on a blocking thread while the client's frames go on.
//! It is written to a temporary file in the format chosen (GIF, WebP, or MP4 when
//! `ffmpeg` is on `PATH`) and sent to the page: [`ServerMessage::Recording`] as it
//! renders, then [`ServerMessage::Recorded`] and, as the very next binary message,
//! the file's bytes.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;

use axum::extract::ws::{Message, WebSocket};
use glint_render::{Renderer, Scene, Turntable};
use tokio::sync::mpsc;

use crate::protocol::ServerMessage;
use crate::{send_json, ViewError};

/// The most frames a recording may have.
pub const MAX_RECORD_FRAMES: u32 = 360;

/// What a recording reports.
pub(crate) enum Event {
    /// Percent of the frames' pixels rendered.
    Progress(u32),
    /// The file's format (its extension) and bytes, or the one-line error.
    Done(Result<(&'static str, u32, Vec<u8>), String>),
}

/// A client's recording in progress, if any.
pub(crate) struct Recording {
    events: Option<mpsc::UnboundedReceiver<Event>>,
    /// Stops a `path` frame in flight when the client goes.
    cancel: Arc<AtomicBool>,
}

/// The formats the page may choose: `gif`, `webp`, and `mp4` when `ffmpeg` is on
/// `PATH` (as `glint render --turntable` writes them).
pub(crate) fn formats() -> Vec<&'static str> {
    let ffmpeg = std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|dir| dir.join("ffmpeg").is_file()));
    let mut out = vec!["gif", "webp"];
    if ffmpeg {
        out.push("mp4");
    }
    out
}

impl Recording {
    /// No recording.
    pub(crate) fn idle() -> Recording {
        Recording {
            events: None,
            cancel: Arc::new(AtomicBool::new(false)),
        }
    }

    /// Starts recording `frames` views round `scene` as `format` with `renderer` (a
    /// clone of the client's); refused while one is under way, or for a count or
    /// format out of range.
    pub(crate) fn start(
        &mut self,
        mut renderer: Renderer,
        scene: Scene,
        frames: u32,
        format: &str,
    ) -> Result<(), ViewError> {
        if self.events.is_some() {
            return Err(ViewError::Message(
                "a recording is under way: wait for it to finish".into(),
            ));
        }
        if !(2..=MAX_RECORD_FRAMES).contains(&frames) {
            return Err(ViewError::Message(format!(
                "record {frames} frames: expected 2..={MAX_RECORD_FRAMES}"
            )));
        }
        let Some(ext) = formats().into_iter().find(|f| *f == format) else {
            return Err(ViewError::Message(format!(
                "record as '{format}': expected one of {}",
                formats().join(", ")
            )));
        };
        let (tx, rx) = mpsc::unbounded_channel();
        self.cancel = Arc::new(AtomicBool::new(false));
        renderer.set_cancel(Some(self.cancel.clone()));
        self.events = Some(rx);
        tokio::task::spawn_blocking(move || {
            let done = record(&mut renderer, &scene, frames, ext, &tx);
            let _ = tx.send(Event::Done(done.map(|(n, bytes)| (ext, n, bytes))));
        });
        Ok(())
    }

    /// The next event of the recording; never ready when there is none.
    pub(crate) async fn next(&mut self) -> Event {
        let Some(rx) = self.events.as_mut() else {
            return std::future::pending().await;
        };
        let event = rx
            .recv()
            .await
            .unwrap_or_else(|| Event::Done(Err("the recording failed unexpectedly".into())));
        if matches!(event, Event::Done(_)) {
            self.events = None;
        }
        event
    }
}

impl Drop for Recording {
    /// The client is gone: a `path` frame in flight stops.
    fn drop(&mut self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}

/// Renders the turntable into a temporary file and reads it back: the frame count
/// and the bytes, or the one-line error.
fn record(
    renderer: &mut Renderer,
    scene: &Scene,
    frames: u32,
    ext: &str,
    tx: &mpsc::UnboundedSender<Event>,
) -> Result<(u32, Vec<u8>), String> {
    let line = |e: &dyn std::error::Error| glint_io::one_line(e);
    let dir = tempfile::tempdir().map_err(|e| line(&e))?;
    let path = dir.path().join(format!("turntable.{ext}"));
    let [w, h] = scene.size;
    let total = (u64::from(w) * u64::from(h) * u64::from(frames)).max(1);
    let (done, sent) = (AtomicU64::new(0), AtomicU64::new(0));
    let progress = |n: u64| {
        let percent = ((done.fetch_add(n, Ordering::Relaxed) + n) * 100 / total).min(100);
        if sent.fetch_max(percent, Ordering::Relaxed) < percent {
            let _ = tx.send(Event::Progress(percent as u32));
        }
    };
    let written = Turntable::new(frames)
        .write(renderer, scene, &path, &progress)
        .map_err(|e| line(&e))?;
    let bytes = std::fs::read(&path).map_err(|e| line(&e))?;
    Ok((written.frames, bytes))
}

/// Sends a recording's event to the page: its progress, or the file (a `recorded`
/// message, then the bytes as a binary message), or its error. `false`: the socket
/// is gone.
pub(crate) async fn forward(socket: &mut WebSocket, event: Event) -> bool {
    match event {
        Event::Progress(percent) => send_json(socket, &ServerMessage::Recording { percent }).await,
        Event::Done(Ok((format, frames, bytes))) => {
            let msg = ServerMessage::Recorded {
                format: format.into(),
                frames,
                bytes: bytes.len(),
            };
            send_json(socket, &msg).await
                && socket.send(Message::Binary(bytes.into())).await.is_ok()
        }
        Event::Done(Err(message)) => send_json(socket, &ServerMessage::Error { message }).await,
    }
}
