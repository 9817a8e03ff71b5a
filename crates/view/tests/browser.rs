//! The page in a real browser: Debian's headless Chromium, driven by playwright-core
//! (crates/view/browser/drive.mjs), loads the viewer, waits for the first frame,
//! drags, checks that the canvas changed and saves a screenshot. The viewer has a token,
//! so the page works only if it carries the token from its URL to its socket; then a
//! page of another origin (a second server, on `localhost` and another port) tries the
//! socket, token and all, and must be refused by the server (counted by
//! [`Access::refused`], so a browser that blocked the attempt itself would not pass
//! for the server). Needs `node`,
//! `chromium` (scripts/install-deps) and `npm ci` in crates/view/browser (scripts/test);
//! in strict mode (`GLINT_STRICT` or `CI` set) a missing piece fails the test.

use std::path::Path;
use std::process::Command;
use std::sync::Arc;

use glint_render::{Input, Lighting, LightingModel, Phantom, Scene};
use glint_view::{Access, Token, Viewer, ViewerConfig};

#[test]
fn the_page_shows_frames_and_dragging_turns_the_volume() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("browser");
    if !glint_testkit::browser_tools(&dir) {
        return;
    }
    let runtime = tokio::runtime::Runtime::new().unwrap();
    let scene = Scene::phantom(Phantom::SheppLogan, 64, [256, 256]);
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
    glint_testkit::ran("chromium + node (view browser test)");
}

/// A path in the target directory's tmp folder (kept for inspection).
fn tempfile_path(name: &str) -> std::path::PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"));
    dir.join(name)
}

#[test]
fn a_path_scene_refines_while_the_mouse_is_still_and_a_drag_restarts_it() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("browser");
    if !glint_testkit::browser_tools(&dir) {
        return;
    }
    let runtime = tokio::runtime::Runtime::new().unwrap();
    let scene = Scene {
        lighting: Lighting {
            model: LightingModel::Path,
            spp: Some(64),
            ..Lighting::default()
        },
        ..Scene::phantom(Phantom::SheppLogan, 48, [128, 128])
    };
    let viewer = Arc::new(Viewer::new(scene, ViewerConfig::default()).unwrap());
    let listener = runtime
        .block_on(tokio::net::TcpListener::bind("127.0.0.1:0"))
        .unwrap();
    let access = Arc::new(Access::new(listener.local_addr().unwrap(), None).unwrap());
    let url = access.url();
    runtime.spawn(glint_view::serve(listener, viewer, access));
    let out = Command::new("node")
        .current_dir(&dir)
        .args(["drive.mjs", "progressive", &url])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "drive.mjs failed: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    let n = |k: &str| report[k].as_u64().unwrap();
    assert!(n("grown") > n("first"), "{report}");
    assert_eq!(report["restarted"], true, "{report}");
    assert!(n("regrown") > 1, "{report}");
    assert!(n("grown") <= 64 && n("regrown") <= 64, "{report}");
    // Issue 42: the panel's environment map, turned by an Alt-drag, camera unmoved.
    assert_eq!(report["envOk"], true, "{report}");
    assert_eq!(report["env"]["rotation"], 25, "{report}");
    // The area key light from the panel: a 40 mm sphere 300 mm towards the eye, then off.
    assert_eq!(report["env"]["keyOk"], true, "{report}");
    assert!(
        report["text"]
            .as_str()
            .unwrap()
            .contains("samples per pixel"),
        "{report}"
    );
    eprintln!("progressive browser test: {report}");
}

/// Issue 33: the legend of a label map in the page: a checkbox per label; unticking
/// one changes the canvas, "all" brings the first image back.
#[test]
fn the_legend_toggles_labels_by_name() {
    use glint_io::{nifti, Endian, Samples, Volume};
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("browser");
    if !glint_testkit::browser_tools(&dir) {
        return;
    }
    // Two blocks side by side, FreeSurfer's 17 and 18, over the same file as a volume.
    let n = 16;
    let values: Vec<u8> = (0..n * n * n)
        .map(|i| {
            let (x, y, z) = (i % n, i / n % n, i / (n * n));
            let inside = (5..11).contains(&y) && (5..11).contains(&z);
            match x {
                2..=7 if inside => 17,
                8..=13 if inside => 18,
                _ => 0,
            }
        })
        .collect();
    let path = tempfile_path("aseg-legend.nii");
    let vol = Volume::new([n; 3], [1.0; 3], Samples::U8(values)).unwrap();
    nifti::write(&path, &vol, false, Endian::Little).unwrap();
    let scene = Scene {
        input: Input::Path(path.clone()),
        labels: Some(glint_render::LabelSpec::new(&path)),
        size: [128, 128],
        ..Scene::default()
    };
    let runtime = tokio::runtime::Runtime::new().unwrap();
    let viewer = Arc::new(Viewer::new(scene, ViewerConfig::default()).unwrap());
    let listener = runtime
        .block_on(tokio::net::TcpListener::bind("127.0.0.1:0"))
        .unwrap();
    let access = Arc::new(Access::new(listener.local_addr().unwrap(), None).unwrap());
    let url = access.url();
    runtime.spawn(glint_view::serve(listener, viewer, access));
    let out = Command::new("node")
        .current_dir(&dir)
        .args(["drive.mjs", "labels", &url])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "drive.mjs failed: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    let rows: Vec<&str> = report["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r.as_str().unwrap())
        .collect();
    assert_eq!(rows.len(), 2, "{report}");
    assert!(
        rows[0].contains("Left-Hippocampus") && rows[0].contains("216"),
        "{report}"
    );
    assert!(rows[1].contains("Left-Amygdala"), "{report}");
    assert_eq!(report["changed"], true, "{report}");
    assert_eq!(report["restored"], true, "{report}");
    eprintln!("legend browser test: {report}");
}

/// Issue 31: the page of a pyramid shown coarse first says the coarse level in its
/// status with the first frame, then the finer one with a later frame.
#[test]
fn the_page_shows_the_pyramid_level_coarse_first() {
    use glint_io::zarr::Level;
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("browser");
    if !glint_testkit::browser_tools(&dir) {
        return;
    }
    let store = Path::new(env!("CARGO_MANIFEST_DIR")).join("../io/tests/data/zarr/v04-blosc.zarr");
    let scene = Scene {
        input: Input::Path(store),
        size: [64, 64],
        ..Scene::default()
    };
    let options = glint_io::ReadOptions {
        level: Level::Auto(64),
        ..glint_io::ReadOptions::default()
    };
    let viewer = Arc::new(Viewer::with_options(scene, ViewerConfig::default(), &options).unwrap());
    let runtime = tokio::runtime::Runtime::new().unwrap();
    let listener = runtime
        .block_on(tokio::net::TcpListener::bind("127.0.0.1:0"))
        .unwrap();
    let access = Arc::new(Access::new(listener.local_addr().unwrap(), None).unwrap());
    let url = access.url();
    runtime.spawn(glint_view::serve(listener, viewer.clone(), access));
    // The finer level is read once the page is seated (its hello already said the
    // coarse level, and its first frame is drawn from it).
    let v = viewer.clone();
    let refine = std::thread::spawn(move || {
        let start = std::time::Instant::now();
        while v.clients() == 0 && start.elapsed().as_secs() < 120 {
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        v.refine()
    });
    let out = Command::new("node")
        .current_dir(&dir)
        .args(["drive.mjs", "levels", &url])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "drive.mjs failed: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(refine.join().unwrap().unwrap().is_some());
    let report: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    assert_eq!(report["first"]["level"], 4, "{report}");
    let first = report["first"]["status"].as_str().unwrap();
    assert!(
        first.contains("level 4 of 0–4 (4×3×10), loading a finer one"),
        "{report}"
    );
    assert_eq!(report["later"]["level"], 0, "{report}");
    let later = report["later"]["status"].as_str().unwrap();
    assert_eq!(later, "level 0 of 0–4 (64×48×10)", "{report}");
    eprintln!("levels browser test: {report}");
}
