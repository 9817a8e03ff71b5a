//! The viewer's pick messages over a real WebSocket: a pick answers with the point
//! and marks it, the marks come projected before every frame (interactive ones too,
//! following the camera), two marks make a ruler, points off the image and split
//! views are refused in one line, `unmark` clears (issue 43 item 2).

use std::sync::Arc;
use std::time::Duration;

use futures_util::{SinkExt, StreamExt};
use glint_render::{Phantom, Scene};
use glint_view::protocol::{FrameHeader, Purpose};
use glint_view::{Access, Viewer, ViewerConfig};
use serde_json::Value;
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::{MaybeTlsStream, WebSocketStream};

type Client = WebSocketStream<MaybeTlsStream<TcpStream>>;

async fn start() -> String {
    let scene = Scene::phantom(Phantom::SheppLogan, 32, [48, 40]);
    let viewer = Arc::new(Viewer::new(scene, ViewerConfig::default()).unwrap());
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

/// The next JSON message of type `kind` (others skipped).
async fn json_of(c: &mut Client, kind: &str) -> Value {
    loop {
        if let Message::Text(t) = next(c).await {
            let v: Value = serde_json::from_str(&t).unwrap();
            if v["type"] == kind {
                return v;
            }
        }
    }
}

/// Waits for the next frame of `purpose`; the `marks` message sent just before it.
async fn marked_frame(c: &mut Client, purpose: Purpose) -> Option<Value> {
    let mut marks = None;
    loop {
        match next(c).await {
            Message::Text(t) => {
                let v: Value = serde_json::from_str(&t).unwrap();
                if v["type"] == "marks" {
                    marks = Some(v);
                }
            }
            Message::Binary(b) => {
                let (h, _) = FrameHeader::decode(&b).expect("a frame header");
                if h.purpose == purpose {
                    return marks;
                }
                marks = None;
            }
            _ => {}
        }
    }
}

async fn send(c: &mut Client, json: &str) {
    c.send(Message::Text(json.into())).await.unwrap();
}

fn point(v: &Value) -> [f64; 2] {
    [v[0].as_f64().unwrap(), v[1].as_f64().unwrap()]
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn picks_mark_points_that_follow_the_camera_and_two_make_a_ruler() {
    let url = start().await;
    let (mut c, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    assert_eq!(
        marked_frame(&mut c, Purpose::Full).await,
        None,
        "no marks yet"
    );
    send(&mut c, r#"{"type": "pick", "x": 24, "y": 20}"#).await;
    let answer = json_of(&mut c, "pick").await;
    assert_eq!(answer["pick"]["object"]["kind"], "volume", "{answer}");
    assert_eq!(answer["marks"].as_array().unwrap().len(), 1);
    assert_eq!(answer["distance_mm"], Value::Null);
    // The mark at once on the frame shown: where it was clicked.
    let marks = json_of(&mut c, "marks").await;
    let [u, v] = point(&marks["points"][0]);
    assert!((u - 0.5).abs() < 1e-3 && (v - 0.5).abs() < 1e-3, "{marks}");
    // A second point: a ruler as long as the distance between the two.
    send(&mut c, r#"{"type": "pick", "x": 30, "y": 20}"#).await;
    let answer = json_of(&mut c, "pick").await;
    let ends: Vec<[f64; 3]> = serde_json::from_value(answer["marks"].clone()).unwrap();
    assert_eq!(ends.len(), 2);
    let d = (0..3)
        .map(|k| (ends[0][k] - ends[1][k]).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(
        (answer["distance_mm"].as_f64().unwrap() - d).abs() < 1e-9,
        "{answer}"
    );
    assert!(d > 1.0);
    let marks = json_of(&mut c, "marks").await;
    let [u, _] = point(&marks["points"][1]);
    assert!((u - 30.0 / 48.0).abs() < 1e-3, "{marks}");
    // Nothing at the corner: no mark made, the ruler stays.
    send(&mut c, r#"{"type": "pick", "x": 0.5, "y": 0.5}"#).await;
    let answer = json_of(&mut c, "pick").await;
    assert_eq!(answer["pick"], Value::Null);
    assert_eq!(answer["marks"].as_array().unwrap().len(), 2);
    // Off the image: one line, the marks kept.
    send(&mut c, r#"{"type": "pick", "x": 48, "y": 5}"#).await;
    let e = json_of(&mut c, "error").await;
    assert!(
        e["message"]
            .as_str()
            .unwrap()
            .contains("off the 48x40 image"),
        "{e}"
    );
    // A drag: the interactive frame comes with the marks projected by its camera.
    send(
        &mut c,
        r#"{"type": "update", "seq": 1, "interactive": true, "scene": {"camera": {"azimuth": 50}}}"#,
    )
    .await;
    let moved = marked_frame(&mut c, Purpose::Interactive)
        .await
        .expect("marks");
    assert_eq!(moved["seq"], 1);
    let [u0, _] = point(&moved["points"][0]);
    assert!((u0 - 0.5).abs() > 0.01, "the mark did not move: {moved}");
    // Cleared: an empty list, and frames come without marks.
    send(&mut c, r#"{"type": "unmark"}"#).await;
    let cleared = json_of(&mut c, "marks").await;
    assert_eq!(cleared["points"], serde_json::json!([]));
    send(
        &mut c,
        r#"{"type": "update", "seq": 2, "scene": {"camera": {"azimuth": 10}}}"#,
    )
    .await;
    assert_eq!(marked_frame(&mut c, Purpose::Full).await, None);
    // Split views are not picked.
    send(&mut c, r#"{"type": "split", "split": "side"}"#).await;
    send(&mut c, r#"{"type": "pick", "x": 24, "y": 20}"#).await;
    let e = json_of(&mut c, "error").await;
    assert!(e["message"].as_str().unwrap().contains("split"), "{e}");
}
