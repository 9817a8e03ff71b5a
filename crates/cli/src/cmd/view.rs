//! `glint view`: the interactive viewer in the browser (a local web server).

use std::net::IpAddr;
use std::sync::Arc;

use anyhow::Context;
use glint_io::zarr::Level;
use glint_render::SceneLobe;
use glint_view::{Access, Token, Viewer, ViewerConfig};

use super::choice::choice;
use super::scene_flags::SceneFlags;

/// Arguments of `glint view`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    glint view                                   # the built-in phantom\n  \
    glint view brain.nii.gz --preset mr-t2-brain\n  \
    glint view --scene brain.json --port 9000\n  \
    glint view ct.nii.gz --labels seg.nii.gz --labels-as volume\n  \
    glint view stack.zarr                        # OME-Zarr: coarse level first\n\n\
Open the printed URL in a browser: drag to orbit, wheel to zoom, the panel sets the\n\
preset, mode, lobe, n, v, geometry, light and split view (exact | lobe, or their\n\
difference); Save downloads the scene (for glint render --scene) and a PNG. With\n\
--labels, a Labels panel toggles each label by name (all/none). An OME-Zarr store is\n\
read at --level auto unless --level is given, coarse first: its coarsest level is\n\
shown at once, the auto level replaces it when read and the camera rests.\n\n\
Access: only the viewer's own page may use it. A request must name this machine\n\
(localhost, a loopback address or the --host address, with the port; else 421), and a\n\
WebSocket opened by a page of any other origin is refused (403); clients that send no\n\
Origin (scripts) are let through. On an address other than loopback the URL carries a\n\
token, random unless --token sets it, without which the page and its socket are\n\
refused (403); there is no way to turn it off. The token travels in clear: on a network\n\
you do not trust, serve loopback and forward the port over SSH with the same number on\n\
both ends (ssh -L 8080:127.0.0.1:8080 host).")]
pub struct Args {
    // Boxed: the options are many, and main's subcommand enum should stay small.
    #[command(flatten)]
    scene: Box<SceneFlags>,
    /// Lobe to start with (hw: the unit of --hw-config) [default: k].
    #[arg(long, value_parser = choice::<SceneLobe>(SceneLobe::ALL.map(|k| k.name())))]
    lobe: Option<SceneLobe>,
    /// Port to listen on (0 picks a free one).
    #[arg(long, default_value_t = 8080)]
    port: u16,
    /// Address to listen on; the default serves this machine only. Any other address
    /// needs a token, printed in the URL.
    #[arg(long, default_value = "127.0.0.1")]
    host: IpAddr,
    /// The token the URL carries, on any address (16 to 256 of A-Z a-z 0-9 - . _ ~;
    /// other users of this machine can read it in the process list) [default: none on
    /// loopback, 192 random bits otherwise].
    #[arg(long, value_name = "TOKEN", value_parser = parse_token)]
    token: Option<Token>,
    /// Clients served at once.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u64).range(1..=64))]
    max_clients: u64,
    /// Of the reader's notes (what a DICOM directory's read skipped, where the affine
    /// came from), only its warnings.
    #[arg(short, long)]
    quiet: bool,
}

/// Runs `glint view` until interrupted.
pub fn run(args: Args) -> anyhow::Result<()> {
    let mut scene = args.scene.scene()?;
    if let Some(kind) = args.lobe {
        args.scene.set_lobe(&mut scene, kind);
    }
    // Saved scenes name their files absolutely, so they render from anywhere.
    let scene = scene.with_absolute_paths()?;
    let config = ViewerConfig {
        max_clients: args.max_clients as usize,
        ..ViewerConfig::default()
    };
    // An OME-Zarr pyramid is shown coarse first: its coarsest level at once, then the
    // auto level (at least one voxel per pixel), read in the background.
    let mut options = args.scene.read_options();
    if args.scene.level.is_none() {
        options.level = Level::Auto(scene.size[0].max(scene.size[1]) as usize);
    }
    eprintln!("glint view: loading the volume");
    let input = match &scene.input {
        glint_render::Input::Path(p) => Some(p.clone()),
        _ => None,
    };
    let viewer = Arc::new(Viewer::with_options(scene, config, &options)?);
    if let Some(path) = &input {
        super::render::print_notes(path, viewer.notes(), args.quiet);
    }
    if let Some(level) = viewer.level().filter(|l| l.coarse) {
        eprintln!(
            "glint view: showing level {} ({}x{}x{}) while the finer one is read",
            level.level, level.dims[0], level.dims[1], level.dims[2]
        );
        let v = viewer.clone();
        std::thread::spawn(move || {
            match v.refine() {
            Ok(Some(l)) => eprintln!(
                "glint view: level {} ({}x{}x{}) read; each client switches to it when its camera rests",
                l.level, l.dims[0], l.dims[1], l.dims[2]
            ),
            Ok(None) => {}
            Err(e) => eprintln!(
                "glint view: the finer level could not be read, the coarse one stays: {}",
                glint_io::one_line(&e)
            ),
        }
        });
    }
    let runtime = tokio::runtime::Runtime::new().context("starting the server runtime")?;
    runtime.block_on(async {
        let listener = tokio::net::TcpListener::bind((args.host, args.port))
            .await
            .with_context(|| format!("cannot listen on {}:{}", args.host, args.port))?;
        let addr = listener.local_addr()?;
        let token = match args.token {
            None if !glint_view::is_loopback(addr.ip()) => Some(Token::random()?),
            t => t,
        };
        let access = Arc::new(Access::new(addr, token)?);
        if !access.loopback() {
            eprintln!(
                "glint view: serving on a non-loopback address: the URL carries a token; \
                 anyone with it can see the volume"
            );
            if addr.ip().is_unspecified() {
                eprintln!(
                    "glint view: from another machine, use this machine's address in the URL"
                );
            }
        }
        println!("glint view: open {} (Ctrl-C to stop)", access.url());
        glint_view::serve(listener, viewer, access)
            .await
            .context("the server stopped")
    })
}

/// `--token`: the viewer's rule (one line, for clap's error).
fn parse_token(s: &str) -> Result<Token, String> {
    s.parse().map_err(|e: glint_view::ViewError| e.to_string())
}
