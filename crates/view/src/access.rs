//! Who may use a viewer: the checks every request passes before a route sees it.
//!
//! The browser does not keep other sites away from the viewer: any page the user has
//! open may open a WebSocket to `ws://127.0.0.1:8080/ws`, and the same-origin policy
//! does not apply to WebSockets; RFC 6455 §10.2 leaves checking `Origin` to the server.
//! Binding to loopback does not help, and a page can also reach the server under its
//! own name by DNS rebinding (its name re-resolved to 127.0.0.1), which makes the page
//! and the socket the attacker's "own origin". So:
//!
//! - **Host**, on every request: `localhost`, a loopback address or the address the
//!   server is bound to (any IP literal when bound to `0.0.0.0` or `::`), with the
//!   bound port (80 when the header has none). Any other name is refused with 421
//!   Misdirected Request (RFC 9110 §15.5.20: the server does not answer for that
//!   authority); a missing, repeated or malformed Host with 400. A rebinding page sends
//!   its own name, and an IP literal cannot be rebound.
//! - **Origin**, on every request that carries one: it must be `http://` followed by
//!   the request's Host, the page the viewer served; anything else, `null` included,
//!   is refused with 403. So the page at `http://localhost:8080` drives the socket at
//!   `localhost:8080`, and a page at `http://localhost:3000` or any other site does
//!   not. A request without `Origin` is allowed: browsers always send it on a
//!   WebSocket handshake (RFC 6455 §4.1), so its absence means a script or a test,
//!   which the Host check and the token still cover; Jupyter's server decides the same
//!   (`check_origin` in jupyter_server/base/handlers.py).
//! - **Token**, on `/` and `/ws` when the viewer has one (required when it is bound
//!   to an address that is not loopback): the `token` query parameter, as in
//!   Jupyter's `http://host:8888/?token=…`, compared in constant time (the `subtle`
//!   crate). The page passes it on to its socket in the same query parameter: that
//!   request goes only to the viewer. No cookie carries it: cookies ignore the port,
//!   so another server on the same host would receive it. Missing or wrong: 403.
//!
//! Every refusal is answered with a one-line plain-text reason and logged to stderr
//! (method, path without the query, peer, reason; never the token). Successful
//! responses carry `Referrer-Policy: no-referrer` (the page's URL holds the token) and
//! `Content-Security-Policy: frame-ancestors 'none'` (no other site frames the page).

use std::fmt;
use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr};
use std::str::FromStr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use axum::extract::{ConnectInfo, Request, State};
use axum::http::uri::Authority;
use axum::http::{header, HeaderMap, HeaderValue, StatusCode, Uri};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use subtle::ConstantTimeEq;

use crate::ViewError;

/// The secret a viewer on a non-loopback address asks for: the `token` query parameter
/// of the page and of its WebSocket. `Debug` does not show it.
#[derive(Clone, PartialEq, Eq)]
pub struct Token(String);

impl Token {
    /// Bytes of a random token, from the operating system's generator: 192 bits, as
    /// Jupyter's (`binascii.hexlify(os.urandom(24))` in jupyter_server/serverapp.py).
    pub const RANDOM_BYTES: usize = 24;
    /// Fewest characters of a token given with `--token`.
    pub const MIN_CHARS: usize = 16;
    /// Most characters of a token given with `--token`.
    pub const MAX_CHARS: usize = 256;

    /// A new token: [`Token::RANDOM_BYTES`] bytes from the OS generator, in hex.
    pub fn random() -> Result<Token, ViewError> {
        let mut bytes = [0u8; Token::RANDOM_BYTES];
        getrandom::fill(&mut bytes).map_err(|e| ViewError::Random(e.to_string()))?;
        Ok(Token(bytes.iter().map(|b| format!("{b:02x}")).collect()))
    }

    /// The token's text, as the URL carries it.
    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// Whether `given` is this token, in time that does not depend on where they
    /// differ (only on the lengths, which a random token makes public anyway).
    fn matches(&self, given: &str) -> bool {
        self.0.as_bytes().ct_eq(given.as_bytes()).into()
    }
}

impl fmt::Debug for Token {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Token(hidden)")
    }
}

/// A token given by the user: [`Token::MIN_CHARS`] to [`Token::MAX_CHARS`] of the
/// characters a URL carries unescaped (RFC 3986 §2.3: `A-Z a-z 0-9 - . _ ~`), so the
/// printed URL is the token as typed.
impl FromStr for Token {
    type Err = ViewError;

    fn from_str(s: &str) -> Result<Token, ViewError> {
        let unreserved = |c: char| c.is_ascii_alphanumeric() || "-._~".contains(c);
        let chars = s.chars().count();
        if (Token::MIN_CHARS..=Token::MAX_CHARS).contains(&chars) && s.chars().all(unreserved) {
            Ok(Token(s.to_owned()))
        } else {
            Err(ViewError::BadToken)
        }
    }
}

/// Whether `ip` is a loopback address (IPv4-mapped IPv6 ones included).
pub fn is_loopback(ip: IpAddr) -> bool {
    ip.to_canonical().is_loopback()
}

/// A host as a request names it: a lowercase name or an IP address.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Host {
    Name(String),
    Ip(IpAddr),
}

/// A parsed `host[:port]` authority; the port is 80 (http's) when absent.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Endpoint {
    host: Host,
    port: u16,
}

impl Endpoint {
    /// Parses a Host header or an origin's authority; `None` if it is not one.
    fn parse(text: &str) -> Option<Endpoint> {
        let authority = Authority::from_str(text).ok()?;
        if text.contains('@') {
            return None;
        }
        let h = authority.host();
        // `Authority::port` is `None` for a port out of range, so read it here.
        let port = match authority.as_str().strip_prefix(h)? {
            "" => 80,
            rest => {
                let digits = rest.strip_prefix(':')?;
                if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
                    return None;
                }
                digits.parse::<u16>().ok()?
            }
        };
        let host = if let Some(inner) = h.strip_prefix('[') {
            Host::Ip(IpAddr::V6(
                inner.strip_suffix(']')?.parse::<Ipv6Addr>().ok()?,
            ))
        } else if let Ok(v4) = h.parse::<Ipv4Addr>() {
            Host::Ip(IpAddr::V4(v4))
        } else {
            Host::Name(h.to_ascii_lowercase())
        };
        Some(Endpoint { host, port })
    }
}

/// A header's value for a log line or a reply: escaped and cut to 80 characters,
/// since it comes from whoever sent the request.
fn shown(value: &[u8]) -> String {
    let text = String::from_utf8_lossy(value);
    let mut cut: String = text.chars().take(80).collect();
    if cut.len() < text.len() {
        cut.push('…');
    }
    format!("{cut:?}")
}

/// The one value of header `name`: `Ok(None)` if absent, `Err(())` if repeated.
fn single<'a>(
    headers: &'a HeaderMap,
    name: &header::HeaderName,
) -> Result<Option<&'a HeaderValue>, ()> {
    let mut values = headers.get_all(name).iter();
    match (values.next(), values.next()) {
        (first, None) => Ok(first),
        _ => Err(()),
    }
}

/// A viewer's access policy: the address it is bound to and its token. See the
/// module documentation for the rules.
#[derive(Debug)]
pub struct Access {
    bound: SocketAddr,
    token: Option<Token>,
    refused: AtomicUsize,
}

impl Access {
    /// The policy of a server bound to `bound` (the listener's own address, with the
    /// port it got). A non-loopback address needs a token; a loopback one may have one.
    pub fn new(bound: SocketAddr, token: Option<Token>) -> Result<Access, ViewError> {
        if !is_loopback(bound.ip()) && token.is_none() {
            return Err(ViewError::TokenRequired { addr: bound });
        }
        Ok(Access {
            bound,
            token,
            refused: AtomicUsize::new(0),
        })
    }

    /// The address the server is bound to.
    pub fn bound(&self) -> SocketAddr {
        self.bound
    }

    /// Whether the server is bound to a loopback address (this machine only).
    pub fn loopback(&self) -> bool {
        is_loopback(self.bound.ip())
    }

    /// The token the page and its socket need, if any.
    pub fn token(&self) -> Option<&Token> {
        self.token.as_ref()
    }

    /// Requests refused so far.
    pub fn refused(&self) -> usize {
        self.refused.load(Ordering::SeqCst)
    }

    /// The URL to open: the bound address (loopback in place of an unspecified one)
    /// and port, with `?token=…` when there is a token.
    pub fn url(&self) -> String {
        let host = match self.bound.ip() {
            IpAddr::V4(ip) if ip.is_unspecified() => "127.0.0.1".to_owned(),
            IpAddr::V6(ip) if ip.is_unspecified() => "[::1]".to_owned(),
            IpAddr::V4(ip) => ip.to_string(),
            IpAddr::V6(ip) => format!("[{ip}]"),
        };
        let query = self
            .token
            .as_ref()
            .map_or(String::new(), |t| format!("?token={}", t.as_str()));
        format!("http://{host}:{}/{query}", self.bound.port())
    }

    /// Whether a request may name `e` as its Host.
    fn answers_to(&self, e: &Endpoint) -> bool {
        let bound = self.bound.ip();
        e.port == self.bound.port()
            && match &e.host {
                Host::Name(name) => name == "localhost",
                Host::Ip(ip) => {
                    is_loopback(*ip)
                        || bound.is_unspecified()
                        || ip.to_canonical() == bound.to_canonical()
                }
            }
    }

    /// The policy on one request: its URI (path and query) and headers. `Ok` lets it
    /// through; the error says why not (its HTTP status: [`ViewError::status`]).
    pub fn check(&self, uri: &Uri, headers: &HeaderMap) -> Result<(), ViewError> {
        let host_value = single(headers, &header::HOST).map_err(|()| ViewError::BadHost)?;
        let host = match (host_value, uri.authority()) {
            (Some(v), _) => v.to_str().ok().and_then(Endpoint::parse),
            // HTTP/1.0, or an absolute-form request target without Host.
            (None, Some(a)) => Endpoint::parse(a.as_str()),
            (None, None) => None,
        }
        .ok_or(ViewError::BadHost)?;
        let absolute = uri.authority().map(|a| Endpoint::parse(a.as_str()));
        if !self.answers_to(&host) || absolute.is_some_and(|a| a.as_ref() != Some(&host)) {
            let text = host_value.map_or(b"" as &[u8], |v| v.as_bytes());
            return Err(ViewError::ForeignHost {
                host: shown(text),
                port: self.bound.port(),
            });
        }
        let origin = single(headers, &header::ORIGIN).map_err(|()| ViewError::ForeignOrigin {
            origin: "(several)".into(),
        })?;
        if let Some(origin) = origin {
            let own = origin
                .to_str()
                .ok()
                .and_then(|o| o.strip_prefix("http://"))
                .and_then(Endpoint::parse)
                .is_some_and(|o| o == host);
            if !own {
                return Err(ViewError::ForeignOrigin {
                    origin: shown(origin.as_bytes()),
                });
            }
        }
        if let Some(token) = &self.token {
            if matches!(uri.path(), "/" | "/ws") {
                let given = form_urlencoded::parse(uri.query().unwrap_or("").as_bytes())
                    .find(|(k, _)| k == "token")
                    .map(|(_, v)| v);
                match given {
                    None => return Err(ViewError::TokenMissing),
                    Some(g) if !token.matches(&g) => return Err(ViewError::TokenWrong),
                    Some(_) => {}
                }
            }
        }
        Ok(())
    }
}

impl ViewError {
    /// The HTTP status a refused request gets: 400 for a bad Host, 421 for a foreign
    /// one, 403 for a foreign Origin or a missing or wrong token; 500 for the rest.
    pub fn status(&self) -> StatusCode {
        match self {
            ViewError::BadHost => StatusCode::BAD_REQUEST,
            ViewError::ForeignHost { .. } => StatusCode::MISDIRECTED_REQUEST,
            ViewError::ForeignOrigin { .. } | ViewError::TokenMissing | ViewError::TokenWrong => {
                StatusCode::FORBIDDEN
            }
            _ => StatusCode::INTERNAL_SERVER_ERROR,
        }
    }
}

/// The middleware: checks a request against the viewer's [`Access`], refuses it with
/// its status and a logged reason, or passes it on and marks the response as not to be
/// framed or referred from.
pub(crate) async fn guard(State(access): State<Arc<Access>>, req: Request, next: Next) -> Response {
    if let Err(e) = access.check(req.uri(), req.headers()) {
        access.refused.fetch_add(1, Ordering::SeqCst);
        let peer = req
            .extensions()
            .get::<ConnectInfo<SocketAddr>>()
            .map_or("an unknown peer".to_owned(), |c| c.0.to_string());
        eprintln!(
            "glint view: refused {} {} from {peer}: {e}",
            req.method(),
            req.uri().path()
        );
        return (e.status(), format!("{e}\n")).into_response();
    }
    let mut response = next.run(req).await;
    let headers = response.headers_mut();
    headers.insert(
        header::REFERRER_POLICY,
        HeaderValue::from_static("no-referrer"),
    );
    headers.insert(
        header::CONTENT_SECURITY_POLICY,
        HeaderValue::from_static("frame-ancestors 'none'"),
    );
    response
}

#[cfg(test)]
mod tests {
    use super::*;

    fn access(bound: &str, token: Option<&str>) -> Access {
        Access::new(bound.parse().unwrap(), token.map(|t| t.parse().unwrap())).unwrap()
    }

    /// The check on a request for `target` with the given headers.
    fn check(a: &Access, target: &str, headers: &[(&str, &str)]) -> Result<(), ViewError> {
        let mut map = HeaderMap::new();
        for (k, v) in headers {
            map.append(
                header::HeaderName::from_bytes(k.as_bytes()).unwrap(),
                HeaderValue::from_str(v).unwrap(),
            );
        }
        a.check(&target.parse().unwrap(), &map)
    }

    fn status(r: Result<(), ViewError>) -> u16 {
        r.map_or_else(|e| e.status().as_u16(), |()| 200)
    }

    #[test]
    fn hosts_are_the_loopback_names_and_the_bound_address_with_the_port() {
        let a = access("127.0.0.1:8080", None);
        for (host, want) in [
            ("127.0.0.1:8080", 200),
            ("localhost:8080", 200),
            ("LocalHost:8080", 200),
            ("[::1]:8080", 200),
            ("127.0.0.2:8080", 200),
            ("localhost:8081", 421),
            ("localhost", 421),
            ("evil.example:8080", 421),
            ("localhost.:8080", 421),
            ("app.localhost:8080", 421),
            ("192.168.1.5:8080", 421),
            ("user@localhost:8080", 400),
            ("localhost:", 400),
            ("localhost:99999", 400),
            ("[::1:8080", 400),
            ("", 400),
        ] {
            assert_eq!(status(check(&a, "/", &[("host", host)])), want, "{host}");
        }
        assert_eq!(status(check(&a, "/", &[])), 400, "no Host");
        let two = [("host", "localhost:8080"), ("host", "localhost:8080")];
        assert_eq!(status(check(&a, "/", &two)), 400, "two Hosts");
        // An absolute-form target must name the same place as Host.
        let h = [("host", "localhost:8080")];
        assert_eq!(status(check(&a, "http://evil.example:8080/", &h)), 421);
        assert_eq!(status(check(&a, "http://localhost:8080/", &h)), 200);
        // Port 80: a Host without a port means 80.
        let a80 = access("127.0.0.1:80", None);
        assert_eq!(status(check(&a80, "/", &[("host", "localhost")])), 200);
        // A specific bound address and the loopback names; no other address.
        let lan = access("192.168.1.5:8080", Some("0123456789abcdef"));
        assert_eq!(
            status(check(&lan, "/app.js", &[("host", "192.168.1.5:8080")])),
            200
        );
        assert_eq!(
            status(check(&lan, "/app.js", &[("host", "192.168.1.6:8080")])),
            421
        );
        assert_eq!(
            status(check(&lan, "/app.js", &[("host", "localhost:8080")])),
            200
        );
        // Bound to every address: any IP literal, still no other name.
        let all = access("0.0.0.0:8080", Some("0123456789abcdef"));
        for (host, want) in [
            ("10.1.2.3:8080", 200),
            ("[fe80::1]:8080", 200),
            ("workstation.lan:8080", 421),
            ("10.1.2.3:8081", 421),
        ] {
            assert_eq!(
                status(check(&all, "/app.js", &[("host", host)])),
                want,
                "{host}"
            );
        }
    }

    #[test]
    fn an_origin_must_be_the_host_the_request_names() {
        let a = access("127.0.0.1:8080", None);
        for (host, origin, want) in [
            ("127.0.0.1:8080", "http://127.0.0.1:8080", 200),
            ("localhost:8080", "http://localhost:8080", 200),
            ("[::1]:8080", "http://[0:0:0:0:0:0:0:1]:8080", 200),
            // Both this machine, but not the page the request names.
            ("127.0.0.1:8080", "http://localhost:8080", 403),
            ("localhost:8080", "http://localhost:3000", 403),
            ("localhost:8080", "https://localhost:8080", 403),
            ("localhost:8080", "http://evil.example", 403),
            ("localhost:8080", "http://localhost:8080/x", 403),
            ("localhost:8080", "null", 403),
            ("localhost:8080", "", 403),
        ] {
            let r = check(&a, "/ws", &[("host", host), ("origin", origin)]);
            assert_eq!(status(r), want, "{host} {origin}");
        }
        let two = [
            ("host", "localhost:8080"),
            ("origin", "http://localhost:8080"),
            ("origin", "http://evil.example"),
        ];
        assert_eq!(status(check(&a, "/ws", &two)), 403);
        // Scripts send no Origin.
        assert_eq!(status(check(&a, "/ws", &[("host", "localhost:8080")])), 200);
    }

    #[test]
    fn a_token_guards_the_page_and_the_socket_only() {
        let a = access("0.0.0.0:8080", Some("Secret-token_0123"));
        let h = [("host", "10.0.0.7:8080")];
        for (target, want) in [
            ("/", 403),
            ("/ws", 403),
            ("/?token=", 403),
            ("/?token=secret-token_0123", 403),
            ("/ws?token=Secret-token_012", 403),
            ("/ws?token=Secret-token_01234", 403),
            ("/?Token=Secret-token_0123", 403),
            ("/?token=Secret-token_0123", 200),
            ("/ws?token=Secret-token_0123", 200),
            ("/ws?x=1&token=Secret-token_0123", 200),
            ("/ws?token=Secret%2Dtoken_0123", 200),
            ("/app.js", 200),
            ("/style.css", 200),
        ] {
            assert_eq!(status(check(&a, target, &h)), want, "{target}");
        }
        assert!(matches!(check(&a, "/", &h), Err(ViewError::TokenMissing)));
        assert!(matches!(
            check(&a, "/?token=nope", &h),
            Err(ViewError::TokenWrong)
        ));
    }

    #[test]
    fn a_non_loopback_address_needs_a_token() {
        for addr in [
            "0.0.0.0:8080",
            "[::]:8080",
            "192.168.1.5:8080",
            "[::ffff:10.0.0.1]:80",
        ] {
            let e = Access::new(addr.parse().unwrap(), None).unwrap_err();
            assert!(matches!(e, ViewError::TokenRequired { .. }), "{addr}");
        }
        for addr in [
            "127.0.0.1:8080",
            "127.8.9.10:8080",
            "[::1]:8080",
            "[::ffff:127.0.0.1]:80",
        ] {
            let a = Access::new(addr.parse().unwrap(), None).unwrap();
            assert!(a.loopback() && a.token().is_none(), "{addr}");
        }
    }

    #[test]
    fn tokens_given_by_hand_need_no_escaping_and_sixteen_characters() {
        assert!("0123456789abcdef".parse::<Token>().is_ok());
        assert!("A-b.c_d~e0123456789".parse::<Token>().is_ok());
        for bad in [
            "short",
            "0123456789abcde",
            "0123456789abcdef ",
            "0123456789abcdef&x",
            "ééééééééééééééééé",
        ] {
            assert!(
                matches!(bad.parse::<Token>(), Err(ViewError::BadToken)),
                "{bad}"
            );
        }
        assert!("x".repeat(257).parse::<Token>().is_err());
        assert_eq!(
            format!("{:?}", "0123456789abcdef".parse::<Token>().unwrap()),
            "Token(hidden)"
        );
    }

    #[test]
    fn random_tokens_are_192_bits_of_hex_and_differ() {
        let (a, b) = (Token::random().unwrap(), Token::random().unwrap());
        assert_eq!(a.as_str().len(), 2 * Token::RANDOM_BYTES);
        assert!(a.as_str().bytes().all(|c| c.is_ascii_hexdigit()));
        assert_ne!(a, b);
        // A random token is also a valid hand-given one (it round-trips through --token).
        assert_eq!(a.as_str().parse::<Token>().unwrap(), a);
    }

    #[test]
    fn urls_name_a_reachable_address_and_carry_the_token() {
        assert_eq!(
            access("127.0.0.1:8080", None).url(),
            "http://127.0.0.1:8080/"
        );
        let t = Some("0123456789abcdef");
        assert_eq!(
            access("0.0.0.0:9000", t).url(),
            "http://127.0.0.1:9000/?token=0123456789abcdef"
        );
        assert_eq!(
            access("[::]:9000", t).url(),
            "http://[::1]:9000/?token=0123456789abcdef"
        );
        assert_eq!(access("[::1]:9000", None).url(), "http://[::1]:9000/");
        assert_eq!(
            access("10.0.0.7:80", t).url(),
            "http://10.0.0.7:80/?token=0123456789abcdef"
        );
    }

    #[test]
    fn shown_values_are_escaped_and_cut() {
        assert_eq!(shown(b"a\"b\x1b"), r#""a\"b\u{1b}""#);
        let long = shown("x".repeat(200).as_bytes());
        assert_eq!(long.chars().count(), 80 + 3);
    }
}
