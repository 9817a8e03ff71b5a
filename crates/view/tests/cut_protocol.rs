//! The viewer's cut messages over a real WebSocket (issue 43 item 1): `hello` carries
//! the volume's bounds; while the scene has a crop box or clip planes every frame,
//! interactive ones too, is preceded by a `cut` message with the box's 8 corners and
//! each plane's outline and handle projected on that frame; without them none is
//! sent. And a cut reuses the classification (no field or classification rebuilt).

use std::sync::Arc;
use std::time::Duration;

use futures_util::{SinkExt, StreamExt};
use glint_render::{Phantom, ReadOptions, Renderer, Scene};
use glint_view::protocol::{FrameHeader, Purpose};
use glint_view::{apply_patch, Access, Viewer, ViewerConfig};
use serde_json::{json, Value};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::{MaybeTlsStream, WebSocketStream};

type Client = WebSocketStream<MaybeTlsStream<TcpStream>>;

fn phantom() -> Scene {
    Scene::phantom(Phantom::SheppLogan, 32, [48, 40])
}

async fn start() -> String {
    let viewer = Arc::new(Viewer::new(phantom(), ViewerConfig::default()).unwrap());
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let url = format!("ws://{}/ws", listener.local_addr().unwrap());
    let access = Arc::new(Access::new(listener.local_addr().unwrap(), None).unwrap());
    tokio::spawn(glint_view::serve(listener, viewer, access));
    url
}

async fn next(c: &mut Client) -> Message {
    tokio::time::timeout(Duration::from_secs(20), c.next())
        .await
        .expect("a message within 20 s")
        .expect("the connection is open")
        .expect("a well-formed message")
}

/// Waits for the next frame of `purpose`; the `cut` message sent just before it.
async fn cut_frame(c: &mut Client, purpose: Purpose) -> Option<Value> {
    let mut cut = None;
    loop {
        match next(c).await {
            Message::Text(t) => {
                let v: Value = serde_json::from_str(&t).unwrap();
                assert_ne!(v["type"], "error", "{v}");
                if v["type"] == "cut" {
                    cut = Some(v);
                }
            }
            Message::Binary(b) => {
                let (h, _) = FrameHeader::decode(&b).expect("a frame header");
                if h.purpose == purpose {
                    return cut;
                }
                cut = None;
            }
            _ => {}
        }
    }
}

async fn update(c: &mut Client, seq: u32, interactive: bool, scene: Value) {
    let msg = json!({"type": "update", "seq": seq, "interactive": interactive, "scene": scene});
    c.send(Message::Text(msg.to_string().into())).await.unwrap();
}

/// A point on the image or just off it (fractions).
fn on_image(p: &Value) -> bool {
    (0..2).all(|a| p[a].as_f64().is_some_and(|x| (-0.5..1.5).contains(&x)))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn frames_of_a_cut_scene_come_with_the_box_and_plane_projected() {
    let url = start().await;
    let (mut c, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    let hello = loop {
        if let Message::Text(t) = next(&mut c).await {
            break serde_json::from_str::<Value>(&t).unwrap();
        }
    };
    assert_eq!(hello["type"], "hello");
    let b: Vec<[f64; 3]> = serde_json::from_value(hello["bounds"].clone()).unwrap();
    assert!((0..3).all(|a| b[0][a] < b[1][a]), "{hello}");
    assert_eq!(
        cut_frame(&mut c, Purpose::Full).await,
        None,
        "nothing cut yet"
    );
    // A crop box while dragging: the interactive frame comes with its 8 corners.
    let mid: Vec<f64> = (0..3).map(|a| (b[0][a] + b[1][a]) / 2.0).collect();
    let crop = json!({"min": b[0], "max": [mid[0], b[1][1], b[1][2]]});
    update(&mut c, 1, true, json!({"crop": crop})).await;
    let cut = cut_frame(&mut c, Purpose::Interactive)
        .await
        .expect("a cut message");
    assert_eq!(cut["seq"], 1);
    let corners = cut["crop"].as_array().unwrap();
    assert_eq!(corners.len(), 8, "{cut}");
    assert!(corners.iter().all(on_image), "{cut}");
    assert_eq!(cut["planes"], json!([]));
    // Corners 0 and 1 differ in x (the box is half the volume wide): apart.
    assert_ne!(corners[0], corners[1], "{cut}");
    // Six face handles, each a centre and a tip; the x faces' centres lie apart,
    // each between its face's corners (x min: corners 0, 2, 4, 6) on the image.
    let faces = cut["faces"].as_array().unwrap();
    assert_eq!(faces.len(), 6, "{cut}");
    for face in faces {
        assert!(face["handle"].as_array().unwrap().iter().all(on_image));
    }
    assert_ne!(faces[0]["handle"][0], faces[1]["handle"][0], "{cut}");
    for (f, ids) in [(0, [0, 2, 4, 6]), (1, [1, 3, 5, 7])] {
        for k in 0..2 {
            let c = |i: usize| corners[i][k].as_f64().unwrap();
            let lo = ids.iter().map(|&i| c(i)).fold(f64::INFINITY, f64::min);
            let hi = ids.iter().map(|&i| c(i)).fold(f64::NEG_INFINITY, f64::max);
            let v = faces[f]["handle"][0][k].as_f64().unwrap();
            assert!(lo - 1e-9 <= v && v <= hi + 1e-9, "face {f}: {cut}");
        }
    }
    // A plane instead: its outline across the bounds (a rectangle) and its handle.
    let plane = json!([{"point": mid, "normal": [0.0, 0.0, 1.0]}]);
    update(&mut c, 2, false, json!({"crop": null, "clip": plane})).await;
    let cut = cut_frame(&mut c, Purpose::Full)
        .await
        .expect("a cut message");
    assert_eq!(cut["crop"], Value::Null, "{cut}");
    assert_eq!(cut["faces"], Value::Null, "{cut}");
    let planes = cut["planes"].as_array().unwrap();
    assert_eq!(planes.len(), 1, "{cut}");
    let outline = planes[0]["outline"].as_array().unwrap();
    assert_eq!(outline.len(), 4, "{cut}");
    assert!(outline.iter().all(on_image), "{cut}");
    let handle = planes[0]["handle"].as_array().unwrap();
    assert!(handle.iter().all(on_image), "{cut}");
    assert_ne!(handle[0], handle[1], "{cut}");
    // Nothing cut again: no cut message.
    update(&mut c, 3, false, json!({"clip": []})).await;
    assert_eq!(cut_frame(&mut c, Purpose::Full).await, None);
}

#[test]
fn a_cut_reuses_the_field_and_the_classification() {
    let scene = phantom();
    let mut renderer = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    let field = renderer.field().unwrap().clone();
    let first = renderer.render(&scene, &|_| {}).unwrap();
    assert!(first.timings.get("classify") > Duration::ZERO, "built once");
    for patch in [
        json!({"crop": {"min": [-100.0, -100.0, -100.0], "max": [0.0, 100.0, 100.0]}}),
        json!({"crop": null, "clip": [{"point": [0.0, 0.0, 0.0], "normal": [1.0, 0.0, 0.0]}]}),
    ] {
        let cut = apply_patch(&renderer, &scene, patch.as_object().unwrap(), None).unwrap();
        let frame = renderer.render(&cut, &|_| {}).unwrap();
        let stages: Vec<&str> = frame.timings.stages().iter().map(|s| s.0).collect();
        assert!(!stages.contains(&"classify"), "{patch}: {stages:?}");
        assert!(Arc::ptr_eq(&field, renderer.field().unwrap()), "{patch}");
        assert_ne!(frame.image, first.image, "{patch} cut nothing");
    }
}
