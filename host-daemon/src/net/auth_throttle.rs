//! [`AuthThrottle`]: failed authentications slowed per address.
//!
//! Each failed token from an address is answered only after a delay that doubles with every
//! failure from that address ([`AuthPolicy::first_delay`] up to [`AuthPolicy::max_delay`]),
//! and the answers to one address come one after another, however many connections it
//! opens: guessing runs at one try per delay. A right token is answered at once (and clears
//! the address's record), so nobody can lock an operator out by failing on purpose from the
//! same address; `stop_all` is never delayed. An address's record is forgotten after
//! [`AuthPolicy::forget_after`] without failures.

use std::collections::HashMap;
use std::net::IpAddr;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// How failed authentications are slowed; `Default` gives the documented values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AuthPolicy {
    /// The delay of an address's first failure (default 100 ms)...
    pub first_delay: Duration,
    /// ...doubling with each further one, up to this (default 5 s).
    pub max_delay: Duration,
    /// A connection is closed after this many failures (default 5).
    pub max_failures_per_connection: u32,
    /// An address's failures are forgotten after this long without one (default 10 min).
    pub forget_after: Duration,
}

impl Default for AuthPolicy {
    fn default() -> Self {
        Self {
            first_delay: Duration::from_millis(100),
            max_delay: Duration::from_secs(5),
            max_failures_per_connection: 5,
            forget_after: Duration::from_secs(600),
        }
    }
}

impl AuthPolicy {
    /// The delay of the `failures`-th failure in a row from one address (1-based).
    pub fn delay(&self, failures: u32) -> Duration {
        let doublings = failures.saturating_sub(1).min(30);
        self.first_delay
            .saturating_mul(1u32 << doublings)
            .min(self.max_delay)
    }
}

/// Addresses remembered at most; the least recent is forgotten first.
const PEERS_KEPT: usize = 4096;

#[derive(Debug, Clone, Copy)]
struct PeerRecord {
    failures: u32,
    last_failure: Instant,
    /// When the address's latest answer is due: the next one comes after it.
    answer_free_at: Instant,
}

/// One failed authentication, as the throttle judged it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Failure {
    /// Failures in a row from this address, this one included.
    pub failures_from_peer: u32,
    /// The delay this failure adds.
    pub delay: Duration,
    /// When the answer may go out.
    pub answer_at: Instant,
}

/// Failed authentications per address (see the module documentation).
#[derive(Debug)]
pub struct AuthThrottle {
    policy: AuthPolicy,
    peers: Mutex<HashMap<IpAddr, PeerRecord>>,
}

impl AuthThrottle {
    /// A throttle that remembers nobody yet.
    pub fn new(policy: AuthPolicy) -> Self {
        Self {
            policy,
            peers: Mutex::new(HashMap::new()),
        }
    }

    /// The policy.
    pub fn policy(&self) -> &AuthPolicy {
        &self.policy
    }

    /// Counts a failure from `ip` at `now` and says when to answer it.
    pub fn failure(&self, ip: IpAddr, now: Instant) -> Failure {
        let mut peers = self.peers.lock().unwrap_or_else(|p| p.into_inner());
        let forget_after = self.policy.forget_after;
        peers.retain(|_, r| now.saturating_duration_since(r.last_failure) < forget_after);
        if peers.len() >= PEERS_KEPT && !peers.contains_key(&ip) {
            let oldest = peers
                .iter()
                .min_by_key(|(_, r)| r.last_failure)
                .map(|(ip, _)| *ip);
            if let Some(oldest) = oldest {
                peers.remove(&oldest);
            }
        }
        let record = peers.entry(ip).or_insert(PeerRecord {
            failures: 0,
            last_failure: now,
            answer_free_at: now,
        });
        record.failures = record.failures.saturating_add(1);
        record.last_failure = now;
        let delay = self.policy.delay(record.failures);
        let answer_at = record.answer_free_at.max(now) + delay;
        record.answer_free_at = answer_at;
        Failure {
            failures_from_peer: record.failures,
            delay,
            answer_at,
        }
    }

    /// Forgets `ip`'s failures: it proved the token.
    pub fn success(&self, ip: IpAddr) {
        let mut peers = self.peers.lock().unwrap_or_else(|p| p.into_inner());
        peers.remove(&ip);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: IpAddr = IpAddr::V4(std::net::Ipv4Addr::new(10, 0, 0, 1));
    const B: IpAddr = IpAddr::V4(std::net::Ipv4Addr::new(10, 0, 0, 2));

    #[test]
    fn delays_double_up_to_the_cap() {
        let policy = AuthPolicy::default();
        let ms: Vec<u128> = (1..=8).map(|n| policy.delay(n).as_millis()).collect();
        assert_eq!(ms, [100, 200, 400, 800, 1600, 3200, 5000, 5000]);
        assert_eq!(policy.delay(u32::MAX), policy.max_delay);
    }

    #[test]
    fn answers_to_one_address_queue_up_and_a_success_clears_them() {
        let throttle = AuthThrottle::new(AuthPolicy::default());
        let t0 = Instant::now();
        let first = throttle.failure(A, t0);
        let second = throttle.failure(A, t0);
        assert_eq!(first.answer_at, t0 + Duration::from_millis(100));
        // The second waits for the first, then its own, longer delay.
        assert_eq!(second.answer_at, t0 + Duration::from_millis(300));
        assert_eq!(second.failures_from_peer, 2);
        // Another address is not slowed by A.
        assert_eq!(
            throttle.failure(B, t0).answer_at,
            t0 + Duration::from_millis(100)
        );
        throttle.success(A);
        assert_eq!(throttle.failure(A, t0).failures_from_peer, 1);
    }

    #[test]
    fn failures_are_forgotten_after_a_quiet_while() {
        let policy = AuthPolicy {
            forget_after: Duration::from_secs(60),
            ..AuthPolicy::default()
        };
        let throttle = AuthThrottle::new(policy);
        let t0 = Instant::now();
        for _ in 0..5 {
            throttle.failure(A, t0);
        }
        let later = throttle.failure(A, t0 + Duration::from_secs(61));
        assert_eq!(later.failures_from_peer, 1);
    }
}
