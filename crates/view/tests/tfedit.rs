//! Issue 43 item 3 in a real browser: window/level by right- or shift-drag on the
//! image, and the transfer-function editor over the histogram (add, move, delete a
//! point), driven by crates/view/browser/tfedit.mjs in Debian's headless Chromium and
//! checked on the frames. Needs `node`, `chromium` and `npm ci` in crates/view/browser
//! (scripts/test); in strict mode (`GLINT_STRICT` or `CI` set) a missing piece fails.

use std::path::Path;
use std::process::Command;
use std::sync::Arc;

use glint_render::{Phantom, RenderMode, Scene, TransferFunction};
use glint_view::{Access, Viewer, ViewerConfig};

/// Serves `scene` and runs `node tfedit.mjs MODE URL`; its JSON report.
fn drive(mode: &str, scene: Scene) -> Option<serde_json::Value> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("browser");
    if !glint_testkit::browser_tools(&dir) {
        return None;
    }
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
        .args(["tfedit.mjs", mode, &url])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "tfedit.mjs {mode} failed: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some(serde_json::from_str(stdout.trim()).unwrap())
}

/// A MIP of the Shepp-Logan phantom (the grey ramp over its range): raising the level
/// darkens the frame, lowering it brightens it, narrowing the window raises the
/// contrast, and the camera stays where it was.
#[test]
fn dragging_on_the_image_sets_window_and_level() {
    let scene = Scene {
        mode: RenderMode::Mip,
        ..Scene::phantom(Phantom::SheppLogan, 64, [256, 256])
    };
    let Some(report) = drive("wl", scene) else {
        return;
    };
    assert_eq!(report["fail"], serde_json::json!([]), "{report}");
    let level = |i: usize| report["wl"][i]["level"].as_f64().unwrap();
    assert!(level(1) > level(0) && level(2) < level(0), "{report}");
    assert_eq!(report["camera_kept"], true, "{report}");
    eprintln!("window/level browser test: {report}");
}

/// A composite scene with a faint two-point ramp: clicking the editor at the brain's
/// value (0.2) adds an opaque point (brighter frame), dragging it down makes it faint
/// (darker), a double click deletes it (the first frame again, byte for byte).
#[test]
fn the_editor_adds_moves_and_deletes_points() {
    let tf = TransferFunction::from_flat(&[0.0, 0.0, 1.0, 0.05], &[0.0, 1.0, 1.0, 1.0]).unwrap();
    let mut scene = Scene::phantom(Phantom::SheppLogan, 64, [256, 256]);
    scene.set_transfer_function(tf);
    let Some(report) = drive("edit", scene) else {
        return;
    };
    assert_eq!(report["fail"], serde_json::json!([]), "{report}");
    assert_eq!(
        report["points"],
        serde_json::json!([2, 3, 3, 2]),
        "{report}"
    );
    assert_eq!(report["restored"], true, "{report}");
    eprintln!("transfer-function editor browser test: {report}");
}
