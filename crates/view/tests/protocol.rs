//! The viewer's protocol, driven by a real WebSocket client against a server on a
//! loopback port: first frame, rotation, bad messages, the client limit, disconnects.

use std::sync::Arc;
use std::time::Duration;

use futures_util::{SinkExt, StreamExt};
use glint_render::{Input, Phantom, Scene};
use glint_view::protocol::{FrameHeader, Purpose};
use glint_view::{Access, Viewer, ViewerConfig};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::{MaybeTlsStream, WebSocketStream};

type Client = WebSocketStream<MaybeTlsStream<TcpStream>>;

/// A viewer of a small phantom on a free loopback port; returns it and the ws URL.
async fn start(max_clients: usize) -> (Arc<Viewer>, String) {
    let scene = Scene::phantom(Phantom::SheppLogan, 32, [48, 40]);
    let config = ViewerConfig {
        max_clients,
        ..ViewerConfig::default()
    };
    let viewer = Arc::new(Viewer::new(scene, config).unwrap());
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let url = format!("ws://{}/ws", listener.local_addr().unwrap());
    let access = Arc::new(Access::new(listener.local_addr().unwrap(), None).unwrap());
    tokio::spawn(glint_view::serve(listener, viewer.clone(), access));
    (viewer, url)
}

/// The next message, within 20 s.
async fn next(c: &mut Client) -> Message {
    tokio::time::timeout(Duration::from_secs(20), c.next())
        .await
        .expect("a message within 20 s")
        .expect("the connection is open")
        .expect("a well-formed message")
}

/// The next JSON message of type `kind` (frames and other messages before it skipped).
async fn json_of(c: &mut Client, kind: &str) -> serde_json::Value {
    loop {
        if let Message::Text(t) = next(c).await {
            let v: serde_json::Value = serde_json::from_str(&t).unwrap();
            if v["type"] == kind {
                return v;
            }
        }
    }
}

/// The next frame whose purpose is `purpose`: header and image bytes.
async fn frame(c: &mut Client, purpose: Purpose) -> (FrameHeader, Vec<u8>) {
    loop {
        if let Message::Binary(b) = next(c).await {
            let (h, img) = FrameHeader::decode(&b).expect("a frame header");
            if h.purpose == purpose {
                return (h, img.to_vec());
            }
        }
    }
}

async fn send(c: &mut Client, json: &str) {
    c.send(Message::Text(json.into())).await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn first_frame_then_rotation_changes_the_image() {
    let (_viewer, url) = start(4).await;
    let (mut c, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    let hello = json_of(&mut c, "hello").await;
    assert_eq!(hello["scene"]["size"], serde_json::json!([48, 40]));
    assert!(hello["presets"].as_array().unwrap().len() > 20);
    // The maps a path scene may name: the built-in one first, then the fetched probes
    // present (scripts/fetch-samples).
    let maps = hello["environments"].as_array().unwrap();
    assert_eq!(maps[0], "studio");
    if glint_testkit::sample("hdri/lab.exr").is_some() {
        assert!(maps.iter().any(|m| m == "lab"), "{maps:?}");
    }
    let (h, first) = frame(&mut c, Purpose::Full).await;
    assert_eq!((h.width, h.height), (48, 40));
    assert_eq!(&first[..2], &[0xFF, 0xD8]);
    // A drag: a half-size interactive frame for seq 1, then the full frame settles.
    send(
        &mut c,
        r#"{"type": "update", "seq": 1, "interactive": true, "scene": {"camera": {"azimuth": 60}}}"#,
    )
    .await;
    let (h, _) = frame(&mut c, Purpose::Interactive).await;
    assert_eq!((h.seq, h.width, h.height), (1, 24, 20));
    let (h, rotated) = frame(&mut c, Purpose::Full).await;
    assert_eq!(h.seq, 1);
    assert_ne!(rotated, first, "rotation must change the image");
    let scene = json_of(&mut c, "scene").await;
    assert_eq!(scene["scene"]["camera"]["azimuth"], 60.0);
    // Save: a PNG at full size.
    send(&mut c, r#"{"type": "save"}"#).await;
    let (h, png) = frame(&mut c, Purpose::Save).await;
    assert_eq!((h.width, &png[1..4]), (48, &b"PNG"[..]));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_messages_get_an_error_and_the_session_goes_on() {
    let (viewer, url) = start(4).await;
    let (mut c, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    frame(&mut c, Purpose::Full).await;
    let oversize = format!(
        r#"{{"type": "update", "seq": 9, "scene": {{"preset": "{}"}}}}"#,
        "x".repeat(100_000)
    );
    let cases: Vec<(String, &str)> = vec![
        ("not json".into(), "bad message"),
        (r#"{"type": "delete"}"#.into(), "delete"),
        (
            r#"{"type": "update", "seq": 2, "scene": {"colour": 1}}"#.into(),
            "colour",
        ),
        (
            r#"{"type": "update", "seq": 2, "scene": {"input": {"path": "/etc/passwd"}}}"#.into(),
            "input",
        ),
        (
            r#"{"type": "update", "seq": 2, "scene": {"camera": {"zoom": 1e9}}}"#.into(),
            "zoom",
        ),
        (
            r#"{"type": "update", "seq": 2, "scene": {"step": -1}}"#.into(),
            "step",
        ),
        (
            r#"{"type": "update", "seq": 2, "scene": {"lobe": {"kind": "cosine"}}}"#.into(),
            "cosine",
        ),
        (
            r#"{"type": "update", "seq": 2, "scene": {"size": [100000, 100000]}}"#.into(),
            "100000",
        ),
        (r#"{"type": "update", "seq": -1}"#.into(), "bad message"),
        (oversize, "bytes refused"),
        // Issue 41: a legal size at an absurd step is refused before any work.
        (
            r#"{"type": "update", "seq": 2, "scene": {"size": [2048, 2048], "step": 0.01}}"#.into(),
            "a 2048x2048 frame at step 0.01 takes up to",
        ),
    ];
    for (msg, needle) in cases {
        send(&mut c, &msg).await;
        let err = json_of(&mut c, "error").await;
        let text = err["message"].as_str().unwrap();
        assert!(
            text.contains(needle),
            "{}: '{text}'",
            &msg[..msg.len().min(60)]
        );
        assert!(!text.contains('\n'));
    }
    c.send(Message::Binary(vec![1, 2, 3].into())).await.unwrap();
    json_of(&mut c, "error").await;
    // Still serving: a good update renders.
    send(
        &mut c,
        r#"{"type": "update", "seq": 3, "scene": {"lobe": {"kind": "exact"}}}"#,
    )
    .await;
    let (h, _) = frame(&mut c, Purpose::Full).await;
    assert_eq!(h.seq, 3);
    // The refused patches changed nothing: the frame is the scene's own size.
    assert_eq!((h.width, h.height), (48, 40));
    assert_eq!(viewer.clients(), 1);
}

/// A viewer whose first frame is long (512x512 local frames at step 0.01 of a 48^3
/// phantom: seconds of work even in a release build); returns it and the ws URL.
async fn start_slow() -> (Arc<Viewer>, String) {
    let scene = Scene {
        step: 0.01,
        ..Scene::phantom(Phantom::SheppLogan, 48, [512, 512])
    };
    let viewer = Arc::new(Viewer::new(scene, ViewerConfig::default()).unwrap());
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let url = format!("ws://{}/ws", listener.local_addr().unwrap());
    let access = Arc::new(Access::new(listener.local_addr().unwrap(), None).unwrap());
    tokio::spawn(glint_view::serve(listener, viewer.clone(), access));
    (viewer, url)
}

/// Waits (up to 60 s) until `viewer` has stopped `n` frames.
async fn stopped(viewer: &Viewer, n: usize) {
    for _ in 0..2400 {
        if viewer.frames_stopped() >= n {
            return;
        }
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
    panic!("{} frames stopped, not {n}", viewer.frames_stopped());
}

/// Issue 41: a client that leaves while its frame is rendered stops it: the work
/// done (pixels finished) is a small part of the frame, not all of it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_leaving_stops_its_frame_in_flight() {
    let (viewer, url) = start_slow().await;
    let (mut c, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    // The server starts the first frame before it reads another message.
    json_of(&mut c, "hello").await;
    c.close(None).await.unwrap();
    drop(c);
    stopped(&viewer, 1).await;
    let done = viewer.pixels_rendered();
    assert!(done < 512 * 512 / 2, "{done} pixels of 262144 rendered");
    assert_eq!(
        viewer.cancelled(),
        0,
        "stopped by the leaving, not by input"
    );
}

/// Issue 41: input stops a full frame of the ray caster (not only a `path`
/// refinement) in flight; the next frame is the input's.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn input_stops_a_local_frame_in_flight() {
    let (viewer, url) = start_slow().await;
    let (mut c, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    json_of(&mut c, "hello").await;
    // Smaller and coarser: quick. It arrives while the first frame renders.
    send(
        &mut c,
        r#"{"type": "update", "seq": 1, "scene": {"size": [32, 32], "step": 1}}"#,
    )
    .await;
    let (h, _) = frame(&mut c, Purpose::Full).await;
    assert_eq!((h.seq, h.width), (1, 32), "no frame of the first state");
    assert_eq!((viewer.cancelled(), viewer.frames_stopped()), (1, 1));
    let done = viewer.pixels_rendered();
    assert!(done < 512 * 512 / 2 + 32 * 32, "{done} pixels rendered");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn clients_beyond_the_limit_are_refused_and_disconnects_free_seats() {
    let (viewer, url) = start(2).await;
    let (mut a, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    let (mut b, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    // Each client has its own camera.
    send(
        &mut a,
        r#"{"type": "update", "seq": 1, "scene": {"camera": {"view": "left"}}}"#,
    )
    .await;
    let sa = loop {
        // The scene of the first frame (seq 0) may come first.
        let m = json_of(&mut a, "scene").await;
        if m["seq"] == 1 {
            break m;
        }
    };
    assert_eq!(sa["scene"]["camera"]["view"], "left");
    let sb = json_of(&mut b, "scene").await;
    assert_eq!(sb["scene"]["camera"]["view"], "anterior");
    let (mut c, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    let err = json_of(&mut c, "error").await;
    assert!(
        err["message"].as_str().unwrap().contains("at most 2"),
        "{err}"
    );
    assert_eq!(viewer.clients(), 2);
    a.close(None).await.unwrap();
    drop(a);
    for _ in 0..200 {
        if viewer.clients() == 1 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
    assert_eq!(viewer.clients(), 1, "a disconnected client frees its seat");
    let (mut d, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    json_of(&mut d, "hello").await;
    frame(&mut d, Purpose::Full).await;
}

/// Issue 16: the viewer serves a scene of meshes only through the same protocol.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_mesh_scene_is_served_and_rotates() {
    let dir = std::env::temp_dir().join(format!("glint-view-mesh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let obj = dir.join("octa.obj");
    std::fs::write(
        &obj,
        "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n\
         f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n",
    )
    .unwrap();
    let scene = Scene {
        input: Input::None,
        meshes: vec![glint_render::MeshSpec::new(&obj)],
        size: [48, 40],
        ..Scene::default()
    };
    let viewer = Arc::new(Viewer::new(scene, ViewerConfig::default()).unwrap());
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let url = format!("ws://{}/ws", listener.local_addr().unwrap());
    let access = Arc::new(Access::new(listener.local_addr().unwrap(), None).unwrap());
    tokio::spawn(glint_view::serve(listener, viewer, access));
    let (mut c, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    let hello = json_of(&mut c, "hello").await;
    assert_eq!(hello["scene"]["input"], "none");
    assert_eq!(hello["scene"]["mode"], "surface");
    let (h, first) = frame(&mut c, Purpose::Full).await;
    assert_eq!((h.width, h.height), (48, 40));
    send(
        &mut c,
        r#"{"type": "update", "seq": 1, "interactive": false, "scene": {"camera": {"azimuth": 30, "elevation": 40}}}"#,
    )
    .await;
    let (h, rotated) = frame(&mut c, Purpose::Full).await;
    assert_eq!(h.seq, 1);
    assert_ne!(rotated, first, "rotation must change the image");
    // The meshes are fixed for a viewer, like the volume.
    send(
        &mut c,
        r#"{"type": "update", "seq": 2, "interactive": false, "scene": {"meshes": []}}"#,
    )
    .await;
    let err = json_of(&mut c, "error").await;
    assert!(err["message"].as_str().unwrap().contains("meshes"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Decodes a PNG frame (8-bit RGB) into its pixels.
fn rgb_pixels(png_bytes: &[u8]) -> Vec<[u8; 3]> {
    let mut reader = png::Decoder::new(std::io::Cursor::new(png_bytes))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf[..info.buffer_size()]
        .chunks_exact(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect()
}

/// The PNG of the client's current state (a `save`), after its frame for `seq`.
async fn saved(c: &mut Client, seq: u32) -> Vec<[u8; 3]> {
    send(c, r#"{"type": "save"}"#).await;
    let (h, png) = frame(c, Purpose::Save).await;
    assert_eq!(h.seq, seq);
    rgb_pixels(&png)
}

/// Issue 33: the hello lists the label map's labels (number, name, colour, voxels),
/// and a `labels` update hiding one changes the frame exactly where that label was.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn labels_are_listed_and_hiding_one_changes_only_its_pixels() {
    use glint_io::{nifti, Endian, Samples, Volume};
    let dir = std::env::temp_dir().join(format!("glint-view-labels-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Two 6-voxel cubes side by side along x: FreeSurfer's 17 Left-Hippocampus and
    // 18 Left-Amygdala (colours (220, 216, 20) and (103, 255, 255) in
    // FreeSurferColorLUT.txt); 5x6x6 and 6x6x6 voxels.
    let n = 16;
    let values: Vec<u8> = (0..n * n * n)
        .map(|i| {
            let (x, y, z) = (i % n, i / n % n, i / (n * n));
            let inside = (5..11).contains(&y) && (5..11).contains(&z);
            match x {
                3..=7 if inside => 17,
                8..=13 if inside => 18,
                _ => 0,
            }
        })
        .collect();
    let path = dir.join("aseg.nii");
    let vol = Volume::new([n; 3], [1.0; 3], Samples::U8(values)).unwrap();
    nifti::write(&path, &vol, false, Endian::Little).unwrap();
    // The same file as the volume, made transparent, so a pixel shows the labels
    // alone, unshaded (a pixel is its label's colour), without the legend.
    let mut spec = glint_render::LabelSpec::new(&path);
    spec.legend = false;
    let scene = Scene {
        input: Input::Path(path.clone()),
        labels: Some(spec),
        size: [64, 64],
        ssaa: Some(1),
        mode: glint_render::RenderMode::Composite,
        transfer_function: Some(
            glint_render::TransferFunction::from_flat(
                &[0.0, 0.0, 100.0, 0.0],
                &[0.0, 1.0, 1.0, 1.0],
            )
            .unwrap(),
        ),
        camera: glint_render::CameraSpec {
            projection: glint_render::Projection::Orthographic,
            ..glint_render::CameraSpec::default()
        },
        material: glint_render::MaterialOverrides {
            ambient: Some(1.0),
            diffuse: Some(0.0),
            specular: Some(0.0),
            shade: Some(false),
        },
        ..Scene::default()
    };
    let viewer = Arc::new(Viewer::new(scene, ViewerConfig::default()).unwrap());
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let url = format!("ws://{}/ws", listener.local_addr().unwrap());
    let access = Arc::new(Access::new(listener.local_addr().unwrap(), None).unwrap());
    tokio::spawn(glint_view::serve(listener, viewer, access));
    let (mut c, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    let hello = json_of(&mut c, "hello").await;
    assert_eq!(
        hello["labels"],
        serde_json::json!([
            {"value": 17, "name": "Left-Hippocampus", "color": "#dcd814", "voxels": 180, "shown": true},
            {"value": 18, "name": "Left-Amygdala", "color": "#67ffff", "voxels": 216, "shown": true},
        ])
    );
    frame(&mut c, Purpose::Full).await;
    let all = saved(&mut c, 0).await;
    let near = |p: [u8; 3], c: [u8; 3]| (0..3).all(|k| p[k].abs_diff(c[k]) <= 2);
    let (hippo, amygdala) = ([220, 216, 20], [103, 255, 255]);
    let count = |img: &[[u8; 3]], c| img.iter().filter(|p| near(**p, c)).count();
    assert!(count(&all, hippo) > 100 && count(&all, amygdala) > 100);

    // Hide 17: the next frame changes exactly where it was drawn.
    send(
        &mut c,
        r#"{"type": "update", "seq": 1, "scene": {"labels": {"hide": ["17"]}}}"#,
    )
    .await;
    let (h, _) = frame(&mut c, Purpose::Full).await;
    assert_eq!(h.seq, 1);
    let hidden = saved(&mut c, 1).await;
    let mut changed = 0;
    for (i, (a, b)) in all.iter().zip(&hidden).enumerate() {
        if a != b {
            changed += 1;
            assert!(near(*a, hippo), "pixel {i} changed but was {a:?}");
        } else {
            assert!(!near(*a, hippo), "pixel {i} of label 17 unchanged");
        }
    }
    assert_eq!(changed, count(&all, hippo));
    // By name, both hidden ("none"): the label layer goes, no label pixel is left.
    send(
        &mut c,
        r#"{"type": "update", "seq": 2, "scene": {"labels": {"hide": ["Left-Hippocampus", "left-amygdala"]}}}"#,
    )
    .await;
    let none = saved(&mut c, 2).await;
    assert_eq!(count(&none, hippo) + count(&none, amygdala), 0);
    // "All" again: the first image, pixel for pixel.
    send(
        &mut c,
        r#"{"type": "update", "seq": 3, "scene": {"labels": {"show": null, "hide": []}}}"#,
    )
    .await;
    assert_eq!(saved(&mut c, 3).await, all);
    // The file, its table and names not in it stay refused, one line each.
    for (patch, needle) in [
        (r#"{"labels": {"path": "/etc/passwd"}}"#, "labels.path"),
        (
            r#"{"labels": {"table": "totalsegmentator"}}"#,
            "labels.table",
        ),
        (
            r#"{"labels": {"hide": ["Left-Hipocampus"]}}"#,
            "Left-Hippocampus",
        ),
        (r#"{"labels": "none"}"#, "takes an object"),
    ] {
        let msg = format!(r#"{{"type": "update", "seq": 4, "scene": {patch}}}"#);
        send(&mut c, &msg).await;
        let err = json_of(&mut c, "error").await;
        let text = err["message"].as_str().unwrap();
        assert!(
            text.contains(needle) && !text.contains('\n'),
            "{patch}: {text}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 29: input arriving while a `path` refinement is traced stops it. The first
/// frame (one sample) is answered at once by an update: the server has already started
/// the refinement to 2 (it starts the next one before it reads another message), so
/// the update arrives during it. Stopped, it sends no frame; the next frame is the
/// update's, at one sample, and the count grows again from there.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn input_stops_a_path_refinement_in_flight_and_the_samples_restart() {
    let scene = Scene {
        // One sample of a frame takes about 0.17 s here (debug build, 2 cores): the
        // refinement the input meets is long beside the message's way to the server.
        lighting: glint_render::Lighting {
            model: glint_render::LightingModel::Path,
            spp: Some(64),
            ..glint_render::Lighting::default()
        },
        ..Scene::phantom(Phantom::SheppLogan, 48, [256, 256])
    };
    let viewer = Arc::new(Viewer::new(scene, ViewerConfig::default()).unwrap());
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let url = format!("ws://{}/ws", listener.local_addr().unwrap());
    let access = Arc::new(Access::new(listener.local_addr().unwrap(), None).unwrap());
    tokio::spawn(glint_view::serve(listener, viewer.clone(), access));
    let (mut c, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    let (h, _) = frame(&mut c, Purpose::Full).await;
    assert_eq!((h.seq, h.samples), (0, 1));
    send(
        &mut c,
        r#"{"type": "update", "seq": 1, "scene": {"camera": {"azimuth": 40}}}"#,
    )
    .await;
    let mut after = Vec::new();
    while after.len() < 2 {
        let (h, _) = frame(&mut c, Purpose::Full).await;
        after.push((h.seq, h.samples));
    }
    // No frame of the old camera at 2 samples: the refinement in flight was stopped.
    assert_eq!(after, [(1, 1), (1, 2)]);
    assert_eq!(viewer.cancelled(), 1);
}

/// Issue 31: a viewer of an OME-Zarr pyramid asked for its `auto` level starts from
/// the coarsest level; the finer one, read during a drag, is not swapped in until
/// the drag ends; then the client is told, and its next frame comes from it; a client
/// arriving later starts from it.
/// The store is the io crate's fixture (written by zarr-python, 5 levels).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_pyramid_is_shown_coarse_first_then_at_the_auto_level() {
    use glint_io::zarr::Level;
    use glint_io::ReadOptions;
    let store = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../io/tests/data/zarr/v04-blosc.zarr");
    let scene = Scene {
        input: Input::Path(store),
        size: [48, 48],
        ..Scene::default()
    };
    // At 48 pixels, auto is level 0 (64x48x10): level 1's 32 voxels are too few.
    let auto = ReadOptions {
        level: Level::Auto(48),
        ..ReadOptions::default()
    };
    let config = ViewerConfig {
        settle: Duration::from_secs(60),
        ..ViewerConfig::default()
    };
    let viewer = Arc::new(Viewer::with_options(scene.clone(), config, &auto).unwrap());
    let level = |l: usize, dims: [usize; 3], coarse: bool| glint_view::PyramidLevel {
        level: l,
        levels: 5,
        dims,
        coarse,
    };
    assert_eq!(viewer.level(), Some(level(4, [4, 3, 10], true)));
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let url = format!("ws://{}/ws", listener.local_addr().unwrap());
    let access = Arc::new(Access::new(listener.local_addr().unwrap(), None).unwrap());
    tokio::spawn(glint_view::serve(listener, viewer.clone(), access));
    let (mut c, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    let hello = json_of(&mut c, "hello").await;
    assert_eq!(
        hello["level"],
        serde_json::json!({"level": 4, "levels": 5, "dims": [4, 3, 10], "coarse": true})
    );
    let (_, coarse) = frame(&mut c, Purpose::Full).await;
    // A drag under way (its full frame not due for a minute) when the level is read.
    let drag = |seq: u32| {
        format!(
            r#"{{"type": "update", "seq": {seq}, "interactive": true, "scene": {{"camera": {{"azimuth": {}}}}}}}"#,
            10 * seq
        )
    };
    send(&mut c, &drag(1)).await;
    frame(&mut c, Purpose::Interactive).await;
    let v = viewer.clone();
    let read = tokio::task::spawn_blocking(move || v.refine())
        .await
        .unwrap();
    assert_eq!(read.unwrap(), Some(level(0, [64, 48, 10], false)));
    // Still dragging: no level message before the drag's next frame.
    send(&mut c, &drag(2)).await;
    loop {
        match next(&mut c).await {
            Message::Text(t) => assert!(!t.contains(r#""type":"level""#), "{t}"),
            Message::Binary(b) => {
                let (h, _) = FrameHeader::decode(&b).unwrap();
                assert_eq!((h.seq, h.purpose), (2, Purpose::Interactive));
                break;
            }
            other => panic!("{other:?}"),
        }
    }
    // The mouse is let go: the level message, then the first frame of the finer level.
    send(
        &mut c,
        r#"{"type": "update", "seq": 3, "scene": {"camera": {"azimuth": 0}}}"#,
    )
    .await;
    let fine = loop {
        match next(&mut c).await {
            Message::Text(t) => {
                let m: serde_json::Value = serde_json::from_str(&t).unwrap();
                if m["type"] == "level" {
                    assert_eq!(m["level"]["level"], 0, "{m}");
                    assert_eq!(m["level"]["coarse"], false, "{m}");
                    break frame(&mut c, Purpose::Full).await.1;
                }
                assert_eq!(m["type"], "scene", "{m}");
            }
            Message::Binary(_) => panic!("a frame before the level message"),
            other => panic!("{other:?}"),
        }
    };
    assert_ne!(fine, coarse, "the finer level changes the image");
    assert_eq!(viewer.refine().unwrap(), None, "read once");
    let (mut d, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    assert_eq!(json_of(&mut d, "hello").await["level"]["level"], 0);
    // A level asked for by number is read as asked, and is the only one.
    let two = ReadOptions {
        level: Level::Index(2),
        ..ReadOptions::default()
    };
    let v = Viewer::with_options(scene, ViewerConfig::default(), &two).unwrap();
    assert_eq!(v.level(), Some(level(2, [16, 12, 10], false)));
    assert_eq!(v.refine().unwrap(), None);
}
