//! Plays the live-input tests' scripted flight (a climbing turn over the
//! built-in terrain) to `ridgeline fly --input` on this machine, as a
//! simulator or a GDL 90 box would send it: try the live display without
//! either.
//!
//! ```text
//! cargo run --release --example live_sender -- KIND PORT [SECONDS] [SILENT_FROM SILENT_TO]
//! ```
//!
//! KIND is `flightgear` (60 Hz), `xplane` (RPOS, 60 Hz) or `gdl90`
//! (ownship and geometric altitude at 1 Hz, Stratux AHRS at 20 Hz); the
//! flight lasts SECONDS (20 by default); between SILENT_FROM and SILENT_TO
//! seconds nothing is sent, so the display goes stale and recovers.

use std::net::UdpSocket;
use std::time::{Duration, Instant};

use testkit::live::SCRIPT;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: live_sender KIND PORT [SECONDS] [SILENT_FROM SILENT_TO]";
    let kind = args.first().ok_or(usage)?.clone();
    let port: u16 = args.get(1).ok_or(usage)?.parse()?;
    let seconds: f64 = args.get(2).map_or(Ok(20.0), |s| s.parse())?;
    let silent = match (args.get(3), args.get(4)) {
        (Some(a), Some(b)) => a.parse::<f64>()?..b.parse::<f64>()?,
        _ => 0.0..0.0,
    };
    let (hz, gdl90) = match kind.as_str() {
        "flightgear" | "xplane" => (60.0, false),
        "gdl90" => (20.0, true),
        other => return Err(format!("unknown kind {other}; {usage}").into()),
    };
    let socket = UdpSocket::bind("127.0.0.1:0")?;
    let to = ("127.0.0.1", port);
    let start = Instant::now();
    let mut sent = 0u64;
    for k in 0..(seconds * hz) as u64 {
        let t = k as f64 / hz;
        if let Some(wait) =
            (start + Duration::from_secs_f64(t)).checked_duration_since(Instant::now())
        {
            std::thread::sleep(wait);
        }
        if silent.contains(&t) {
            continue;
        }
        let mut datagrams = Vec::new();
        match kind.as_str() {
            "flightgear" => datagrams.push(SCRIPT.flightgear(24, t)),
            "xplane" => datagrams.push(SCRIPT.rpos(t)),
            _ => {
                if gdl90 && k % hz as u64 == 0 {
                    datagrams.push(SCRIPT.gdl90_ownship(t));
                }
                datagrams.push(SCRIPT.gdl90_stratux_ahrs(t));
            }
        }
        for datagram in datagrams {
            socket.send_to(&datagram, to)?;
            sent += 1;
        }
    }
    println!("live_sender: {sent} {kind} datagrams sent to port {port} over {seconds} s");
    Ok(())
}
