//! Session admission: who may create sessions, how often.
//!
//! * [`TokenBucket`]: the one rate limiter of the server (session creation per client here,
//!   client WebSocket messages per connection in [`super::ws`]).
//! * [`ClientKey`]: the client a request comes from — its peer address, or with trusted
//!   proxies configured the address they report in `X-Forwarded-For`; IPv6 clients are keyed
//!   by their /64 prefix (one host usually holds a whole /64).
//! * [`CreationLimiter`]: a token bucket per client for `POST /api/sessions`.

use std::collections::HashMap;
use std::net::{IpAddr, Ipv6Addr, SocketAddr};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use axum::extract::{ConnectInfo, FromRequestParts};
use axum::http::HeaderMap;
use axum::http::request::Parts;

/// The peer address of the connection, when the server was started with connect info
/// ([`crate::run`] always is).
#[derive(Debug, Clone)]
pub struct Peer(pub Option<ConnectInfo<SocketAddr>>);

impl<S: Send + Sync> FromRequestParts<S> for Peer {
    type Rejection = std::convert::Infallible;

    async fn from_request_parts(parts: &mut Parts, _state: &S) -> Result<Self, Self::Rejection> {
        Ok(Peer(
            parts.extensions.get::<ConnectInfo<SocketAddr>>().cloned(),
        ))
    }
}

/// Token bucket: `rate_per_s` tokens per second, holding at most `capacity` (the burst).
#[derive(Debug, Clone)]
pub struct TokenBucket {
    capacity: f64,
    rate_per_s: f64,
    tokens: f64,
    last: Instant,
}

impl TokenBucket {
    /// A full bucket.
    pub fn new(capacity: f64, rate_per_s: f64, now: Instant) -> TokenBucket {
        let capacity = capacity.max(1.0);
        TokenBucket {
            capacity,
            rate_per_s: rate_per_s.max(f64::MIN_POSITIVE),
            tokens: capacity,
            last: now,
        }
    }

    fn refill(&mut self, now: Instant) {
        let dt = now.saturating_duration_since(self.last).as_secs_f64();
        self.tokens = (self.tokens + dt * self.rate_per_s).min(self.capacity);
        self.last = now;
    }

    /// Takes one token when there is one.
    pub fn try_take(&mut self, now: Instant) -> bool {
        self.refill(now);
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }

    /// Time until a token is available (zero when one is).
    pub fn wait_time(&self) -> Duration {
        let missing = (1.0 - self.tokens).max(0.0);
        Duration::from_secs_f64(missing / self.rate_per_s)
    }

    /// Whether the bucket has refilled completely by `now` (then it is the same as a new one).
    fn is_full(&self, now: Instant) -> bool {
        let dt = now.saturating_duration_since(self.last).as_secs_f64();
        self.tokens + dt * self.rate_per_s >= self.capacity
    }
}

/// The client a request is attributed to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ClientKey {
    /// An IPv4 address, or an IPv6 address with its low 64 bits cleared.
    Ip(IpAddr),
    /// Not limited (sessions created with the instructor token).
    Exempt,
}

impl ClientKey {
    /// The key of an address (IPv4-mapped IPv6 counts as IPv4; other IPv6 by /64 prefix).
    pub fn from_ip(ip: IpAddr) -> ClientKey {
        match ip {
            IpAddr::V4(_) => ClientKey::Ip(ip),
            IpAddr::V6(v6) => match v6.to_ipv4_mapped() {
                Some(v4) => ClientKey::Ip(IpAddr::V4(v4)),
                None => {
                    let prefix = u128::from(v6) & !((1u128 << 64) - 1);
                    ClientKey::Ip(IpAddr::V6(Ipv6Addr::from(prefix)))
                }
            },
        }
    }
}

/// The client's address: the peer address, unless the peer is one of `trusted_proxies`; then
/// the right-most `X-Forwarded-For` entry that is not itself a trusted proxy (entries to its
/// left can be forged by the client). Without trusted proxies the header is ignored.
pub fn client_ip(
    peer: Option<&ConnectInfo<SocketAddr>>,
    headers: &HeaderMap,
    trusted_proxies: &[IpAddr],
) -> Option<IpAddr> {
    let peer = peer.map(|c| c.0.ip())?;
    if !trusted_proxies.contains(&peer) {
        return Some(peer);
    }
    let mut forwarded: Vec<IpAddr> = Vec::new();
    for value in headers.get_all("x-forwarded-for") {
        let Ok(text) = value.to_str() else {
            return Some(peer);
        };
        for entry in text.split(',') {
            match entry.trim().parse::<IpAddr>() {
                Ok(ip) => forwarded.push(ip),
                // A malformed chain cannot be trusted beyond the proxy itself.
                Err(_) => return Some(peer),
            }
        }
    }
    Some(
        forwarded
            .into_iter()
            .rev()
            .find(|ip| !trusted_proxies.contains(ip))
            .unwrap_or(peer),
    )
}

/// Buckets beyond which fully refilled ones are dropped (they equal fresh buckets).
const PRUNE_ABOVE: usize = 1024;

/// Per-client token buckets for session creation.
#[derive(Debug)]
pub struct CreationLimiter {
    burst: f64,
    rate_per_s: f64,
    buckets: Mutex<HashMap<ClientKey, TokenBucket>>,
}

impl CreationLimiter {
    /// `burst` creations at once per client, refilled at `per_minute`.
    pub fn new(burst: u32, per_minute: f64) -> CreationLimiter {
        CreationLimiter {
            burst: f64::from(burst.max(1)),
            rate_per_s: (per_minute / 60.0).max(f64::MIN_POSITIVE),
            buckets: Mutex::new(HashMap::new()),
        }
    }

    /// Creations allowed at once.
    pub fn burst(&self) -> u32 {
        self.burst as u32
    }

    /// Refill rate (per minute).
    pub fn per_minute(&self) -> f64 {
        self.rate_per_s * 60.0
    }

    /// Takes a token for `client`; `Err(wait)` says how long until one is available.
    pub fn check(&self, client: ClientKey) -> Result<(), Duration> {
        if client == ClientKey::Exempt {
            return Ok(());
        }
        let now = Instant::now();
        let mut buckets = self.buckets.lock().unwrap_or_else(|e| e.into_inner());
        if buckets.len() > PRUNE_ABOVE {
            buckets.retain(|_, b| !b.is_full(now));
        }
        let bucket = buckets
            .entry(client)
            .or_insert_with(|| TokenBucket::new(self.burst, self.rate_per_s, now));
        if bucket.try_take(now) {
            Ok(())
        } else {
            Err(bucket.wait_time())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bucket_gives_its_burst_then_refills_at_its_rate() {
        let t0 = Instant::now();
        let mut b = TokenBucket::new(3.0, 2.0, t0);
        assert!((0..3).all(|_| b.try_take(t0)));
        assert!(!b.try_take(t0));
        // 2 tokens/s: after 0.5 s exactly one more.
        let t1 = t0 + Duration::from_millis(500);
        assert!(b.try_take(t1));
        assert!(!b.try_take(t1));
        assert!((b.wait_time().as_secs_f64() - 0.5).abs() < 1e-9);
        // Never more than the capacity, however long it waits.
        let t2 = t1 + Duration::from_secs(3600);
        assert!((0..3).all(|_| b.try_take(t2)));
        assert!(!b.try_take(t2));
    }

    #[test]
    fn ipv6_clients_are_keyed_by_their_64_prefix() {
        let a: IpAddr = "2001:db8:1:2:aaaa::1".parse().unwrap();
        let b: IpAddr = "2001:db8:1:2:bbbb::9".parse().unwrap();
        let c: IpAddr = "2001:db8:1:3::1".parse().unwrap();
        assert_eq!(ClientKey::from_ip(a), ClientKey::from_ip(b));
        assert_ne!(ClientKey::from_ip(a), ClientKey::from_ip(c));
        let mapped: IpAddr = "::ffff:10.0.0.7".parse().unwrap();
        assert_eq!(
            ClientKey::from_ip(mapped),
            ClientKey::Ip("10.0.0.7".parse().unwrap())
        );
    }

    #[test]
    fn forwarded_for_is_believed_only_from_trusted_proxies() {
        let peer = |ip: &str| ConnectInfo(SocketAddr::new(ip.parse().unwrap(), 4000));
        let mut h = HeaderMap::new();
        h.insert("x-forwarded-for", "6.6.6.6, 10.1.1.1".parse().unwrap());
        let proxy: IpAddr = "10.0.0.1".parse().unwrap();
        // Untrusted peer: the header is ignored.
        assert_eq!(
            client_ip(Some(&peer("192.0.2.5")), &h, &[proxy]),
            Some("192.0.2.5".parse().unwrap())
        );
        // Trusted proxy: the right-most entry (the one the proxy appended).
        assert_eq!(
            client_ip(Some(&peer("10.0.0.1")), &h, &[proxy]),
            Some("10.1.1.1".parse().unwrap())
        );
        // No proxies configured: never believed.
        assert_eq!(client_ip(Some(&peer("10.0.0.1")), &h, &[]), Some(proxy));
        // Garbage in the chain: the proxy itself.
        h.insert("x-forwarded-for", "nonsense".parse().unwrap());
        assert_eq!(
            client_ip(Some(&peer("10.0.0.1")), &h, &[proxy]),
            Some(proxy)
        );
    }

    #[test]
    fn the_limiter_keys_clients_separately_and_exempts_the_instructor() {
        let l = CreationLimiter::new(2, 1.0);
        let a = ClientKey::Ip("127.0.0.1".parse().unwrap());
        let b = ClientKey::Ip("127.0.0.2".parse().unwrap());
        assert!(l.check(a).is_ok() && l.check(a).is_ok());
        let wait = l.check(a).unwrap_err();
        assert!(wait > Duration::from_secs(50), "one per minute: {wait:?}");
        assert!(l.check(b).is_ok());
        assert!((0..100).all(|_| l.check(ClientKey::Exempt).is_ok()));
    }
}
