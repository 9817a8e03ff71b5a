//! `glint view`: the interactive viewer in the browser (a local web server).

use std::net::IpAddr;
use std::sync::Arc;

use anyhow::Context;
use glint_render::SceneLobe;
use glint_view::{Viewer, ViewerConfig};

use super::choice::choice;
use super::scene_flags::SceneFlags;

/// Arguments of `glint view`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    glint view                                   # the built-in phantom\n  \
    glint view brain.nii.gz --preset mr-t2-brain\n  \
    glint view --scene brain.json --port 9000\n\n\
Open the printed URL in a browser: drag to orbit, wheel to zoom, the panel sets the\n\
preset, mode, lobe, n, v, geometry, light and split view (exact | lobe, or their\n\
difference); Save downloads the scene (for glint render --scene) and a PNG.")]
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
    /// Address to listen on; the default serves this machine only.
    #[arg(long, default_value = "127.0.0.1")]
    host: IpAddr,
    /// Clients served at once.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u64).range(1..=64))]
    max_clients: u64,
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
    eprintln!("glint view: loading the volume");
    let viewer = Arc::new(Viewer::new(scene, config)?);
    let runtime = tokio::runtime::Runtime::new().context("starting the server runtime")?;
    runtime.block_on(async {
        let listener = tokio::net::TcpListener::bind((args.host, args.port))
            .await
            .with_context(|| format!("cannot listen on {}:{}", args.host, args.port))?;
        let addr = listener.local_addr()?;
        println!("glint view: open http://{addr}/ (Ctrl-C to stop)");
        glint_view::serve(listener, viewer)
            .await
            .context("the server stopped")
    })
}
