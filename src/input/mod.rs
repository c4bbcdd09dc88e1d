//! Live aircraft state over UDP, GL-free: FlightGear's native FDM packet
//! (FlightGear and JSBSim), X-Plane's `RPOS` and `DATA` output, and GDL 90
//! (Stratux, ForeFlight Sentry, GDL 90 boxes). Every datagram is decoded
//! on a receiver thread into one pose record in geodetic terms, checked for
//! plausibility and taken or ignored with a counted reason; a frame reads
//! the newest state without ever waiting for the thread, extrapolates it
//! to its own time (at most [`pose::MAX_EXTRAPOLATION_S`] ahead) or finds
//! the data stale.
//!
//! Input is untrusted: each protocol reads only inside the length it has
//! checked, the receive buffer is fixed ([`receiver::MAX_DATAGRAM_BYTES`])
//! and no datagram allocates.
//!
//! | module | owns |
//! |---|---|
//! | [`pose`] | the pose record ([`GeoPose`]), position with velocity, attitude with rates, bounded extrapolation |
//! | [`update`] | what a datagram contributes ([`Update`]), why one is ignored ([`Ignored`]), plausibility |
//! | [`flightgear`] | FlightGear's `FGNetFDM`, versions 24 and 25 |
//! | [`xplane`] | X-Plane's `RPOS` and `DATA` groups 17 and 20 |
//! | [`gdl90`] | GDL 90 framing, CRC, messages and the decoder state |
//! | [`state`] | the newest data, jumps, staleness, the frame's view ([`LiveView`]) |
//! | [`receiver`] | the UDP socket's thread, the counters, the state a frame reads |
//! | [`record`] | `--record`: received poses as a `--path` CSV |
//! | [`place`] | the one conversion from geodetic to the display's frame |

pub mod flightgear;
pub mod gdl90;
pub mod place;
pub mod pose;
pub mod receiver;
pub mod record;
pub mod state;
pub mod update;
pub mod xplane;

pub use pose::{Attitude, GeoPose, Position, Track, Turning};
pub use receiver::{Counts, LiveInput, ReceiverError};
pub use state::{LiveState, LiveView, StaleReason};
pub use update::{Ignored, Update};

use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::time::Instant;

/// Which protocol a live input speaks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum InputKind {
    /// FlightGear's native FDM packet (FlightGear, JSBSim).
    Flightgear,
    /// X-Plane's `RPOS` and `DATA` output.
    Xplane,
    /// GDL 90 (Stratux, ForeFlight Sentry, GDL 90 boxes).
    Gdl90,
}

impl InputKind {
    /// The name on the command line and in stats.json.
    pub fn name(self) -> &'static str {
        match self {
            InputKind::Flightgear => "flightgear",
            InputKind::Xplane => "xplane",
            InputKind::Gdl90 => "gdl90",
        }
    }
}

/// `--input KIND:[ADDR:]PORT`: the protocol and the local address to listen on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InputSpec {
    /// The protocol.
    pub kind: InputKind,
    /// Where to bind; 127.0.0.1 unless an address is given. Port 0 lets
    /// the system choose (the receiver reports the one bound).
    pub address: SocketAddr,
}

impl std::str::FromStr for InputSpec {
    type Err = String;

    fn from_str(text: &str) -> Result<InputSpec, String> {
        let usage =
            || format!("`{text}`: expected KIND:[ADDR:]PORT with KIND flightgear, xplane or gdl90");
        let (kind, rest) = text.split_once(':').ok_or_else(usage)?;
        let kind = match kind.to_ascii_lowercase().as_str() {
            "flightgear" | "fg" | "jsbsim" => InputKind::Flightgear,
            "xplane" | "x-plane" => InputKind::Xplane,
            "gdl90" | "gdl-90" => InputKind::Gdl90,
            other => return Err(format!("`{text}`: unknown input kind `{other}`; {}", usage())),
        };
        let (ip, port) = match rest.rsplit_once(':') {
            Some((ip, port)) => {
                let ip = ip.trim_start_matches('[').trim_end_matches(']');
                let ip: IpAddr =
                    ip.parse().map_err(|_| format!("`{text}`: `{ip}` is not an IP address"))?;
                (ip, port)
            }
            None => (IpAddr::V4(Ipv4Addr::LOCALHOST), rest),
        };
        let port: u16 =
            port.parse().map_err(|_| format!("`{text}`: `{port}` is not a port number"))?;
        Ok(InputSpec { kind, address: SocketAddr::new(ip, port) })
    }
}

/// One protocol's decoder, with the state a protocol keeps across datagrams.
#[derive(Clone, Debug)]
pub enum Decoder {
    /// FlightGear: stateless.
    Flightgear,
    /// X-Plane: stateless.
    Xplane,
    /// GDL 90: earlier messages feed later ones.
    Gdl90(gdl90::Gdl90),
}

impl Decoder {
    /// The decoder for `kind`; `geoid_m` is the geoid's height above the
    /// ellipsoid, for GDL 90's ellipsoidal geometric altitude.
    pub fn new(kind: InputKind, geoid_m: f64) -> Decoder {
        match kind {
            InputKind::Flightgear => Decoder::Flightgear,
            InputKind::Xplane => Decoder::Xplane,
            InputKind::Gdl90 => Decoder::Gdl90(gdl90::Gdl90::new(geoid_m)),
        }
    }

    /// Decodes and checks one datagram received at `now`.
    pub fn decode(&mut self, datagram: &[u8], now: Instant) -> Result<Update, Ignored> {
        let update = match self {
            Decoder::Flightgear => flightgear::decode(datagram),
            Decoder::Xplane => xplane::decode(datagram),
            Decoder::Gdl90(gdl) => gdl.decode(datagram, now),
        }?;
        update::check(&update)?;
        Ok(update)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn input_specs_parse_with_and_without_an_address() {
        let spec: InputSpec = "flightgear:5500".parse().unwrap();
        assert_eq!(spec.kind, InputKind::Flightgear);
        assert_eq!(spec.address, "127.0.0.1:5500".parse().unwrap());
        let spec: InputSpec = "gdl90:0.0.0.0:4000".parse().unwrap();
        assert_eq!((spec.kind, spec.address), (InputKind::Gdl90, "0.0.0.0:4000".parse().unwrap()));
        let spec: InputSpec = "xplane:[::1]:49005".parse().unwrap();
        assert_eq!(spec.address, "[::1]:49005".parse().unwrap());
        for bad in ["flightgear", "mavlink:14550", "gdl90:host:4000", "xplane:99999"] {
            assert!(bad.parse::<InputSpec>().is_err(), "{bad} was accepted");
        }
    }
}
