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

/// The protocol side, without a browser: the histogram follows `hello`; a
/// `window_level` patch comes back in the frame's scene and as the scene message's
/// `window_level`; a bad window is refused with one line and the session goes on.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn histogram_and_window_level_over_the_socket() {
    use futures_util::{SinkExt, StreamExt};
    use tokio_tungstenite::tungstenite::Message;
    let scene = Scene {
        mode: RenderMode::Mip,
        ..Scene::phantom(Phantom::SheppLogan, 32, [48, 40])
    };
    let viewer = Arc::new(Viewer::new(scene, ViewerConfig::default()).unwrap());
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let url = format!("ws://{}/ws", listener.local_addr().unwrap());
    let access = Arc::new(Access::new(listener.local_addr().unwrap(), None).unwrap());
    tokio::spawn(glint_view::serve(listener, viewer, access));
    let (mut c, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    let mut texts = Vec::new();
    // The JSON messages up to (and including) the first one of type `kind`.
    async fn until(
        c: &mut (impl StreamExt<Item = Result<Message, tokio_tungstenite::tungstenite::Error>> + Unpin),
        kind: &str,
        texts: &mut Vec<serde_json::Value>,
    ) -> serde_json::Value {
        loop {
            let msg = tokio::time::timeout(std::time::Duration::from_secs(20), c.next())
                .await
                .expect("a message within 20 s")
                .unwrap()
                .unwrap();
            if let Message::Text(t) = msg {
                let v: serde_json::Value = serde_json::from_str(&t).unwrap();
                texts.push(v.clone());
                if v["type"] == kind {
                    return v;
                }
            }
        }
    }
    let h = until(&mut c, "histogram", &mut texts).await;
    assert_eq!(texts[0]["type"], "hello", "the histogram follows hello");
    let bins = h["log_counts"].as_array().unwrap();
    assert_eq!(bins.len(), glint_view::HISTOGRAM_BINS);
    assert_eq!(h["counted"], 32 * 32 * 32);
    let total: f64 = bins.iter().map(|b| b.as_f64().unwrap().exp_m1()).sum();
    assert!((total - 32768.0).abs() < 1.0, "{total}");
    let first = until(&mut c, "scene", &mut texts).await;
    let own = first["window_level"]["window"].as_f64().unwrap();
    assert!(own > 0.0, "{first}");
    let send = |text: &str| Message::Text(text.to_string().into());
    c.send(send(
        r#"{"type": "update", "seq": 1, "scene": {"window_level": {"window": 0.2, "level": 0.3}}}"#,
    ))
    .await
    .unwrap();
    let s = until(&mut c, "scene", &mut texts).await;
    assert_eq!(s["seq"], 1);
    assert_eq!(
        s["scene"]["window_level"],
        serde_json::json!({"window": 0.2, "level": 0.3})
    );
    let wl = &s["window_level"];
    assert!((wl["window"].as_f64().unwrap() - 0.2).abs() < 1e-9, "{s}");
    assert!((wl["level"].as_f64().unwrap() - 0.3).abs() < 1e-9, "{s}");
    c.send(send(
        r#"{"type": "update", "seq": 2, "scene": {"window_level": {"window": -1, "level": 0}}}"#,
    ))
    .await
    .unwrap();
    let e = until(&mut c, "error", &mut texts).await;
    let message = e["message"].as_str().unwrap();
    assert!(
        message.contains("window -1") && !message.contains('\n'),
        "{message}"
    );
    c.send(send(
        r#"{"type": "update", "seq": 3, "scene": {"camera": {"azimuth": 10}}}"#,
    ))
    .await
    .unwrap();
    let s = until(&mut c, "scene", &mut texts).await;
    assert_eq!(s["seq"], 3);
    assert_eq!(
        s["scene"]["window_level"]["window"], 0.2,
        "the refused window changed nothing"
    );
}
