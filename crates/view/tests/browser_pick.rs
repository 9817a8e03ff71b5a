//! Picking and measuring in a real browser (crates/view/browser/pick.mjs, headless
//! Chromium through playwright-core, as tests/browser.rs): a click on an analytic
//! ball marks the point of its surface it shows, a second click draws a ruler whose
//! length is the distance between the two points, both checked on the overlay's
//! pixels, and the marks follow the camera when it turns. Needs `node`, `chromium`
//! and `npm ci` in crates/view/browser; in strict mode a missing piece fails.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

use glint_io::{nifti, Endian, Samples, Volume};
use glint_render::{Input, RenderMode, Scene};
use glint_view::{Access, Viewer, ViewerConfig};
use serde_json::Value;

/// Grid edge, voxel size (mm) and radius (mm) of the ball; its value is the depth
/// below its surface, mm.
const N: usize = 40;
const SPACING: f64 = 1.0;
const R: f64 = 15.0;

fn centre() -> f64 {
    SPACING * (N - 1) as f64 / 2.0
}

/// The ball written as NIfTI into the test's temporary folder.
fn ball() -> PathBuf {
    let mut values = Vec::with_capacity(N * N * N);
    for k in 0..N {
        for j in 0..N {
            for i in 0..N {
                let d2: f64 = [i, j, k]
                    .iter()
                    .map(|&x| (x as f64 * SPACING - centre()).powi(2))
                    .sum();
                values.push((R - d2.sqrt()) as f32);
            }
        }
    }
    let vol = Volume::new([N; 3], [SPACING; 3], Samples::F32(values)).unwrap();
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join("glint-pick-ball.nii");
    nifti::write(&path, &vol, false, Endian::Little).unwrap();
    path
}

fn world(v: &Value) -> [f64; 3] {
    [0, 1, 2].map(|a| v["world_mm"][a].as_f64().unwrap())
}

#[test]
fn a_click_marks_the_point_and_a_second_draws_a_ruler_of_its_length() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("browser");
    if !glint_testkit::browser_tools(&dir) {
        return;
    }
    let runtime = tokio::runtime::Runtime::new().unwrap();
    let scene = Scene {
        input: Input::Path(ball()),
        mode: RenderMode::Iso,
        iso: Some(0.0),
        size: [256, 256],
        ..Scene::default()
    };
    let viewer = Arc::new(Viewer::new(scene, ViewerConfig::default()).unwrap());
    let listener = runtime
        .block_on(tokio::net::TcpListener::bind("127.0.0.1:0"))
        .unwrap();
    let access = Arc::new(Access::new(listener.local_addr().unwrap(), None).unwrap());
    let url = access.url();
    runtime.spawn(glint_view::serve(listener, viewer, access));
    let shot = Path::new(env!("CARGO_TARGET_TMPDIR")).join("glint-view-pick.png");
    let out = Command::new("node")
        .current_dir(&dir)
        .args(["pick.mjs", &url, shot.to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "pick.mjs failed: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Value = serde_json::from_str(stdout.trim()).unwrap();
    // Both clicks show the ball's surface: points on the sphere, on the side facing
    // the (anterior, +y) camera.
    let (a, b) = (world(&report["first"]), world(&report["second"]));
    for (p, what) in [(a, "first"), (b, "second")] {
        assert_eq!(report[what]["object"]["kind"], "volume", "{report}");
        let r = p.iter().map(|x| (x - centre()).powi(2)).sum::<f64>().sqrt();
        assert!(
            (r - R).abs() < SPACING / 2.0,
            "{what} pick {p:?} is off the sphere: {report}"
        );
        assert!(
            p[1] > centre(),
            "{what} pick {p:?} is on the far side: {report}"
        );
    }
    // The ruler's length is the distance between them, and the panel shows it.
    let distance = (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt();
    let reported = report["distance_mm"].as_f64().unwrap();
    assert!((reported - distance).abs() < 1e-6, "{distance} vs {report}");
    assert!(distance > 3.0, "the clicks were apart: {report}");
    let ruler = report["ruler"].as_str().unwrap();
    assert!(ruler.contains(&format!("{distance:.2} mm")), "{ruler}");
    // Drawn: the marker, the ruler's middle; nothing in a far corner; after a drag
    // the marks moved with the camera and are drawn where they moved to.
    for key in ["marker", "middle", "follows"] {
        assert!(
            report[key].as_u64().unwrap() > 0,
            "{key} not drawn: {report}"
        );
    }
    assert_eq!(report["corner"], 0, "{report}");
    assert_ne!(report["before"][0], report["after"][0], "{report}");
    eprintln!("browser pick test: {report}; screenshot {}", shot.display());
    glint_testkit::ran("chromium + node (view pick browser test)");
}
