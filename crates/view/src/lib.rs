//! glint-view: the interactive viewer. The Rust ray caster renders on the server; the
//! browser shows frames and sends interaction over a WebSocket (the remote-rendering
//! arrangement of Kitware's ParaViewWeb and trame). The page, its script and styles
//! are embedded in the binary.
//!
//! ```no_run
//! use std::sync::Arc;
//! use glint_render::Scene;
//! use glint_view::{Access, Viewer, ViewerConfig};
//!
//! # async fn run() -> Result<(), Box<dyn std::error::Error>> {
//! let viewer = Arc::new(Viewer::new(Scene::default(), ViewerConfig::default())?);
//! let listener = tokio::net::TcpListener::bind("127.0.0.1:8080").await?;
//! // Loopback: no token needed; any other address needs one (Token::random()).
//! let access = Arc::new(Access::new(listener.local_addr()?, None)?);
//! println!("open {}", access.url());
//! glint_view::serve(listener, viewer, access).await?;
//! # Ok(())
//! # }
//! ```
//!
//! Protocol ([`protocol`]): on connection the server sends a `hello` (the resolved
//! scene, presets, lobes, views, the value range) and a first frame. The page sends
//! `update` messages (a partial scene, a sequence number, whether the user is still
//! dragging), `split`, `save`, `pick`, `unmark` and `record` (a turntable of the
//! scene rendered on the server and sent as a file, see `record.rs`). Only the latest state is rendered: updates that
//! arrive while a frame renders are merged, never queued. While the user drags,
//! frames are half size and JPEG at quality 70; 150 ms after the last interactive
//! update a full-resolution frame follows. A `path` scene is progressive: its
//! interactive frames take one sample per pixel, denoised, at the size its measured
//! cost allows ([`drag`]; half-size `local` when even the smallest would be too
//! slow), and while the scene holds still full
//! frames follow one another, each adding samples to the last ([`next_samples`]), up
//! to the scene's `spp`; the frame header carries the sample count. Any change
//! starts again from one sample.
//!
//! Access ([`access`]): only the viewer's own page may use it.
//! Requests must name this machine in `Host` (DNS rebinding), a WebSocket handshake
//! from a page must come from the origin the page was served from, and a viewer on a
//! non-loopback address asks for a random token in the URL, as Jupyter does.

#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod access;
mod cut;
pub mod drag;
pub mod histogram;
pub mod labels;
pub mod levels;
mod pick;
pub mod protocol;
mod record;
pub mod schedule;
mod session;

use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::State;
use axum::http::header;
use axum::response::{Html, IntoResponse};
use axum::routing::get;
use axum::{middleware, Router};
use glint_render::{
    LightingModel, RenderError, Renderer, Scene, SceneLobe, View, DEFAULT_SPP, PRESETS,
};

pub use access::{is_loopback, Access, Token};
pub use drag::{drag_frame, DragCost, DragFrame};
pub use histogram::{Histogram, HISTOGRAM_BINS};
pub use labels::{LabelInfo, LabelList};
pub use levels::PyramidLevel;
pub use pick::MAX_MARKS;
pub use schedule::{next_samples, Schedule};
pub use session::{
    apply_patch, drag_lighting, frame_ray_samples, render_frame, render_frame_counted,
    render_image, Frame, FrameImage, Session, MAX_FRAME_RAY_SAMPLES, MAX_VIEW_SIDE,
};

use levels::Stage;
use protocol::{ClientMessage, Purpose, ServerMessage, Split};
use tokio::sync::watch;

/// Why the viewer refused something.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// Rendering or resolving the scene failed.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// A client message was refused.
    #[error("{0}")]
    Message(String),
    /// A non-loopback address without a token.
    #[error("{addr} is not a loopback address: serving it needs a token")]
    TokenRequired {
        /// The address.
        addr: SocketAddr,
    },
    /// A token given by hand that is too short, too long or needs escaping.
    #[error(
        "a token is {min} to {max} characters from A-Z a-z 0-9 - . _ ~",
        min = Token::MIN_CHARS,
        max = Token::MAX_CHARS
    )]
    BadToken,
    /// The operating system's random number generator failed.
    #[error("cannot make a token: the OS random number generator failed: {0}")]
    Random(String),
    /// A request without one well-formed `Host` header.
    #[error("a request needs one Host header naming host and port")]
    BadHost,
    /// A request naming a host this viewer does not answer for (DNS rebinding).
    #[error(
        "Host {host} is not this viewer: it answers for localhost, a loopback address \
         or the address it is bound to, on port {port}"
    )]
    ForeignHost {
        /// The Host header as sent (escaped, cut).
        host: String,
        /// The viewer's port.
        port: u16,
    },
    /// A request from a page of another origin.
    #[error("Origin {origin} is not this viewer's page: only its own page may use it")]
    ForeignOrigin {
        /// The Origin header as sent (escaped, cut).
        origin: String,
    },
    /// A request without the viewer's token.
    #[error("this viewer needs its token: open the URL glint view printed (…/?token=…)")]
    TokenMissing,
    /// A request with another token.
    #[error("wrong token: open the URL glint view printed (…/?token=…)")]
    TokenWrong,
}

/// Limits and timing of a viewer.
#[derive(Clone, Copy, Debug)]
pub struct ViewerConfig {
    /// Clients served at once; more are refused with a message.
    pub max_clients: usize,
    /// Largest client message, bytes (scene patches are a few hundred bytes).
    pub max_message_bytes: usize,
    /// Quiet time after the last interactive update before the full frame.
    pub settle: Duration,
}

impl Default for ViewerConfig {
    fn default() -> Self {
        ViewerConfig {
            max_clients: 8,
            max_message_bytes: 64 * 1024,
            settle: Duration::from_millis(150),
        }
    }
}

/// A viewer of one volume: the field every client renders, the starting scene and the
/// limits.
pub struct Viewer {
    /// Reads nothing more: every client renders with a clone of it.
    renderer: Renderer,
    scene: Scene,
    range: [f32; 2],
    /// The labels of the scene's label map, if it has one (the page's legend).
    labels: Option<LabelList>,
    /// The volume's histogram (`None`: a scene of meshes only).
    histogram: Option<Histogram>,
    /// The world box of the volume's voxel centres (`None`: a scene of meshes only).
    bounds: Option<cut::Bounds>,
    /// The pyramid level `renderer` reads (`None`: not a pyramid).
    level: Option<PyramidLevel>,
    /// The finer level to read when `renderer` reads a coarse stand-in.
    finer: Option<(glint_io::ReadOptions, PyramidLevel)>,
    /// The finer level once read ([`Viewer::refine`]); clients watch it.
    refined: watch::Sender<Option<Arc<Stage>>>,
    config: ViewerConfig,
    clients: AtomicUsize,
    cancelled: AtomicUsize,
    /// Pixels the clients' frames finished (a split frame's two renders both count).
    pixels: Arc<AtomicU64>,
    /// Frames that stopped before they were done (input or the client leaving).
    stopped: Arc<AtomicUsize>,
}

impl Viewer {
    /// Reads the scene's input and checks the scene resolves.
    pub fn new(scene: Scene, config: ViewerConfig) -> Result<Viewer, RenderError> {
        Viewer::with_options(scene, config, &glint_io::ReadOptions::default())
    }

    /// [`Viewer::new`] reading the input with `options` (e.g. the level of an OME-Zarr
    /// pyramid, `strict`). An OME-Zarr store asked for at `Level::Auto` is opened at
    /// its coarsest level when that is not the one asked for: [`Viewer::refine`] then
    /// reads the level asked for.
    pub fn with_options(
        scene: Scene,
        config: ViewerConfig,
        options: &glint_io::ReadOptions,
    ) -> Result<Viewer, RenderError> {
        let plan = levels::plan(&scene.input, options)?;
        let mut renderer = Renderer::open(&scene, &plan.first)?;
        let scene = renderer.resolve(&scene)?.scene;
        // A scene of meshes only has no value range (the page's iso slider).
        let (lo, hi) = renderer.field().map_or((0.0, 1.0), |f| f.range());
        let image = match &scene.input {
            glint_render::Input::Path(p) => Some(p.as_path()),
            _ => None,
        };
        let labels = scene
            .labels
            .as_ref()
            .map(|l| LabelList::read(l, image))
            .transpose()?;
        let histogram = renderer.field().map(|f| Histogram::of(f, HISTOGRAM_BINS));
        let bounds = renderer
            .field()
            .map(|f| cut::bounds(f.dims(), |p| f.index_to_world(p)));
        Ok(Viewer {
            renderer,
            scene,
            range: [lo, hi],
            labels,
            histogram,
            bounds,
            level: plan.level,
            finer: plan.finer,
            refined: watch::Sender::new(None),
            config,
            clients: AtomicUsize::new(0),
            cancelled: AtomicUsize::new(0),
            pixels: Arc::new(AtomicU64::new(0)),
            stopped: Arc::new(AtomicUsize::new(0)),
        })
    }

    /// Reads the finer pyramid level when the viewer started from a coarse one, and
    /// offers it to every client: each swaps it in when its camera rests (no drag
    /// under way, no frame in flight), new clients start from it. Blocks while
    /// reading (call it on a thread of its own). Returns the level offered, `None`
    /// when there is none to read or it was read already.
    pub fn refine(&self) -> Result<Option<PyramidLevel>, RenderError> {
        let Some((options, level)) = &self.finer else {
            return Ok(None);
        };
        if self.refined.borrow().is_some() {
            return Ok(None);
        }
        let mut renderer = Renderer::open(&self.scene, options)?;
        renderer.resolve(&self.scene)?;
        let (lo, hi) = renderer.field().map_or((0.0, 1.0), |f| f.range());
        self.refined.send_replace(Some(Arc::new(Stage {
            renderer,
            level: level.clone(),
            range: [lo, hi],
        })));
        Ok(Some(level.clone()))
    }

    /// What the reader said about the scene's input (the level first read): objects
    /// of a DICOM directory skipped, where the affine came from, what it assumed.
    pub fn notes(&self) -> &[String] {
        self.renderer.notes()
    }

    /// The pyramid level a new client starts from (`None`: not a pyramid).
    pub fn level(&self) -> Option<PyramidLevel> {
        match &*self.refined.borrow() {
            Some(stage) => Some(stage.level.clone()),
            None => self.level.clone(),
        }
    }

    /// Full frames (progressive refinements or not) stopped by a client's input,
    /// over all clients (frames stopped by a client leaving are not counted).
    pub fn cancelled(&self) -> usize {
        self.cancelled.load(Ordering::SeqCst)
    }

    /// The labels of the scene's label map (`None` without one).
    pub fn labels(&self) -> Option<&LabelList> {
        self.labels.as_ref()
    }

    /// Pixels the clients' frames have finished so far, over all clients: the work
    /// done, counted per tile of the ray caster and per row of the path tracer.
    pub fn pixels_rendered(&self) -> u64 {
        self.pixels.load(Ordering::SeqCst)
    }

    /// Frames stopped before they were done, over all clients: by input (as
    /// [`Viewer::cancelled`] counts) or because their client left.
    pub fn frames_stopped(&self) -> usize {
        self.stopped.load(Ordering::SeqCst)
    }

    /// Clients connected now.
    pub fn clients(&self) -> usize {
        self.clients.load(Ordering::SeqCst)
    }
}

/// Serves the page and the WebSocket on `listener` until the process ends, to the
/// requests `access` lets through; `access` must be made for the listener's address.
pub async fn serve(
    listener: tokio::net::TcpListener,
    viewer: Arc<Viewer>,
    access: Arc<Access>,
) -> std::io::Result<()> {
    let addr = listener.local_addr()?;
    if addr != access.bound() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "the access policy is for {}, the listener is on {addr}",
                access.bound()
            ),
        ));
    }
    let app = router(viewer, access).into_make_service_with_connect_info::<SocketAddr>();
    axum::serve(listener, app).await
}

/// The viewer's routes: `/` (the page), `/app.js`, `/tfedit.js`, `/pick.js`, `/clip.js`,
/// `/record.js`, `/style.css`, `/ws`, behind the checks of `access`.
pub fn router(viewer: Arc<Viewer>, access: Arc<Access>) -> Router {
    Router::new()
        .route("/", get(|| async { Html(include_str!("page/index.html")) }))
        .route(
            "/app.js",
            get(|| async {
                (
                    [(header::CONTENT_TYPE, "text/javascript")],
                    include_str!("page/app.js"),
                )
            }),
        )
        .route(
            "/tfedit.js",
            get(|| async {
                (
                    [(header::CONTENT_TYPE, "text/javascript")],
                    include_str!("page/tfedit.js"),
                )
            }),
        )
        .route(
            "/pick.js",
            get(|| async {
                (
                    [(header::CONTENT_TYPE, "text/javascript")],
                    include_str!("page/pick.js"),
                )
            }),
        )
        .route(
            "/clip.js",
            get(|| async {
                (
                    [(header::CONTENT_TYPE, "text/javascript")],
                    include_str!("page/clip.js"),
                )
            }),
        )
        .route(
            "/record.js",
            get(|| async {
                (
                    [(header::CONTENT_TYPE, "text/javascript")],
                    include_str!("page/record.js"),
                )
            }),
        )
        .route(
            "/style.css",
            get(|| async {
                (
                    [(header::CONTENT_TYPE, "text/css")],
                    include_str!("page/style.css"),
                )
            }),
        )
        .route("/ws", get(upgrade))
        .with_state(viewer)
        .layer(middleware::from_fn_with_state(access, access::guard))
}

async fn upgrade(ws: WebSocketUpgrade, State(viewer): State<Arc<Viewer>>) -> impl IntoResponse {
    // The transport limit is well above the protocol's, so an oversize message is
    // answered with an error instead of closing the connection.
    let limit = viewer.config.max_message_bytes * 16;
    ws.max_message_size(limit)
        .on_upgrade(move |socket| connection(socket, viewer))
}

/// Counts a client while it is connected.
struct Seat(Arc<Viewer>);

impl Seat {
    fn take(viewer: &Arc<Viewer>) -> Option<Seat> {
        let max = viewer.config.max_clients;
        viewer
            .clients
            .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| {
                (n < max).then_some(n + 1)
            })
            .ok()
            .map(|_| Seat(viewer.clone()))
    }
}

impl Drop for Seat {
    fn drop(&mut self) {
        self.0.clients.fetch_sub(1, Ordering::SeqCst);
    }
}

async fn send_json(socket: &mut WebSocket, msg: &ServerMessage) -> bool {
    let text = serde_json::to_string(msg).expect("server messages serialise");
    socket.send(Message::Text(text.into())).await.is_ok()
}

/// A frame being rendered on the blocking pool, with what it is for.
type FrameJob = tokio::task::JoinHandle<Result<(Frame, Purpose), RenderError>>;

/// The first message a client gets: the scene and the names it may choose from;
/// `stage`: the finer level, when the client starts from it.
fn hello(viewer: &Viewer, stage: Option<&Stage>) -> ServerMessage {
    ServerMessage::Hello {
        scene: serde_json::to_value(&viewer.scene).expect("scenes serialise"),
        presets: PRESETS.iter().map(|p| p.name).collect(),
        lobes: SceneLobe::ALL.map(|k| k.name()).to_vec(),
        views: View::NAMES.to_vec(),
        environments: glint_render::available_environments(),
        range: stage.map_or(viewer.range, |s| s.range),
        level: stage.map_or_else(|| viewer.level.clone(), |s| Some(s.level.clone())),
        bounds: viewer.bounds,
        record: record::formats(),
        labels: viewer
            .labels
            .as_ref()
            .map_or_else(Vec::new, |l| l.entries().to_vec()),
    }
}

/// Starts rendering `state` for `purpose` on the blocking pool; a full frame of a
/// progressive (`path`) state takes the sample count `schedule` gives it, a drag
/// frame of a `path` state the size the client's `drag` estimate gives it.
fn spawn_frame(
    viewer: &Viewer,
    (renderer, drag): (&Arc<Mutex<Renderer>>, &Arc<Mutex<DragCost>>),
    cancel: &Arc<AtomicBool>,
    state: &ClientState,
    purpose: Purpose,
    schedule: &Schedule,
) -> FrameJob {
    let (r, d, mut s) = (renderer.clone(), drag.clone(), state.clone());
    let (pixels, stopped) = (viewer.pixels.clone(), viewer.stopped.clone());
    if let Some(list) = viewer.labels() {
        s.scene = list.visible(&s.scene);
    }
    if purpose == Purpose::Full {
        if let Some(spp) = schedule.samples_for(state.progressive()) {
            s.scene.lighting.spp = Some(spp);
        }
    }
    // A cancel asked of the job before this one (which finished first) is spent.
    // Cleared here, before the job is queued, not when it starts: input arriving
    // while it waits for a thread must stop it too (issue 29's protocol test).
    cancel.store(false, Ordering::Relaxed);
    tokio::task::spawn_blocking(move || {
        let mut r = r.lock().unwrap_or_else(|e| e.into_inner());
        let mut d = d.lock().unwrap_or_else(|e| e.into_inner());
        let count = |n| {
            pixels.fetch_add(n, Ordering::Relaxed);
        };
        let (scene, split) = (&s.scene, s.split);
        let done = render_frame_counted(&mut r, scene, split, purpose, s.seq, &count, &mut d);
        if matches!(done, Err(RenderError::Cancelled)) {
            stopped.fetch_add(1, Ordering::SeqCst);
        }
        done.map(|f| (f, purpose))
    })
}

/// Seats a new client and greets it: `None` (the socket told why, or gone) when the
/// viewer is full or the greeting cannot be sent; `stage`: the finer level, when the
/// client starts from it.
async fn admit(
    socket: &mut WebSocket,
    viewer: &Arc<Viewer>,
    stage: Option<&Stage>,
) -> Option<Seat> {
    let Some(seat) = Seat::take(viewer) else {
        let message = format!(
            "server busy: at most {} clients at once",
            viewer.config.max_clients
        );
        send_json(socket, &ServerMessage::Error { message }).await;
        let _ = socket.send(Message::Close(None)).await;
        return None;
    };
    if !send_json(socket, &hello(viewer, stage)).await {
        return None;
    }
    if let Some(histogram) = &viewer.histogram {
        let msg = ServerMessage::Histogram {
            histogram: histogram.clone(),
        };
        if !send_json(socket, &msg).await {
            return None;
        }
    }
    Some(seat)
}

/// A client's own renderer (sharing the viewer's data, or `stage`'s, the finer level)
/// and the flag that stops its progressive frame in flight: set when input arrives
/// while a frame refines, so the input is answered at once (the refinement's samples
/// are dropped).
fn client_renderer(
    viewer: &Viewer,
    stage: Option<&Stage>,
) -> (Arc<Mutex<Renderer>>, Arc<AtomicBool>) {
    let cancel = Arc::new(AtomicBool::new(false));
    let mut renderer = stage.map_or(&viewer.renderer, |s| &s.renderer).clone();
    renderer.set_cancel(Some(cancel.clone()));
    (Arc::new(Mutex::new(renderer)), cancel)
}

/// Swaps the finer level in for a client whose camera rests: its renderer renders
/// from it (the cancel flag kept), and the page is told. `false`: the socket is gone.
async fn swap_level(
    socket: &mut WebSocket,
    renderer: &Mutex<Renderer>,
    cancel: &Arc<AtomicBool>,
    stage: &Stage,
) -> bool {
    let mut fine = stage.renderer.clone();
    fine.set_cancel(Some(cancel.clone()));
    *renderer.lock().unwrap_or_else(|e| e.into_inner()) = fine;
    let msg = ServerMessage::Level {
        level: stage.level.clone(),
    };
    send_json(socket, &msg).await
}

/// What a connection owes its client ([`Schedule`]) and the frame it shows.
struct Pending {
    schedule: Schedule,
    /// The resolved scene and update of the last frame shown: new marks are drawn
    /// on it at once.
    shown: Option<(Scene, u32)>,
}

/// Sends a finished frame (and, for a full or saved one, its scene) or the error of
/// a failed one; a `path` state still holding still asks for its next refinement.
/// `false`: the socket is gone.
async fn finished(
    socket: &mut WebSocket,
    viewer: &Viewer,
    state: &ClientState,
    pending: &mut Pending,
    done: Result<Result<(Frame, Purpose), RenderError>, tokio::task::JoinError>,
) -> bool {
    let message = match done {
        Ok(Ok((frame, purpose))) => {
            // A `path` state still holding still refines: the next full frame adds
            // samples, until the scene's count.
            if purpose == Purpose::Full && frame.seq == state.seq {
                pending
                    .schedule
                    .full_done(frame.samples, state.progressive());
            }
            // The marks on this frame, before it (the page draws them with it).
            let marked = !state.marks.is_empty() && state.split == Split::Off;
            if marked && purpose != Purpose::Save {
                let marks = state.marks.projected(&frame.scene, frame.seq);
                if !send_json(socket, &marks).await {
                    return false;
                }
            }
            // The crop box and clip planes on this frame, before it.
            let cut = viewer.bounds.filter(|_| state.split == Split::Off);
            if let Some(msg) = cut.and_then(|b| cut::projected(&frame.scene, frame.seq, b)) {
                if purpose != Purpose::Save && !send_json(socket, &msg).await {
                    return false;
                }
            }
            if purpose != Purpose::Save {
                pending.shown = Some((frame.scene.clone(), frame.seq));
            }
            if socket
                .send(Message::Binary(frame.message.into()))
                .await
                .is_err()
            {
                return false;
            }
            if purpose == Purpose::Interactive {
                return true;
            }
            let window_level = frame
                .scene
                .derived
                .as_ref()
                .and_then(|d| d.transfer_function.as_ref())
                .map(|tf| tf.window_level());
            let scene = serde_json::to_value(&frame.scene).expect("scenes serialise");
            return send_json(
                socket,
                &ServerMessage::Scene {
                    seq: frame.seq,
                    scene,
                    window_level,
                },
            )
            .await;
        }
        Ok(Err(RenderError::Cancelled)) => {
            // The refinement's samples are gone: start again from none.
            viewer.cancelled.fetch_add(1, Ordering::SeqCst);
            pending.schedule.cancelled();
            return true;
        }
        Ok(Err(e)) => glint_io::one_line(&e),
        Err(_) => "the render failed unexpectedly".into(),
    };
    send_json(socket, &ServerMessage::Error { message }).await
}

/// Picks and marks pixel `at` of the client's scene (as its frames show it, hidden
/// labels hidden) and answers; then the marks on the frame shown now (the frames
/// after it bring theirs). `false`: the socket is gone.
async fn answer_pick(
    socket: &mut WebSocket,
    viewer: &Viewer,
    renderer: &Mutex<Renderer>,
    state: &mut ClientState,
    pending: &Pending,
    at: (f64, f64),
) -> bool {
    let mut scene = state.scene.clone();
    if let Some(list) = viewer.labels() {
        scene = list.visible(&scene);
    }
    let answer = {
        let mut r = renderer.lock().unwrap_or_else(|e| e.into_inner());
        state.marks.pick(&mut r, &scene, at)
    };
    let msg = answer.unwrap_or_else(|e| ServerMessage::Error {
        message: glint_io::one_line(&e),
    });
    if !send_json(socket, &msg).await {
        return false;
    }
    match &pending.shown {
        Some((shown, seq)) if !state.marks.is_empty() => {
            send_json(socket, &state.marks.projected(shown, *seq)).await
        }
        _ => true,
    }
}

async fn connection(mut socket: WebSocket, viewer: Arc<Viewer>) {
    let mut stages = viewer.refined.subscribe();
    let stage = stages.borrow_and_update().clone();
    let Some(_seat) = admit(&mut socket, &viewer, stage.as_deref()).await else {
        return;
    };
    let (renderer, cancel) = client_renderer(&viewer, stage.as_deref());
    // What this client's `path` drag frames cost: their size follows it.
    let drag = Arc::new(Mutex::new(DragCost::default()));
    // The finer level, read since and not yet swapped in (when the camera rests).
    let mut finer: Option<Arc<Stage>> = None;
    // What the frame in flight is for, and whether it refines a `path` state: any
    // message stops a refinement (issue 29), a change of the scene or split any other
    // full frame; a drag's reduced frames are left to finish (each input of a drag
    // would stop the last and none would be shown; they are small and bounded).
    let mut inflight_for: Option<(Purpose, bool)> = None;
    // The client leaving (any return below) stops the frame in flight.
    let _stop = StopOnDrop(cancel.clone());
    let mut state = ClientState {
        scene: viewer.scene.clone(),
        split: Split::Off,
        seq: 0,
        marks: pick::Marks::default(),
    };
    let mut pending = Pending {
        schedule: Schedule::default(),
        shown: None,
    };
    let mut inflight: Option<FrameJob> = None;
    let mut recording = record::Recording::idle();
    loop {
        if inflight.is_none() && pending.schedule.resting() {
            if let Some(stage) = finer.take() {
                if !swap_level(&mut socket, &renderer, &cancel, &stage).await {
                    return;
                }
                pending.schedule.restart();
            }
        }
        if inflight.is_none() {
            if let Some(purpose) = pending.schedule.take() {
                inflight_for = Some((purpose, state.progressive().is_some()));
                let job = spawn_frame(
                    &viewer,
                    (&renderer, &drag),
                    &cancel,
                    &state,
                    purpose,
                    &pending.schedule,
                );
                inflight = Some(job);
            }
        }
        tokio::select! {
            msg = socket.recv() => {
                let Some(Ok(msg)) = msg else { return };
                let text = match msg {
                    Message::Text(t) => t,
                    Message::Close(_) => return,
                    Message::Binary(_) => {
                        let message = "binary messages are not accepted: send JSON text".into();
                        if !send_json(&mut socket, &ServerMessage::Error { message }).await { return }
                        continue;
                    }
                    _ => continue,
                };
                if inflight.is_some() && stops(inflight_for, text.as_str()) {
                    cancel.store(true, Ordering::Relaxed);
                }
                let outcome = {
                    let r = renderer.lock().unwrap_or_else(|e| e.into_inner());
                    state.handle(text.as_str(), &r, &viewer)
                };
                match outcome {
                    Ok(Action::Render { interactive }) => {
                        let now = std::time::Instant::now();
                        pending.schedule.input(interactive, now, viewer.config.settle);
                    }
                    Ok(Action::Save) => pending.schedule.save(),
                    Ok(Action::Record(frames, format)) => {
                        let mine = renderer.lock().unwrap_or_else(|e| e.into_inner()).clone();
                        let scene = viewer.labels().map_or_else(|| state.scene.clone(), |l| l.visible(&state.scene));
                        if let Err(e) = recording.start(mine, scene, frames, &format) {
                            if !send_json(&mut socket, &ServerMessage::Error { message: e.to_string() }).await { return }
                        }
                    }
                    Ok(Action::Pick(x, y)) => {
                        if !answer_pick(&mut socket, &viewer, &renderer, &mut state, &pending, (x, y)).await { return }
                    }
                    Ok(Action::Unmarked) => {
                        let msg = ServerMessage::Marks { seq: state.seq, points: Vec::new(), distance_mm: None };
                        if !send_json(&mut socket, &msg).await { return }
                    }
                    Err(e) => {
                        let message = glint_io::one_line(&e);
                        if !send_json(&mut socket, &ServerMessage::Error { message }).await { return }
                    }
                }
            }
            done = async { inflight.as_mut().expect("guarded").await }, if inflight.is_some() => {
                inflight = None;
                if !finished(&mut socket, &viewer, &state, &mut pending, done).await { return }
            }
            _ = tokio::time::sleep_until(settle_instant(&pending.schedule)), if pending.schedule.settle_at().is_some() => {
                // Tokio's timer never wakes early; were it to, the loop sleeps again.
                pending.schedule.settled(std::time::Instant::now());
            }
            event = recording.next() => if !record::forward(&mut socket, event).await { return },
            Ok(()) = stages.changed() => finer = stages.borrow_and_update().clone(),
        }
    }
}

/// Whether message `text` stops the frame in flight, made for `inflight` (its
/// purpose, and whether it refines a `path` state): any message stops a refinement, a
/// change of the scene or of the split another full frame; nothing stops a drag's
/// reduced frame or a save.
fn stops(inflight: Option<(Purpose, bool)>, text: &str) -> bool {
    match inflight {
        Some((Purpose::Full, true)) => true,
        Some((Purpose::Full, false)) => matches!(
            serde_json::from_str::<ClientMessage>(text),
            Ok(ClientMessage::Update { .. } | ClientMessage::Split { .. })
        ),
        _ => false,
    }
}

/// Sets a client's cancel flag when dropped: its connection ended, so the frame it
/// has in flight on the blocking pool stops (at its next tile or row) instead of
/// running on for nobody.
struct StopOnDrop(Arc<AtomicBool>);

impl Drop for StopOnDrop {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Relaxed);
    }
}

/// When the drag's full frame is due, on tokio's clock (now when none is due).
fn settle_instant(schedule: &Schedule) -> tokio::time::Instant {
    schedule
        .settle_at()
        .map_or_else(tokio::time::Instant::now, tokio::time::Instant::from_std)
}

/// One client's scene, split mode and last event number.
#[derive(Clone)]
struct ClientState {
    scene: Scene,
    split: Split,
    seq: u32,
    /// Picked points (a point, or a ruler's ends).
    marks: pick::Marks,
}

/// What a client message asks for.
enum Action {
    Render {
        interactive: bool,
    },
    Save,
    /// Pick and mark the pixel at `(x, y)` of the full-resolution image.
    Pick(f64, f64),
    /// Tell the page the marks are gone.
    Unmarked,
    /// Record a turntable: frames, format.
    Record(u32, String),
}

impl ClientState {
    /// The sample count a progressive state refines to: a `path` scene shown alone
    /// (split views render both images to the full count at once).
    fn progressive(&self) -> Option<u32> {
        let lighting = &self.scene.lighting;
        (lighting.model == LightingModel::Path && self.split == Split::Off)
            .then(|| lighting.spp.unwrap_or(DEFAULT_SPP))
    }

    fn handle(
        &mut self,
        text: &str,
        renderer: &Renderer,
        viewer: &Viewer,
    ) -> Result<Action, ViewError> {
        let config = &viewer.config;
        if text.len() > config.max_message_bytes {
            return Err(ViewError::Message(format!(
                "message of {} bytes refused: at most {}",
                text.len(),
                config.max_message_bytes
            )));
        }
        let msg: ClientMessage = serde_json::from_str(text)
            .map_err(|e| ViewError::Message(format!("bad message: {e}")))?;
        match msg {
            ClientMessage::Update {
                seq,
                interactive,
                scene,
            } => {
                self.scene = apply_patch(renderer, &self.scene, &scene, viewer.labels())?;
                self.seq = seq;
                Ok(Action::Render { interactive })
            }
            ClientMessage::Split { split } => {
                self.split = split;
                Ok(Action::Render { interactive: false })
            }
            ClientMessage::Save {} => Ok(Action::Save),
            ClientMessage::Pick { .. } if self.split != Split::Off => Err(ViewError::Message(
                "picking needs the single view: set split to off".into(),
            )),
            ClientMessage::Pick { x, y } => Ok(Action::Pick(x, y)),
            ClientMessage::Record { frames, format } => Ok(Action::Record(frames, format)),
            ClientMessage::Unmark {} => {
                self.marks.clear();
                Ok(Action::Unmarked)
            }
        }
    }
}
