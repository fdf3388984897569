//! Who may connect when the server is full: [`admit`] takes the connections there are and
//! the new one's address and says whether it comes in, and whose place it takes.
//!
//! The rule keeps an operator from being locked out by readers, however many there are:
//! a connection that proved the token (an operator's) is never dropped; when the server is
//! full (`max_clients`), or the new connection's address is (`max_clients_per_peer`), the new
//! connection takes the place of the oldest connection that never proved the token, of its
//! own address when that address is full, otherwise of the address holding the most
//! connections. Only when every candidate proved the token is the new one refused.

use std::net::IpAddr;

/// A connection as admission sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Occupant {
    /// Its number: smaller is older.
    pub id: u64,
    /// Its address.
    pub ip: IpAddr,
    /// It proved the token.
    pub authenticated: bool,
}

/// What happens to a new connection.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Admission {
    /// It comes in.
    Admit,
    /// It comes in, and the connection of this id is dropped for it.
    Evict(u64),
    /// It is refused, for this reason.
    Refuse(String),
}

/// Decides on a new connection from `ip` (see the module documentation).
pub fn admit(
    occupants: &[Occupant],
    ip: IpAddr,
    max_clients: usize,
    max_clients_per_peer: usize,
) -> Admission {
    let oldest_unproven = |of: &dyn Fn(&Occupant) -> bool| {
        occupants
            .iter()
            .filter(|o| !o.authenticated && of(o))
            .min_by_key(|o| o.id)
            .map(|o| o.id)
    };
    let from_ip = occupants.iter().filter(|o| o.ip == ip).count();
    if from_ip >= max_clients_per_peer {
        return match oldest_unproven(&|o| o.ip == ip) {
            Some(id) => Admission::Evict(id),
            None => Admission::Refuse(format!(
                "{ip} already has {from_ip} connections, all of them operators'"
            )),
        };
    }
    if occupants.len() < max_clients {
        return Admission::Admit;
    }
    // The address holding the most connections gives way; among equals, the one whose
    // unproven connection is oldest.
    let mut best: Option<(usize, u64)> = None;
    for candidate in occupants.iter().filter(|o| !o.authenticated) {
        let count = occupants.iter().filter(|o| o.ip == candidate.ip).count();
        let better = match best {
            None => true,
            Some((best_count, best_id)) => {
                count > best_count || (count == best_count && candidate.id < best_id)
            }
        };
        if better {
            best = Some((count, candidate.id));
        }
    }
    // (Within one address the smaller id wins too: that address's oldest unproven one.)
    match best {
        Some((_, id)) => Admission::Evict(id),
        None => Admission::Refuse(format!(
            "the server already has {} connections, all of them operators'",
            occupants.len()
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ip(last: u8) -> IpAddr {
        IpAddr::from([10, 0, 0, last])
    }

    fn occupants(spec: &[(u8, bool)]) -> Vec<Occupant> {
        spec.iter()
            .enumerate()
            .map(|(i, &(last, authenticated))| Occupant {
                id: i as u64,
                ip: ip(last),
                authenticated,
            })
            .collect()
    }

    #[test]
    fn room_admits() {
        assert_eq!(
            admit(&occupants(&[(1, false)]), ip(2), 2, 2),
            Admission::Admit
        );
    }

    #[test]
    fn a_full_address_gives_up_its_oldest_reader() {
        let o = occupants(&[(1, true), (1, false), (2, false), (1, false)]);
        assert_eq!(admit(&o, ip(1), 10, 3), Admission::Evict(1));
        let operators = occupants(&[(1, true), (1, true)]);
        assert!(matches!(
            admit(&operators, ip(1), 10, 2),
            Admission::Refuse(_)
        ));
    }

    #[test]
    fn a_full_server_takes_from_the_busiest_address() {
        // Address 3 holds three connections: its oldest reader goes, not address 1's.
        let o = occupants(&[(1, false), (3, false), (3, true), (3, false), (2, false)]);
        assert_eq!(admit(&o, ip(4), 5, 5), Admission::Evict(1));
        // Equal counts: the oldest reader goes.
        let o = occupants(&[(1, true), (2, false), (3, false)]);
        assert_eq!(admit(&o, ip(4), 3, 3), Admission::Evict(1));
    }

    #[test]
    fn operators_are_never_dropped() {
        let o = occupants(&[(1, true), (2, true)]);
        assert!(matches!(admit(&o, ip(3), 2, 2), Admission::Refuse(_)));
    }

    /// 40 readers from one address, then an operator from the same address: there is always
    /// room for the operator.
    #[test]
    fn forty_readers_never_fill_the_server_for_an_operator() {
        let mut o: Vec<Occupant> = Vec::new();
        for id in 0..41u64 {
            let new = Occupant {
                id,
                ip: ip(1),
                authenticated: false,
            };
            match admit(&o, new.ip, 32, 16) {
                Admission::Admit => {}
                Admission::Evict(victim) => o.retain(|x| x.id != victim),
                Admission::Refuse(why) => panic!("connection {id} refused: {why}"),
            }
            o.push(new);
            assert!(o.len() <= 16);
        }
    }
}
