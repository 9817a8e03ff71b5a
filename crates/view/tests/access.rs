//! The viewer serves only its own page (issue 34): real sockets against a running
//! server. A WebSocket handshake from another origin, a request naming another host
//! (DNS rebinding) and, on a non-loopback address, a request without the right token
//! are refused with their status; the viewer's own page and script clients are served.

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use futures_util::StreamExt;
use glint_render::{Phantom, Scene};
use glint_view::{Access, Token, Viewer, ViewerConfig};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::http::HeaderValue;
use tokio_tungstenite::tungstenite::{Error, Message};

/// A viewer of a small phantom bound to `bind` (port 0: a free one), with `token`;
/// returns its policy and the loopback address to reach it at.
async fn start(bind: &str, token: Option<Token>) -> (Arc<Access>, SocketAddr) {
    let scene = Scene::phantom(Phantom::SheppLogan, 32, [48, 40]);
    let viewer = Arc::new(Viewer::new(scene, ViewerConfig::default()).unwrap());
    let listener = tokio::net::TcpListener::bind(bind).await.unwrap();
    let bound = listener.local_addr().unwrap();
    let access = Arc::new(Access::new(bound, token).unwrap());
    tokio::spawn(glint_view::serve(listener, viewer, access.clone()));
    (access, SocketAddr::from(([127, 0, 0, 1], bound.port())))
}

/// A WebSocket handshake to `path` on `addr` with extra headers (a Host among them
/// replaces the client's): the first message's type if it succeeds, else the status.
async fn socket(addr: SocketAddr, path: &str, headers: &[(&str, &str)]) -> Result<String, u16> {
    let mut request = format!("ws://{addr}{path}").into_client_request().unwrap();
    for (name, value) in headers {
        let name: tokio_tungstenite::tungstenite::http::HeaderName = name.parse().unwrap();
        request
            .headers_mut()
            .insert(name, HeaderValue::from_str(value).unwrap());
    }
    let connect = tokio_tungstenite::connect_async(request);
    match tokio::time::timeout(Duration::from_secs(20), connect)
        .await
        .unwrap()
    {
        Ok((mut client, _)) => {
            let msg = tokio::time::timeout(Duration::from_secs(20), client.next())
                .await
                .unwrap()
                .unwrap()
                .unwrap();
            let Message::Text(text) = msg else {
                panic!("a text message first, not {msg:?}")
            };
            let v: serde_json::Value = serde_json::from_str(&text).unwrap();
            Ok(v["type"].as_str().unwrap().to_owned())
        }
        Err(Error::Http(response)) => Err(response.status().as_u16()),
        Err(e) => panic!("handshake failed without an HTTP answer: {e}"),
    }
}

/// A raw HTTP request (the text after the request line is `head`; the connection is
/// closed after it): the status and the whole response.
async fn http(addr: SocketAddr, request_line: &str, head: &str) -> (u16, String) {
    let mut stream = TcpStream::connect(addr).await.unwrap();
    let request = format!("{request_line}\r\n{head}Connection: close\r\n\r\n");
    stream.write_all(request.as_bytes()).await.unwrap();
    let mut response = Vec::new();
    tokio::time::timeout(Duration::from_secs(20), stream.read_to_end(&mut response))
        .await
        .unwrap()
        .unwrap();
    let text = String::from_utf8_lossy(&response).into_owned();
    let status = text
        .split(' ')
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no status line in {text:?}"));
    (status, text)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_page_of_another_origin_cannot_open_the_socket() {
    let (access, addr) = start("127.0.0.1:0", None).await;
    let port = addr.port();
    let other = format!("http://localhost:{}", port.wrapping_add(1).max(1));
    for origin in ["http://evil.example", other.as_str(), "null"] {
        let r = socket(addr, "/ws", &[("origin", origin)]).await;
        assert_eq!(r, Err(403), "{origin}");
    }
    // The same machine under another name is another origin than the Host it names.
    let r = socket(
        addr,
        "/ws",
        &[("origin", &format!("http://localhost:{port}"))],
    )
    .await;
    assert_eq!(r, Err(403));
    assert_eq!(access.refused(), 4);
    // The page's own origin: the Host it names.
    let own = format!("http://127.0.0.1:{port}");
    assert_eq!(
        socket(addr, "/ws", &[("origin", &own)]).await.as_deref(),
        Ok("hello")
    );
    let local = [
        ("host", format!("localhost:{port}")),
        ("origin", format!("http://localhost:{port}")),
    ];
    let local: Vec<(&str, &str)> = local.iter().map(|(k, v)| (*k, v.as_str())).collect();
    assert_eq!(socket(addr, "/ws", &local).await.as_deref(), Ok("hello"));
    // The refusal says why, as plain text.
    let (status, text) = http(
        addr,
        "GET /ws HTTP/1.1",
        &format!("Host: 127.0.0.1:{port}\r\nOrigin: http://evil.example\r\n"),
    )
    .await;
    assert_eq!(status, 403);
    assert!(
        text.contains("Origin \"http://evil.example\" is not this viewer's page"),
        "{text}"
    );
    assert_eq!(access.refused(), 5);
}

/// Decision: clients that send no Origin (scripts; browsers always send one on a
/// WebSocket handshake) are served, on loopback without a token.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_without_origin_is_served() {
    let (access, addr) = start("127.0.0.1:0", None).await;
    assert_eq!(socket(addr, "/ws", &[]).await.as_deref(), Ok("hello"));
    assert_eq!(access.refused(), 0);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_request_naming_another_host_is_refused() {
    let (access, addr) = start("127.0.0.1:0", None).await;
    let port = addr.port();
    // DNS rebinding: a page of evil.example whose name now resolves to 127.0.0.1.
    let evil = format!("evil.example:{port}");
    for path in ["/", "/app.js", "/ws"] {
        let (status, text) = http(
            addr,
            &format!("GET {path} HTTP/1.1"),
            &format!("Host: {evil}\r\n"),
        )
        .await;
        assert_eq!(status, 421, "{path}: {text}");
        assert!(text.contains("is not this viewer"), "{text}");
    }
    let origin = format!("http://{evil}");
    let r = socket(addr, "/ws", &[("host", &evil), ("origin", &origin)]).await;
    assert_eq!(r, Err(421));
    // This machine on another port (a tunnel or proxy under another number).
    let r = socket(
        addr,
        "/ws",
        &[(
            "host",
            &format!("127.0.0.1:{}", port.wrapping_add(1).max(1)),
        )],
    )
    .await;
    assert_eq!(r, Err(421));
    // No Host at all (HTTP/1.0): 400.
    let (status, _) = http(addr, "GET / HTTP/1.0", "").await;
    assert_eq!(status, 400);
    assert_eq!(access.refused(), 6);
    // The loopback names, with the port: the page, marked not to be framed or referred.
    for host in [
        format!("localhost:{port}"),
        format!("127.0.0.1:{port}"),
        format!("[::1]:{port}"),
    ] {
        let (status, text) = http(addr, "GET / HTTP/1.1", &format!("Host: {host}\r\n")).await;
        assert_eq!(status, 200, "{host}: {text}");
        assert!(text.contains("<canvas id=\"frame\""), "{host}");
        let lower = text.to_ascii_lowercase();
        assert!(lower.contains("referrer-policy: no-referrer"), "{text}");
        assert!(
            lower.contains("content-security-policy: frame-ancestors 'none'"),
            "{text}"
        );
    }
    assert_eq!(access.refused(), 6);
}

/// Bound to every address (0.0.0.0, so not loopback), reached through 127.0.0.1.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_viewer_on_a_non_loopback_address_needs_its_token() {
    let any: SocketAddr = "0.0.0.0:8080".parse().unwrap();
    assert!(matches!(
        Access::new(any, None),
        Err(glint_view::ViewError::TokenRequired { .. })
    ));
    let token = Token::random().unwrap();
    let (access, addr) = start("0.0.0.0:0", Some(token.clone())).await;
    assert!(!access.loopback());
    let port = addr.port();
    let url = access.url();
    assert_eq!(
        url,
        format!("http://127.0.0.1:{port}/?token={}", token.as_str())
    );
    let right = format!("?token={}", token.as_str());
    let wrong = format!("?token={}", Token::random().unwrap().as_str());
    // The socket: no token, a wrong one, the right one.
    assert_eq!(socket(addr, "/ws", &[]).await, Err(403));
    assert_eq!(socket(addr, &format!("/ws{wrong}"), &[]).await, Err(403));
    assert_eq!(
        socket(addr, &format!("/ws{right}"), &[]).await.as_deref(),
        Ok("hello")
    );
    // The token does not let another origin in.
    let evil = [("origin", "http://evil.example")];
    assert_eq!(socket(addr, &format!("/ws{right}"), &evil).await, Err(403));
    // The page needs it too; its script and styles are the same for everyone.
    let host = format!("Host: 127.0.0.1:{port}\r\n");
    let (status, text) = http(addr, "GET / HTTP/1.1", &host).await;
    assert_eq!(status, 403);
    assert!(text.contains("this viewer needs its token"), "{text}");
    let (status, text) = http(addr, &format!("GET /{wrong} HTTP/1.1"), &host).await;
    assert_eq!(status, 403);
    assert!(text.contains("wrong token"), "{text}");
    let (status, text) = http(addr, &format!("GET /{right} HTTP/1.1"), &host).await;
    assert_eq!(status, 200, "{text}");
    assert!(text.contains("<canvas id=\"frame\""));
    assert_eq!(http(addr, "GET /app.js HTTP/1.1", &host).await.0, 200);
    // Bound to every address: any IP literal names it, a name other than localhost not.
    let named = format!("Host: workstation.example:{port}\r\n");
    assert_eq!(
        http(addr, &format!("GET /{right} HTTP/1.1"), &named)
            .await
            .0,
        421
    );
    let ip = format!("Host: 10.9.8.7:{port}\r\n");
    assert_eq!(
        http(addr, &format!("GET /{right} HTTP/1.1"), &ip).await.0,
        200
    );
    assert_eq!(access.refused(), 6);
}

#[tokio::test]
async fn serve_refuses_a_policy_made_for_another_address() {
    let scene = Scene::phantom(Phantom::SheppLogan, 16, Scene::default().size);
    let viewer = Arc::new(Viewer::new(scene, ViewerConfig::default()).unwrap());
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let mut elsewhere = listener.local_addr().unwrap();
    elsewhere.set_port(elsewhere.port().wrapping_add(1).max(1));
    let access = Arc::new(Access::new(elsewhere, None).unwrap());
    let e = glint_view::serve(listener, viewer, access)
        .await
        .unwrap_err();
    assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
}
