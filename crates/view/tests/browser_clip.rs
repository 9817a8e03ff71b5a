//! Cutting in a real browser (crates/view/browser/clip.mjs, headless Chromium through
//! playwright-core, as tests/browser.rs): the "Cut" panel's crop box is ticked and
//! its x max slider dragged to the middle of a ball's volume shown in MIP, facing
//! the camera; on the frames, the cut half of the image goes dark and the other half
//! is unchanged, the overlay draws the box's edges over the half kept, and the
//! server's scene holds the crop; the clip plane's handle, dragged on the image,
//! moves the plane along its normal without turning the camera, and so does a crop box
//! face's handle (the strip it cuts away goes dark on the frames); the "record"
//! button brings a turntable GIF of the scene, decoded here. Needs `node`, `chromium` and `npm ci` in
//! crates/view/browser; in strict mode a missing piece fails.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

use glint_io::{nifti, Endian, Samples, Volume};
use glint_render::{Input, Projection, RenderMode, Scene};
use glint_view::{Access, Viewer, ViewerConfig};
use serde_json::{json, Value};

/// Grid edge and ball radius, voxels (1 mm each); the value is the depth below the
/// ball's surface, mm.
const N: usize = 40;
const R: f64 = 15.0;

/// The ball written as NIfTI into the test's temporary folder.
fn ball() -> PathBuf {
    let c = (N - 1) as f64 / 2.0;
    let mut values = Vec::with_capacity(N * N * N);
    for k in 0..N {
        for j in 0..N {
            for i in 0..N {
                let d2: f64 = [i, j, k].iter().map(|&x| (x as f64 - c).powi(2)).sum();
                values.push((R - d2.sqrt()) as f32);
            }
        }
    }
    let vol = Volume::new([N; 3], [1.0; 3], Samples::F32(values)).unwrap();
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join("glint-clip-ball.nii");
    nifti::write(&path, &vol, false, Endian::Little).unwrap();
    path
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

fn xyz(v: &Value) -> [f64; 3] {
    [0, 1, 2].map(|a| f(&v[a]))
}

#[test]
fn a_crop_slider_darkens_the_half_it_cuts_and_the_box_is_drawn() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("browser");
    if !glint_testkit::browser_tools(&dir) {
        return;
    }
    let runtime = tokio::runtime::Runtime::new().unwrap();
    let mut scene = Scene {
        input: Input::Path(ball()),
        mode: RenderMode::Mip,
        size: [128, 128],
        ..Scene::default()
    };
    // Parallel rays: a pixel's ray stays on one side of the cut.
    scene.camera.projection = Projection::Orthographic;
    let viewer = Arc::new(Viewer::new(scene, ViewerConfig::default()).unwrap());
    let listener = runtime
        .block_on(tokio::net::TcpListener::bind("127.0.0.1:0"))
        .unwrap();
    let access = Arc::new(Access::new(listener.local_addr().unwrap(), None).unwrap());
    let url = access.url();
    runtime.spawn(glint_view::serve(listener, viewer, access));
    let shot = Path::new(env!("CARGO_TARGET_TMPDIR")).join("glint-view-clip.png");
    let out = Command::new("node")
        .current_dir(&dir)
        .args(["clip.mjs", "test", &url, shot.to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "clip.mjs failed: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut report: Value = serde_json::from_str(stdout.trim()).unwrap();
    // The panel starts from the volume's bounds: its voxel centres, 0 to N-1 mm.
    let top = (N - 1) as f64;
    let bounds = &report["bounds"];
    assert_eq!([xyz(&bounds[0]), xyz(&bounds[1])], [[0.0; 3], [top; 3]]);
    assert_eq!(xyz(&report["ticked"]["min"]), [0.0; 3], "{report}");
    assert_eq!(xyz(&report["ticked"]["max"]), [top; 3], "{report}");
    // The server's scene holds the crop: x up to the middle, the rest whole.
    let crop = &report["crop"];
    assert!((f(&crop["max"][0]) - top / 2.0).abs() < 1e-9, "{report}");
    assert_eq!(f(&crop["max"][1]), top, "{report}");
    // The box drawn lies over one half of the image: the half kept.
    let (x0, x1) = (f(&report["box_x"][0]), f(&report["box_x"][1]));
    let (kept, cut) = if x1 <= 0.55 {
        ("left", "right")
    } else if x0 >= 0.45 {
        ("right", "left")
    } else {
        panic!("the box drawn spans both halves: {report}")
    };
    let halves = &report["halves"];
    let background = f(&halves["background"]);
    // The ball showed in both halves before.
    for side in ["left", "right"] {
        assert!(
            f(&halves[side]["before"]) > background + 20.0,
            "{side} half was dark before: {report}"
        );
    }
    // The cut half is background now; the kept half is as it was.
    assert!(
        (f(&halves[cut]["after"]) - background).abs() < 1.0,
        "the cut ({cut}) half is not dark: {report}"
    );
    assert!(
        f(&halves[kept]["diff"]) < 0.5,
        "the kept ({kept}) half changed: {report}"
    );
    // The box's edges are drawn on the overlay.
    let edges = report["edges"].as_array().unwrap();
    assert!(
        !edges.is_empty() && edges.iter().all(|a| a.as_u64().unwrap() > 0),
        "box edges not drawn: {report}"
    );
    // The box's x min face handle (drawn), dragged 90% of its length inwards on the
    // image: the box's x min moves 90% of the handle's world length (15% of the
    // bounds' diagonal), nothing else of the box moves; the strip between the face's
    // old and new place showed the ball and is dark now, the rest of the box is
    // unchanged; the camera did not turn and nothing was picked.
    let face = &report["face"];
    assert!(f(&face["drawn"]) > 0.0, "face handle not drawn: {report}");
    let (start, end) = (&face["start"]["crop"], &face["end"]["crop"]);
    let moved = f(&end["min"][0]) - f(&start["min"][0]);
    let expected = 0.9 * 0.15 * (3.0f64).sqrt() * top;
    assert!(
        (moved - expected).abs() < 1.5,
        "the x min face moved {moved} mm, not {expected}: {report}"
    );
    assert_eq!(start["max"], end["max"], "{report}");
    for a in [1, 2] {
        assert_eq!(start["min"][a], end["min"][a], "{report}");
    }
    let strip = &face["regions"]["strip"];
    assert!(
        f(&strip["most_before"]) > background + 20.0,
        "the strip showed nothing before: {report}"
    );
    assert!(
        (f(&strip["after"]) - background).abs() < 1.0,
        "the strip cut away by the face is not dark: {report}"
    );
    assert!(
        f(&face["regions"]["rest"]["diff"]) < 0.5,
        "the rest of the box changed: {report}"
    );
    assert_eq!(face["end"]["camera"]["azimuth"], 0.0, "{report}");
    assert_eq!(face["end"]["picks"], 0, "{report}");
    // The clip plane across x at the middle; its handle (drawn) dragged half its
    // length towards its tip moves the plane half the handle's world length (15% of
    // the bounds' diagonal) along +x, and turns neither the camera nor picks.
    assert_eq!(xyz(&report["plane"]["normal"]), [1.0, 0.0, 0.0], "{report}");
    assert!((f(&report["plane"]["point"][0]) - top / 2.0).abs() < 1e-9);
    assert!(
        f(&report["handle_drawn"]) > 0.0,
        "handle not drawn: {report}"
    );
    let moved = f(&report["dragged"]["plane"]["point"][0]) - top / 2.0;
    let expected = 0.5 * 0.15 * (3.0f64).sqrt() * top;
    assert!(
        (moved - expected).abs() < 1.5,
        "the plane moved {moved} mm, not {expected}: {report}"
    );
    assert_eq!(report["dragged"]["camera"]["azimuth"], 0.0, "{report}");
    assert_eq!(report["dragged"]["picks"], 0, "{report}");
    // The record button: a valid 4-frame GIF of the scene's size arrived, its
    // frames differ (views round a cut ball), the progress reached 100% and the
    // page offers the file.
    let record = &report["record"];
    assert_eq!(record["recorded"]["format"], "gif", "{record}");
    assert_eq!(record["recorded"]["frames"], 4, "{record}");
    let formats = record["formats"].as_array().unwrap();
    assert_eq!(&formats[..2], [json!("gif"), json!("webp")], "{record}");
    let bytes: Vec<u8> = record["bytes"]
        .as_array()
        .expect("the file's bytes")
        .iter()
        .map(|b| b.as_u64().unwrap() as u8)
        .collect();
    assert_eq!(record["recorded"]["bytes"], bytes.len(), "{record}");
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options.read_info(bytes.as_slice()).expect("a GIF");
    assert_eq!((decoder.width(), decoder.height()), (128, 128));
    let mut frames = Vec::new();
    while let Some(frame) = decoder.read_next_frame().expect("a GIF frame") {
        frames.push(frame.buffer.to_vec());
    }
    assert_eq!(frames.len(), 4);
    assert!(frames[1..].iter().all(|f| *f != frames[0]), "frames alike");
    let progress = record["progress"].as_array().unwrap();
    assert_eq!(progress.last(), Some(&json!(100)), "{}", record["progress"]);
    assert_eq!(record["link"]["shown"], true);
    assert_eq!(record["link"]["download"], "glint-turntable.gif");
    assert_eq!(record["link"]["href"], "blob:");
    report["record"]["bytes"] = json!(bytes.len());
    eprintln!("browser clip test: {report}; screenshot {}", shot.display());
    glint_testkit::ran("chromium + node (view clip browser test)");
}
