//! The page in a real browser: Debian's headless Chromium, driven by playwright-core
//! (crates/view/browser/drive.mjs), loads the viewer, waits for the first frame,
//! drags, checks that the canvas changed and saves a screenshot. The viewer has a token,
//! so the page works only if it carries the token from its URL to its socket; then a
//! page of another origin (a second server, on `localhost` and another port) tries the
//! socket, token and all, and must be refused by the server (counted by
//! [`Access::refused`], so a browser that blocked the attempt itself would not pass
//! for the server). Needs `node`,
//! `chromium` (scripts/install-deps) and `npm ci` in crates/view/browser (scripts/test);
//! with CI set, a missing piece fails the test.

use std::path::Path;
use std::process::Command;
use std::sync::Arc;

use glint_render::{Input, Phantom, Scene};
use glint_view::{Access, Token, Viewer, ViewerConfig};

fn ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false" && v != "0")
}

/// Whether the browser, node and playwright-core are here; in CI they must be.
fn tools_present(dir: &Path) -> bool {
    let chromium = std::env::var("CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
    let missing: Vec<&str> = [
        (
            !Path::new(&chromium).exists(),
            "chromium (scripts/install-deps)",
        ),
        (
            Command::new("node").arg("--version").output().is_err(),
            "node",
        ),
        (
            !dir.join("node_modules/playwright-core").is_dir(),
            "playwright-core (npm ci in crates/view/browser)",
        ),
    ]
    .into_iter()
    .filter_map(|(gone, what)| gone.then_some(what))
    .collect();
    if missing.is_empty() {
        return true;
    }
    assert!(!ci(), "missing in CI: {}", missing.join(", "));
    eprintln!("skipping the browser test: missing {}", missing.join(", "));
    false
}

#[test]
fn the_page_shows_frames_and_dragging_turns_the_volume() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("browser");
    if !tools_present(&dir) {
        return;
    }
    let runtime = tokio::runtime::Runtime::new().unwrap();
    let scene = Scene {
        input: Input::Phantom {
            name: Phantom::SheppLogan,
            size: 64,
        },
        size: [256, 256],
        ..Scene::default()
    };
    let viewer = Arc::new(Viewer::new(scene, ViewerConfig::default()).unwrap());
    let listener = runtime
        .block_on(tokio::net::TcpListener::bind("127.0.0.1:0"))
        .unwrap();
    let token = Token::random().unwrap();
    let access = Arc::new(Access::new(listener.local_addr().unwrap(), Some(token)).unwrap());
    let url = access.url();
    assert!(url.contains("?token="), "{url}");
    runtime.spawn(glint_view::serve(listener, viewer, access.clone()));
    let foreign = runtime
        .block_on(tokio::net::TcpListener::bind("127.0.0.1:0"))
        .unwrap();
    let foreign_url = format!("http://localhost:{}/", foreign.local_addr().unwrap().port());
    let page = axum::Router::new().route(
        "/",
        axum::routing::get(|| async {
            axum::response::Html("<!doctype html><title>another site</title>")
        }),
    );
    runtime.spawn(async move { axum::serve(foreign, page).await });
    let shot = tempfile_path("glint-view-browser.png");
    let out = Command::new("node")
        .current_dir(&dir)
        .args([
            "drive.mjs",
            "test",
            &url,
            shot.to_str().unwrap(),
            &foreign_url,
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "drive.mjs failed: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    assert_eq!(report["changed"], true, "{report}");
    assert!(report["full"].as_u64().unwrap() >= 2, "{report}");
    assert_eq!(report["foreign"], "refused", "{report}");
    assert!(
        access.refused() >= 1,
        "the server refused nothing: {report}"
    );
    let png = std::fs::read(&shot).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    eprintln!("browser test: {report}; screenshot {}", shot.display());
}

/// A path in the target directory's tmp folder (kept for inspection).
fn tempfile_path(name: &str) -> std::path::PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"));
    dir.join(name)
}
