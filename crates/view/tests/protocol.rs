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
    let scene = Scene {
        input: Input::Phantom {
            name: Phantom::SheppLogan,
            size: 32,
        },
        size: [48, 40],
        ..Scene::default()
    };
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
    assert_eq!(viewer.clients(), 1);
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
