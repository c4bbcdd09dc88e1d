//! `ridgeline fly --input` as a user runs it headless: the scripted flight
//! sent as FlightGear packets to the port the display reports, with a
//! silence in the middle. Every frame of `stats.json` records its pose,
//! the input's state and the wall time; the display is stale exactly on
//! the frames drawn more than `--stale-ms` after the newest sample (so the
//! first frame past the stale time is already stale) with its terrain
//! withdrawn, and live again from the first frame after the data resume;
//! the summary counts the datagrams and the time spent stale; the
//! `--record` file replays with `--path`.

use std::io::{BufRead, BufReader};
use std::net::UdpSocket;
use std::process::Stdio;
use std::time::{Duration, Instant};

use testkit::cli::Ridgeline;
use testkit::fresh_dir;
use testkit::live::SCRIPT;

const STALE_MS: f64 = 400.0;

#[test]
fn silence_turns_the_display_stale_and_resuming_clears_it() {
    let out = fresh_dir("cli-fly-live");
    let record = out.join("flight.csv");
    let ridgeline = Ridgeline::new(env!("CARGO_BIN_EXE_ridgeline"));
    let mut running = ridgeline
        .args(["fly", "--backend", "egl", "--input", "flightgear:127.0.0.1:0", "--frames", "96"])
        .args(["--fps", "30", "--stale-ms", "400", "--size", "160x90", "--snapshots", "1", "--out"])
        .arg(&out)
        .arg("--record")
        .arg(&record)
        .spawn(Stdio::piped(), Stdio::piped());
    let mut stdout = BufReader::new(running.child.stdout.take().unwrap());
    let mut port = None;
    let mut said = String::new();
    for _ in 0..20 {
        let mut line = String::new();
        if stdout.read_line(&mut line).unwrap_or(0) == 0 {
            break;
        }
        said.push_str(&line);
        if let Some(address) =
            line.trim().strip_prefix("ridgeline fly: listening for flightgear on ")
        {
            port = Some(address.rsplit(':').next().unwrap().parse::<u16>().unwrap());
            break;
        }
    }
    let port = port.unwrap_or_else(|| panic!("no port reported: {said}"));
    // 1 s of data, 1 s of silence, then data until the display is done.
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let start = Instant::now();
    let mut sent = 0;
    while start.elapsed() < Duration::from_secs(5) {
        let t = start.elapsed().as_secs_f64();
        if !(1.0..2.0).contains(&t) {
            socket.send_to(&SCRIPT.flightgear(24, t), ("127.0.0.1", port)).unwrap();
            sent += 1;
        }
        std::thread::sleep(Duration::from_millis(16));
        if running.child.try_wait().unwrap().is_some() {
            break;
        }
    }
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stdout, &mut rest).unwrap();
    running.finish().ok();
    let summary = said + &rest;
    assert!(summary.contains("datagrams taken") && summary.contains("stale "), "{summary}");

    let text = std::fs::read_to_string(out.join("stats.json")).expect("stats.json");
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let frames = json["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 96);
    let mut kinds = String::new();
    let mut last_wall = 0.0;
    for frame in frames {
        let input = &frame["input"];
        let stale = input["stale"].as_bool().unwrap();
        let age = input["age_ms"].as_f64();
        assert_eq!(
            stale,
            age.is_none_or(|ms| ms > STALE_MS),
            "stale exactly past the stale time: {frame}"
        );
        if stale {
            assert_eq!(frame["tiles"], 0, "a stale frame withdraws the terrain: {frame}");
            assert!(frame["pose"].is_null());
        } else {
            assert!(frame["tiles"].as_u64().unwrap() > 0, "{frame}");
            let pose = &frame["pose"];
            assert!(
                (pose["lat_deg"].as_f64().unwrap() - SCRIPT.start.lat_deg).abs() < 0.05,
                "{pose}"
            );
        }
        let wall = frame["wall_time"].as_f64().unwrap();
        assert!(wall >= last_wall, "wall time runs forward");
        last_wall = wall;
        kinds.push(match (stale, input["reason"].as_str()) {
            (false, _) => 'L',
            (true, Some("no_data")) => 'N',
            (true, _) => 'S',
        });
    }
    // No data, live, stale through the silence, live again.
    let runs: String = kinds.chars().fold(String::new(), |mut runs, c| {
        if !runs.ends_with(c) {
            runs.push(c);
        }
        runs
    });
    assert!(runs.contains("LSL"), "the display went stale in the silence and recovered: {kinds}");
    let input = &json["input"];
    assert!(input["datagrams"]["taken"].as_u64().unwrap() > 50, "{input}");
    assert_eq!(input["datagrams"]["ignored"], 0, "{input}");
    assert!(input["stale_s"].as_f64().unwrap() > 0.3, "{input}");
    println!("{kinds}\n{sent} sent; {input}");

    // The recording replays.
    ridgeline
        .args(["fly", "--backend", "egl", "--frames", "2", "--size", "160x90", "--snapshots", "1"])
        .arg("--path")
        .arg(&record)
        .arg("--out")
        .arg(out.join("replay"))
        .ok();
}
